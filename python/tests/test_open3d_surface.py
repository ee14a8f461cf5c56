"""volley.RaycastingScene as Open3D's o3d.t.geometry.RaycastingScene, in the project's own
words: the constructor, both add_triangles forms and meshes (tensor and legacy, without
Open3D), INVALID_ID, create_rays_pinhole in both forms, Open3D's keywords and defaults,
signatures and docstrings, the type stub, and the errors that name their argument."""
import inspect
import math
import os
import pickle
from types import SimpleNamespace

import numpy as np
import pytest

import volley

BOX_V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], np.float32)
BOX_T = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                  [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]], np.uint32)
DOWN = np.array([[0.3, 0.6, 5, 0, 0, -1], [5, 5, 5, 0, 0, 1]], np.float32)
PUBLIC = ["add_triangles", "add_instance", "update_vertices", "set_geometry_mask", "disable_geometry",
          "enable_geometry", "cast_rays", "test_occlusions", "count_intersections", "list_intersections",
          "compute_closest_points", "compute_distance", "compute_signed_distance", "compute_occupancy",
          "create_rays_pinhole", "info", "save", "load"]


class CpuDevice:
    """What open3d.core.Device("CPU:0") prints."""

    def __str__(self):
        return "CPU:0"


class OnlyArray:
    """An array-like with __array__ only (as many tensor types are)."""

    def __init__(self, a):
        self.a = a

    def __array__(self, dtype=None):
        return self.a if dtype is None else self.a.astype(dtype)


class OnlyNumpy:
    """An array-like with a .numpy() method only (as Open3D 0.16's tensors are)."""

    def __init__(self, a):
        self.a = a

    def numpy(self):
        return self.a


def test_the_constructor_takes_open3ds_arguments_and_volleys_as_keywords():
    for scene in (volley.RaycastingScene(nthreads=2), volley.RaycastingScene(0, "CPU:0"),
                  volley.RaycastingScene(device=CpuDevice()),
                  volley.RaycastingScene(nthreads=1, test="moller", isa="scalar", quality="high")):
        assert scene.add_triangles(BOX_V, BOX_T) == 0
        assert scene.count_intersections(DOWN).tolist() == [2, 0]
    with pytest.raises(ValueError, match="device: volley runs on the CPU"):
        volley.RaycastingScene(device="CUDA:0")
    with pytest.raises(ValueError, match="nthreads"):
        volley.RaycastingScene(nthreads=-1)
    with pytest.raises(TypeError, match="nthreads"):
        volley.RaycastingScene(nthreads="4")
    with pytest.raises(TypeError):
        volley.RaycastingScene(0, None, "moller")  # volley's options are keyword-only


def test_add_triangles_by_position_keyword_and_mesh():
    tensor_mesh = SimpleNamespace(vertex=SimpleNamespace(positions=OnlyNumpy(BOX_V.astype(np.float64))),
                                  triangle=SimpleNamespace(indices=OnlyNumpy(BOX_T.astype(np.int64))))
    legacy_mesh = SimpleNamespace(vertices=OnlyArray(BOX_V.astype(np.float64)), triangles=BOX_T.astype(np.int32).tolist())
    s = volley.RaycastingScene()
    ids = [s.add_triangles(BOX_V, BOX_T), s.add_triangles(vertex_positions=BOX_V + 2, triangle_indices=BOX_T),
           s.add_triangles(tensor_mesh), s.add_triangles(mesh=legacy_mesh)]
    assert ids == [0, 1, 2, 3]
    assert s.count_intersections(DOWN).tolist() == [6, 0]  # three boxes in place, one moved away
    with pytest.raises(TypeError, match="mesh"):
        s.add_triangles(object())
    with pytest.raises(TypeError, match="either a mesh"):
        s.add_triangles(BOX_V, BOX_T, mesh=tensor_mesh)
    with pytest.raises(TypeError, match="vertex_positions, triangle_indices"):
        s.add_triangles(BOX_V)


def test_invalid_id_is_a_class_attribute_as_in_open3d():
    assert volley.RaycastingScene.INVALID_ID == volley.INVALID_ID == 2**32 - 1
    s = volley.RaycastingScene()
    s.add_triangles(BOX_V, BOX_T)
    assert s.cast_rays(DOWN)["geometry_ids"][1] == s.INVALID_ID


def test_open3ds_keywords_and_defaults():
    s = volley.RaycastingScene()
    s.add_triangles(BOX_V, BOX_T)
    np.testing.assert_array_equal(s.test_occlusions(rays=DOWN, tnear=0.0, tfar=math.inf, nthreads=1), [True, False])
    np.testing.assert_array_equal(s.test_occlusions(DOWN, tfar=3.9), [False, False])
    np.testing.assert_array_equal(s.test_occlusions(DOWN, tnear=4.1, tfar=5.1), [True, False])
    pts = np.array([[0.5, 0.5, 0.5], [2, 2, 2]], np.float32)
    np.testing.assert_array_equal(s.compute_occupancy(query_points=pts, nthreads=0, nsamples=3), [1, 0])
    np.testing.assert_allclose(s.compute_signed_distance(query_points=pts, nsamples=5), [-0.5, math.sqrt(3)], rtol=1e-6)
    assert s.cast_rays(rays=DOWN, nthreads=2)["t_hit"][0] == 4
    assert s.list_intersections(rays=DOWN, nthreads=1)["ray_splits"].tolist() == [0, 2, 2]
    assert s.compute_closest_points(query_points=pts)["primitive_ids"].dtype == np.uint32
    for bad in (0, 2, -1):
        with pytest.raises(ValueError, match="nsamples"):
            s.compute_occupancy(pts, nsamples=bad)
    with pytest.raises(ValueError, match="nthreads"):
        s.cast_rays(DOWN, nthreads=-2)


def test_answer_dtypes_and_shapes_are_open3ds():
    s = volley.RaycastingScene()
    s.add_triangles(BOX_V, BOX_T)
    rays = np.tile(DOWN, (3, 1, 1))  # (3, 2, 6)
    hits = s.cast_rays(rays)
    assert {k: (v.dtype, v.shape) for k, v in hits.items()} == {
        "t_hit": (np.float32, (3, 2)), "geometry_ids": (np.uint32, (3, 2)), "primitive_ids": (np.uint32, (3, 2)),
        "primitive_uvs": (np.float32, (3, 2, 2)), "primitive_normals": (np.float32, (3, 2, 3))}
    assert s.test_occlusions(rays).dtype == np.bool_
    assert s.count_intersections(rays).dtype == np.int32
    assert s.compute_occupancy(rays[..., :3]).dtype == np.float32


def test_nan_rays_miss_and_nan_points_are_documented():
    s = volley.RaycastingScene()
    s.add_triangles(BOX_V, BOX_T)
    rays = np.array([[np.nan, 0.5, 5, 0, 0, -1], [0.5, 0.5, 5, 0, 0, np.inf], [0.5, 0.5, 5, 0, 0, 0]], np.float32)
    hits = s.cast_rays(rays)
    assert np.isinf(hits["t_hit"]).all() and (hits["geometry_ids"] == s.INVALID_ID).all()
    assert not s.test_occlusions(rays).any()
    assert s.count_intersections(rays).tolist() == [0, 0, 0]
    assert s.compute_occupancy(np.array([[np.nan, 0.5, 0.5]], np.float32)).tolist() == [0.0]


def test_create_rays_pinhole_both_forms_agree_and_point_where_asked():
    eye, center, up = np.array([0.5, 0.5, 4.0]), np.array([0.5, 0.5, 0.0]), np.array([0, 1, 0])
    rays = volley.RaycastingScene.create_rays_pinhole(fov_deg=60, center=center, eye=eye, up=up, width_px=8, height_px=6)
    assert rays.shape == (6, 8, 6) and rays.dtype == np.float32
    np.testing.assert_allclose(rays[..., :3], np.broadcast_to(eye, (6, 8, 3)), rtol=1e-6)
    # Unit depth along the optical axis (-z here), so that t_hit is the depth.
    np.testing.assert_allclose(rays[..., 5], -1.0, rtol=1e-6)
    # The horizontal field of view sets the focal length; the camera's x axis is up x
    # forward and its y axis up, as Open3D's (whose rays these equal bit for bit, checked
    # against Debian's Open3D 0.16 when it was written).
    focal = 0.5 * 8 / math.tan(math.radians(30))
    np.testing.assert_allclose(rays[0, 0, 3:], [(4 - 0.5) / focal, -(3 - 0.5) / focal, -1], rtol=1e-5)
    # The matrix form with the same camera gives the same rays (positional arguments).
    k = np.array([[focal, 0, 4], [0, focal, 3], [0, 0, 1]])
    r = np.array([[-1, 0, 0], [0, 1, 0], [0, 0, -1]], np.float64)  # x = up x forward, y = forward x x
    extrinsic = np.eye(4)
    extrinsic[:3, :3], extrinsic[:3, 3] = r, -r @ eye
    np.testing.assert_allclose(volley.RaycastingScene.create_rays_pinhole(k, extrinsic, 8, 6), rays, rtol=1e-5, atol=1e-6)
    # A depth image of the box's top face at depth 3 (the rays that hit it).
    s = volley.RaycastingScene()
    s.add_triangles(BOX_V, BOX_T)
    depth = s.cast_rays(volley.RaycastingScene.create_rays_pinhole(20, center, eye, up, 8, 6))["t_hit"]
    np.testing.assert_allclose(depth[np.isfinite(depth)], 3.0, rtol=1e-6)
    assert np.isfinite(depth).sum() > 0
    with pytest.raises(ValueError, match="center"):
        volley.RaycastingScene.create_rays_pinhole(60, eye, eye, up, 8, 6)
    with pytest.raises(ValueError, match="up"):
        volley.RaycastingScene.create_rays_pinhole(60, center, eye, [0, 0, 1], 8, 6)
    with pytest.raises(ValueError, match="intrinsic_matrix"):
        volley.RaycastingScene.create_rays_pinhole(np.eye(2), extrinsic, 8, 6)
    with pytest.raises(ValueError, match="width_px"):
        volley.RaycastingScene.create_rays_pinhole(k, extrinsic, 0, 6)


def test_array_likes_without_a_copy_where_the_layout_allows():
    s = volley.RaycastingScene()
    s.add_triangles(OnlyArray(BOX_V), OnlyNumpy(BOX_T))
    assert s.count_intersections(OnlyNumpy(DOWN)).tolist() == [2, 0]
    assert s.count_intersections(DOWN.tolist()).tolist() == [2, 0]
    assert volley.raycasting_scene.as_array(OnlyNumpy(DOWN), "rays") is DOWN
    with pytest.raises(TypeError, match="rays: expected an array"):
        s.cast_rays(object())


def test_masks_out_of_range_name_the_argument():
    s = volley.RaycastingScene()
    s.add_triangles(BOX_V, BOX_T)
    for bad in (2**33, -1, 1.5, "1"):
        with pytest.raises(ValueError, match="mask: expected an integer in"):
            s.set_geometry_mask(0, bad)
    s.set_geometry_mask(0, 2**32 - 1)


def test_every_method_has_a_signature_and_a_docstring():
    for name in PUBLIC:
        method = getattr(volley.RaycastingScene, name)
        inspect.signature(method)
        assert method.__doc__ and len(method.__doc__) > 40, name
        assert "handle" not in method.__doc__, name
    assert list(inspect.signature(volley.RaycastingScene.compute_occupancy).parameters) == [
        "self", "query_points", "nthreads", "nsamples"]
    occlusions = inspect.signature(volley.RaycastingScene.test_occlusions).parameters
    assert list(occlusions) == ["self", "rays", "tnear", "tfar", "nthreads", "masks", "exclude"]  # Open3D's, then volley's
    assert occlusions["masks"].kind == inspect.Parameter.KEYWORD_ONLY
    init = inspect.signature(volley.RaycastingScene.__init__).parameters
    assert [p.kind for p in init.values()][3:] == [inspect.Parameter.KEYWORD_ONLY] * 3


def test_the_package_ships_its_type_stub():
    folder = os.path.dirname(volley.__file__)
    assert os.path.isfile(os.path.join(folder, "py.typed"))
    with open(os.path.join(folder, "__init__.pyi"), encoding="utf-8") as f:
        stub = f.read()
    for name in PUBLIC:
        assert f"def {name}(" in stub, name


def test_a_scene_pickles_as_itself():
    s = volley.RaycastingScene(nthreads=1, test="moller")
    s.add_triangles(BOX_V, BOX_T)
    t = pickle.loads(pickle.dumps(s))
    assert isinstance(t, volley.RaycastingScene)
    np.testing.assert_array_equal(t.cast_rays(DOWN)["t_hit"], s.cast_rays(DOWN)["t_hit"])
    assert t.info()["test"] == "moller"
    assert "1 geometries" in repr(t)


def test_ray_masks_in_every_ray_query_select_geometries_as_hiding_them_would():
    # Box 0 (mask 1) at z in [0, 1], box 1 (mask 2) at z in [2, 3]; rays come down from z = 5.
    s = volley.RaycastingScene()
    s.add_triangles(BOX_V, BOX_T)
    s.add_triangles(BOX_V + [0, 0, 2], BOX_T)
    s.set_geometry_mask(0, 1)
    s.set_geometry_mask(1, 2)
    rays = np.tile(np.array([0.3, 0.6, 5, 0, 0, -1], np.float32), (2, 3, 1))  # (2, 3, 6)
    masks = np.array([[1, 2, 3], [0, 1, 2]], np.uint32)
    hits = s.cast_rays(rays, masks=masks)
    assert hits["geometry_ids"].tolist() == [[0, 1, 1], [s.INVALID_ID, 0, 1]]
    np.testing.assert_array_equal(hits["t_hit"], [[4, 2, 2], [np.inf, 4, 2]])
    assert s.test_occlusions(rays, masks=masks).tolist() == [[True, True, True], [False, True, True]]
    assert s.test_occlusions(rays, tfar=2.5, masks=masks).tolist() == [[False, True, True], [False, False, True]]
    assert s.count_intersections(rays, masks=masks).tolist() == [[2, 2, 4], [0, 2, 2]]
    lists = s.list_intersections(rays, nthreads=1, masks=masks)
    assert lists["ray_splits"].tolist() == [0, 2, 4, 8, 8, 10, 12]
    assert lists["geometry_ids"].tolist() == [0, 0, 1, 1, 1, 1, 0, 0, 0, 0, 1, 1]
    np.testing.assert_array_equal(lists["t_hit"][4:8], [2, 3, 4, 5])
    # Without masks every ray sees everything (the default mask of a ray is all bits).
    assert s.count_intersections(rays).tolist() == [[4, 4, 4], [4, 4, 4]]


def test_ray_masks_out_of_range_or_misshapen_name_the_argument():
    s = volley.RaycastingScene()
    s.add_triangles(BOX_V, BOX_T)
    for bad, why in ((np.array([1, -1]), "values in"), (np.array([1, 2**32]), "values in"),
                     (np.array([1.0, 2.0]), "integers"), (np.array([1, 2, 3]), "one mask per ray")):
        for query in (s.cast_rays, s.test_occlusions, s.count_intersections, s.list_intersections):
            with pytest.raises(ValueError, match="masks: expected " + why):
                query(DOWN, masks=bad)
