"""RaycastingScene.cast_rays / test_occlusions with exclude=: a secondary ray from a hit
point passes over the triangle it leaves (given as the cast_rays answer it came from), with
no offset of its origin; the answers are those of the scene without that triangle."""
import numpy as np
import pytest

import volley

from test_scene import box_scene


def surface_points(s, n=2000, seed=5):
    """Rays from outside the unit box to random points on it, the hits, and the points."""
    rng = np.random.default_rng(seed)
    target = rng.uniform(0.05, 0.95, (n, 3)).astype(np.float32)
    origin = target + rng.normal(0, 1, (n, 3)).astype(np.float32) * 4
    rays = np.concatenate([origin, target - origin], axis=1)
    ans = s.cast_rays(rays)
    hit = np.isfinite(ans["t_hit"])
    p = rays[:, :3] + ans["t_hit"][:, None] * rays[:, 3:]
    return rays[hit], {k: v[hit] for k, v in ans.items()}, p[hit]


def test_rays_from_hit_points_pass_over_their_own_triangle():
    s = box_scene()
    _, ans, p = surface_points(s)
    # Out of the box's faces along the outward normal: nothing else is there.
    out = np.concatenate([p, ans["primitive_normals"]], axis=1)
    plain = s.cast_rays(out)
    assert np.mean(np.isfinite(plain["t_hit"])) > 0.05  # without exclusion: self-hits at t ~ 0
    excluded = s.cast_rays(out, exclude=ans)
    assert np.all(np.isinf(excluded["t_hit"]))
    assert np.all(excluded["primitive_ids"] == volley.INVALID_ID)
    assert not s.test_occlusions(out, exclude=ans).any()
    # Into the box: the opposite face, never the triangle left (1 - t from a face to the other).
    into = np.concatenate([p, -ans["primitive_normals"]], axis=1)
    back = s.cast_rays(into, exclude=ans, nthreads=3)
    assert np.all(np.isfinite(back["t_hit"]))
    assert np.all(back["primitive_ids"] != ans["primitive_ids"])
    assert s.test_occlusions(into, exclude=ans).all()


def test_an_invalid_id_excludes_nothing_and_masks_combine():
    s = box_scene()
    rays, ans, _ = surface_points(s, 200)
    none = {"geometry_ids": np.full(len(rays), volley.INVALID_ID, np.uint32),
            "primitive_ids": np.full(len(rays), volley.INVALID_ID, np.uint32)}
    np.testing.assert_array_equal(s.cast_rays(rays, exclude=none)["t_hit"], ans["t_hit"])
    masked = s.cast_rays(rays, masks=np.zeros(len(rays), np.uint32), exclude=ans)
    assert np.all(np.isinf(masked["t_hit"]))


def test_bad_exclusions_raise_value_error_naming_them():
    s = box_scene()
    rays = np.array([[0.5, 0.5, 5, 0, 0, -1]] * 3, np.float32)
    with pytest.raises(ValueError, match="primitive_ids"):
        s.cast_rays(rays, exclude={"geometry_ids": [0, 0, 0]})
    with pytest.raises(ValueError, match="one id per ray"):
        s.cast_rays(rays, exclude={"geometry_ids": [0, 0], "primitive_ids": [0, 0]})
    with pytest.raises(ValueError, match="exclude"):
        s.cast_rays(rays, exclude=[1, 2, 3])
    with pytest.raises(ValueError, match="prim 12"):
        s.cast_rays(rays, exclude={"geometry_ids": [0, 0, 0], "primitive_ids": [0, 12, 0]})
    with pytest.raises(ValueError, match="geom 4"):
        s.test_occlusions(rays, exclude={"geometry_ids": [4, 0, 0], "primitive_ids": [0, 0, 0]})
