"""volley's binary files from Python: every kind read back as written, the files the
command line writes read with the answers Python computes, and a bad file refused with the
command line's own message."""
import os
import subprocess

import numpy as np
import pytest

import volley

VOLLEY = os.environ.get("VOLLEY_BINARY")
SOURCE = os.environ.get("VOLLEY_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
CORNELL = os.path.join(SOURCE, "scenes", "cornell.json")


def test_every_kind_round_trips(tmp_path):
    rng = np.random.default_rng(7)
    rays = np.zeros(5, volley.RAY_DTYPE)
    rays["org"], rays["dir"], rays["tmin"], rays["tmax"] = rng.random((5, 3)), rng.random((5, 3)), 0.5, np.inf
    volley.write_rays(tmp_path / "r.vray", rays)
    np.testing.assert_array_equal(volley.read_rays(tmp_path / "r.vray"), rays)

    hits = np.zeros(4, volley.HIT_DTYPE)
    hits["t"], hits["prim"], hits["geom"], hits["inst"] = [1, 2, np.inf, 3], [0, 5, 2**32 - 1, 1], [0, 1, 2**32 - 1, 0], 7
    volley.write_hits(str(tmp_path / "h.vhit"), hits)
    np.testing.assert_array_equal(volley.read_hits(tmp_path / "h.vhit"), hits)

    points = rng.random((6, 3)).astype(np.float32)
    volley.write_points(tmp_path / "p.vpts", points)
    np.testing.assert_array_equal(volley.read_points(tmp_path / "p.vpts"), points)

    volley.write_counts(tmp_path / "c.vcnt", [0, 3, 2**31])
    assert volley.read_counts(tmp_path / "c.vcnt").tolist() == [0, 3, 2**31]

    volley.write_occupancy(tmp_path / "o.vocc", [True, False, True])
    assert volley.read_occupancy(tmp_path / "o.vocc").tolist() == [True, False, True]

    volley.write_distances(tmp_path / "d.vdst", [-0.5, 0.25, np.inf])
    assert volley.read_distances(tmp_path / "d.vdst").tolist() == [-0.5, 0.25, np.inf]

    closest = np.zeros(2, volley.CLOSEST_DTYPE)
    closest["point"], closest["geometry"], closest["primitive"] = [[1, 2, 3], [np.inf] * 3], [0, 2**32 - 1], [4, 2**32 - 1]
    volley.write_closest(tmp_path / "x.vclp", closest)
    np.testing.assert_array_equal(volley.read_closest(tmp_path / "x.vclp"), closest)

    volley.write_hit_lists(tmp_path / "a.vall", [0, 2, 2, 4], hits)
    lists = volley.read_hit_lists(tmp_path / "a.vall")
    assert lists["ray_splits"].tolist() == [0, 2, 2, 4]
    np.testing.assert_array_equal(lists["hits"], hits)


def test_open3d_rays_become_a_ray_file(tmp_path):
    six = np.array([[[0, 0, 1, 0, 0, -1], [1, 2, 3, 4, 5, 6]]], np.float64)  # (1, 2, 6)
    volley.write_rays(tmp_path / "r.vray", six)
    r = volley.read_rays(tmp_path / "r.vray")
    assert r.shape == (2,)
    np.testing.assert_array_equal(r["org"], six[0, :, :3])
    np.testing.assert_array_equal(r["dir"], six[0, :, 3:])
    assert r["tmin"].tolist() == [0, 0] and np.isinf(r["tmax"]).all()


@pytest.mark.skipif(not VOLLEY, reason="VOLLEY_BINARY is not set (make test sets it)")
def test_the_command_lines_files_hold_the_answers_python_computes(tmp_path):
    rays_file, hits_file = tmp_path / "p.vray", tmp_path / "p.vhit"
    subprocess.run([VOLLEY, "rays", CORNELL, "--workload", "primary", "--width", "16", "--height", "16", "-o",
                    str(rays_file)], check=True, capture_output=True)
    subprocess.run([VOLLEY, "trace", CORNELL, "--rays", str(rays_file), "--reps", "1", "-o", str(hits_file)],
                   check=True, capture_output=True)
    rays, hits = volley.read_rays(rays_file), volley.read_hits(hits_file)
    assert rays.shape == hits.shape == (256,)
    scene = volley.RaycastingScene()
    vertices, triangles = volley.read_triangle_mesh(CORNELL)
    scene.add_triangles(vertices, triangles)
    six = np.concatenate([rays["org"], rays["dir"]], axis=1)
    assert (rays["tmin"] == 0).all() and np.isinf(rays["tmax"]).all()
    ans = scene.cast_rays(six)
    np.testing.assert_array_equal(ans["t_hit"], hits["t"])


@pytest.mark.skipif(not VOLLEY, reason="VOLLEY_BINARY is not set (make test sets it)")
def test_a_bad_file_gets_the_command_lines_message(tmp_path):
    good = tmp_path / "good.vray"
    volley.write_rays(good, np.zeros((3, 6), np.float32))
    bad = tmp_path / "bad.vray"
    bad.write_bytes(good.read_bytes()[:-4])
    with pytest.raises(OSError) as python_error:
        volley.read_rays(bad)
    cli = subprocess.run([VOLLEY, "trace", CORNELL, "--rays", str(bad)], capture_output=True, text=True)
    assert cli.returncode == 1
    assert str(python_error.value) in cli.stderr
    assert "truncated" in str(python_error.value)
    with pytest.raises(OSError, match="this is a hit file"):
        volley.write_hits(tmp_path / "h.vhit", np.zeros(1, volley.HIT_DTYPE))
        volley.read_rays(tmp_path / "h.vhit")
    with pytest.raises(OSError, match="file not found"):
        volley.read_points(tmp_path / "missing.vpts")


def test_wrong_values_name_the_argument(tmp_path):
    with pytest.raises(ValueError, match="rays: expected shape"):
        volley.write_rays(tmp_path / "r.vray", np.zeros((2, 5)))
    with pytest.raises(ValueError, match="hits: expected a structured array"):
        volley.write_hits(tmp_path / "h.vhit", np.zeros((2, 6)))
    with pytest.raises(ValueError, match="counts: expected non-negative integers"):
        volley.write_counts(tmp_path / "c.vcnt", [1, -1])
    with pytest.raises(ValueError, match="inside: expected booleans"):
        volley.write_occupancy(tmp_path / "o.vocc", [0, 2])
    with pytest.raises(ValueError, match="ray_splits"):
        volley.write_hit_lists(tmp_path / "a.vall", [0, 3], np.zeros(2, volley.HIT_DTYPE))
