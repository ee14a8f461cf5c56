"""volley.RaycastingScene: Open3D's API and answers, errors that name the argument, the same
answers as `volley trace` / `volley query` on the same files, pickling, and no leaks."""
import os
import pickle
import resource
import struct
import subprocess
import tempfile

import numpy as np
import pytest

import volley

# The unit box [0, 1]^3 as 12 triangles (consistently oriented, outward normals).
BOX_V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], np.float32)
BOX_T = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                  [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]], np.uint32)


def box_scene(**options):
    s = volley.RaycastingScene(**options)
    assert s.add_triangles(BOX_V, BOX_T) == 0
    return s


def test_cast_rays_hits_and_misses_as_open3d_reports_them():
    s = box_scene()
    rays = np.array([[0.5, 0.5, 5, 0, 0, -1], [0.25, 0.75, -3, 0, 0, 1], [5, 5, 5, 0, 0, 1]], np.float64)
    a = s.cast_rays(rays)
    assert a["t_hit"].dtype == np.float32 and a["t_hit"].shape == (3,)
    np.testing.assert_array_equal(a["t_hit"][:2], [4.0, 3.0])
    assert np.isinf(a["t_hit"][2])
    assert a["geometry_ids"].tolist() == [0, 0, volley.INVALID_ID]
    assert a["primitive_ids"][2] == volley.INVALID_ID
    assert a["primitive_uvs"].shape == (3, 2) and a["primitive_normals"].shape == (3, 3)
    np.testing.assert_allclose(a["primitive_normals"][0], [0, 0, 1])   # the top face, outward
    np.testing.assert_allclose(a["primitive_normals"][1], [0, 0, -1])  # the bottom face
    np.testing.assert_array_equal(a["primitive_normals"][2], [0, 0, 0])


def test_leading_dimensions_and_layouts_are_kept():
    s = box_scene()
    rays = np.zeros((4, 5, 6), np.float32)
    rays[..., 0:2] = 0.5
    rays[..., 2] = 2
    rays[..., 5] = -1
    a = s.cast_rays(rays)
    assert a["t_hit"].shape == (4, 5)
    assert a["primitive_uvs"].shape == (4, 5, 2)
    # A Fortran-ordered, strided float64 view answers the same.
    b = s.cast_rays(np.asfortranarray(rays.astype(np.float64))[:, ::2])
    np.testing.assert_array_equal(b["t_hit"], a["t_hit"][:, ::2])


def test_large_batches_answer_as_small_ones_on_any_thread_count():
    # Answers of 1 MiB or more are streamed into reused, aligned memory group by group; a
    # count that is no multiple of the groups ends in a part group. Small calls (plain
    # arrays) are the reference, the scene and rays the same.
    s = box_scene()
    rng = np.random.default_rng(11)
    n = 270_001
    rays = np.hstack([rng.uniform(-1, 2, (n, 3)), rng.normal(size=(n, 3))]).astype(np.float32)
    small = [s.cast_rays(rays[i:i + 4999], nthreads=1) for i in range(0, n, 4999)]
    for threads in (1, 2, 0):
        big = s.cast_rays(rays, nthreads=threads)
        for key in ("t_hit", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"):
            np.testing.assert_array_equal(big[key], np.concatenate([a[key] for a in small]), err_msg=key)
        np.testing.assert_array_equal(s.test_occlusions(rays, nthreads=threads),
                                      np.concatenate([s.test_occlusions(rays[i:i + 4999]) for i in range(0, n, 4999)]))
        np.testing.assert_array_equal(s.count_intersections(rays, nthreads=threads),
                                      np.concatenate([s.count_intersections(rays[i:i + 4999]) for i in range(0, n, 4999)]))
    assert np.isfinite(big["t_hit"]).sum() > n // 10  # rays that hit, and rays that miss
    assert np.isinf(big["t_hit"]).sum() > n // 10


def test_occlusion_counts_and_lists_count_shared_edges_once():
    s = box_scene()
    # Straight down through the top face's diagonal (shared by two triangles) and the bottom's.
    rays = np.array([[0.5, 0.5, 2, 0, 0, -1], [0.3, 0.6, 2, 0, 0, -1], [3, 3, 3, 1, 0, 0]], np.float32)
    np.testing.assert_array_equal(s.count_intersections(rays), [2, 2, 0])
    assert s.count_intersections(rays).dtype == np.int32
    lst = s.list_intersections(rays)
    np.testing.assert_array_equal(lst["ray_splits"], [0, 2, 4, 4])
    np.testing.assert_array_equal(lst["ray_ids"], [0, 0, 1, 1])
    np.testing.assert_array_equal(lst["t_hit"], [1, 2, 1, 2])
    np.testing.assert_array_equal(s.test_occlusions(rays), [True, True, False])
    np.testing.assert_array_equal(s.test_occlusions(rays, tfar=0.5), [False, False, False])


def test_points_distances_and_occupancy():
    s = box_scene()
    pts = np.array([[0.5, 0.5, 0.5], [2, 0.5, 0.5], [0.5, 0.5, 0.9], [0.5, -1, 0.5]], np.float32)
    np.testing.assert_allclose(s.compute_distance(pts), [0.5, 1.0, 0.1, 1.0], rtol=1e-6)
    np.testing.assert_allclose(s.compute_signed_distance(pts), [-0.5, 1.0, -0.1, 1.0], rtol=1e-6)
    np.testing.assert_array_equal(s.compute_occupancy(pts), [1, 0, 1, 0])
    c = s.compute_closest_points(pts)
    np.testing.assert_allclose(c["points"][1], [1, 0.5, 0.5])
    np.testing.assert_allclose(c["primitive_normals"][1], [1, 0, 0], atol=1e-6)
    assert c["geometry_ids"].tolist() == [0, 0, 0, 0]
    many = np.repeat(pts, 5000, axis=0)  # normals of a batch on threads: those of the small call
    np.testing.assert_array_equal(s.compute_closest_points(many, nthreads=2)["primitive_normals"],
                                  np.repeat(c["primitive_normals"], 5000, axis=0))
    nothing = volley.RaycastingScene().compute_closest_points(pts[:1])  # an empty scene finds nothing
    assert np.isinf(nothing["points"]).all() and nothing["primitive_ids"][0] == volley.INVALID_ID
    np.testing.assert_array_equal(nothing["primitive_normals"], [[0, 0, 0]])
    for n in (1, 2, 3):
        np.testing.assert_array_equal(s.compute_distance(pts, nthreads=n), s.compute_distance(pts))


def test_bad_input_raises_value_error_naming_the_argument():
    s = volley.RaycastingScene()
    with pytest.raises(ValueError, match="vertices"):
        s.add_triangles(np.zeros((4, 2)), BOX_T[:1])
    with pytest.raises(ValueError, match="row 1"):
        s.add_triangles(np.array([[0, 0, 0], [np.nan, 0, 0], [0, 1, 0]]), [[0, 1, 2]])
    with pytest.raises(ValueError, match="triangles.*out of range"):
        s.add_triangles(BOX_V, np.array([[0, 1, 8]]))
    with pytest.raises(ValueError, match="triangles.*out of range"):
        s.add_triangles(BOX_V, np.array([[0, -1, 2]]))
    with pytest.raises(ValueError, match=r"triangles: expected shape \(M, 3\)"):
        s.add_triangles(BOX_V, np.array([0, 1, 2]))
    s.add_triangles(BOX_V, BOX_T)
    with pytest.raises(ValueError, match=r"rays: expected shape \(\.\.\., 6\)"):
        s.cast_rays(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="query_points"):
        s.compute_distance(np.zeros((3, 4)))
    with pytest.raises(ValueError, match="nthreads"):
        s.cast_rays(np.zeros((1, 6)), nthreads=-2)
    with pytest.raises(ValueError, match="test"):
        volley.RaycastingScene(test="fast")
    with pytest.raises(ValueError, match="geometry 7"):
        s.update_vertices(7, BOX_V)
    with pytest.raises(ValueError):
        s.update_vertices(0, BOX_V[:5])  # another vertex count
    plane = box_scene(test="plane")
    with pytest.raises(ValueError, match="plane test"):
        plane.compute_distance(np.zeros((1, 3)))
    with pytest.raises(OSError, match="missing.obj"):
        volley.read_triangle_mesh("/nonexistent/missing.obj")


def test_instances_refit_options_and_info():
    proto = box_scene()
    s = volley.RaycastingScene(test="watertight", isa="auto")
    m = np.array([[2, 0, 0, 10], [0, 2, 0, 0], [0, 0, 2, 0]], np.float32)
    assert s.add_instance(proto, m) == 0
    a = s.cast_rays(np.array([[11, 1, 5, 0, 0, -1]], np.float32))
    assert a["t_hit"][0] == 3.0
    np.testing.assert_allclose(a["primitive_normals"][0], [0, 0, 1], atol=1e-6)
    info = s.info()
    assert info["instances"] == 1 and info["instanced_triangles"] == 12
    # Refit: move the box up by 1, the next query sees it.
    b = box_scene(isa="scalar")
    b.cast_rays(np.zeros((1, 6), np.float32))
    b.update_vertices(0, BOX_V + np.float32([0, 0, 1]))
    assert b.cast_rays(np.array([[0.5, 0.5, 5, 0, 0, -1]], np.float32))["t_hit"][0] == 3.0
    assert b.info()["isa"] == "scalar"


def test_pickle_and_save_load_give_the_same_answers(tmp_path):
    s = box_scene()
    s.set_geometry_mask(0, 3)
    rays = np.random.default_rng(1).uniform(-1, 2, (500, 6)).astype(np.float32)
    want = s.cast_rays(rays)
    back = pickle.loads(pickle.dumps(s))
    got = back.cast_rays(rays)
    for k in ("t_hit", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"):
        np.testing.assert_array_equal(got[k], want[k])
    path = str(tmp_path / "box.vacc")
    s.save(path)
    loaded = volley.RaycastingScene.load(path)
    from_file = loaded.cast_rays(rays)
    for k in ("t_hit", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"):
        np.testing.assert_array_equal(from_file[k], want[k])  # normals too: the Accel reads them from the file
    assert loaded.info()["loaded"]
    with pytest.raises(ValueError, match="pickle"):
        pickle.dumps(loaded)


def test_high_quality_gives_the_same_answers_and_pickles_with_its_quality():
    # Long slivers across a box of small triangles: the spatial-split build cuts them.
    rng = np.random.default_rng(5)
    a, b = rng.uniform(-10, 10, (100, 3)), rng.uniform(-10, 10, (100, 3))
    slivers = np.stack([a, b, (a + b) / 2 + rng.uniform(-0.5, 0.5, (100, 3))], axis=1).reshape(-1, 3)
    centres = rng.uniform(-10, 10, (400, 1, 3))
    dust = (centres + rng.uniform(-0.5, 0.5, (400, 3, 3))).reshape(-1, 3)
    vertices = np.concatenate([slivers, dust]).astype(np.float32)
    triangles = np.arange(len(vertices), dtype=np.uint32).reshape(-1, 3)
    medium, high = volley.RaycastingScene(), volley.RaycastingScene(quality="high")
    for s in (medium, high):
        s.add_triangles(vertices, triangles)
    rays = np.concatenate([rng.uniform(-15, 15, (3000, 3)), rng.uniform(-1, 1, (3000, 3))], axis=1).astype(np.float32)
    want, got = medium.cast_rays(rays), high.cast_rays(rays)
    for k in ("t_hit", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"):
        np.testing.assert_array_equal(got[k], want[k])
    np.testing.assert_array_equal(high.count_intersections(rays), medium.count_intersections(rays))
    info = high.info()
    assert info["quality"] == "high" and info["references"] > len(triangles)
    assert medium.info()["quality"] == "medium"
    back = pickle.loads(pickle.dumps(high))
    assert back.info()["quality"] == "high"
    with pytest.raises(ValueError, match="quality"):
        volley.RaycastingScene(quality="low")


def write_vray(path, rays):
    with open(path, "wb") as f:
        f.write(b"VRAY" + struct.pack("<IQ", 1, len(rays)))
        f.write(rays.astype("<f4").tobytes())


def write_vpts(path, pts):
    with open(path, "wb") as f:
        f.write(b"VPTS" + struct.pack("<IQ", 1, len(pts)))
        f.write(pts.astype("<f4").tobytes())


def read_records(path, dtype, width=1):
    with open(path, "rb") as f:
        head = f.read(16)
        n = struct.unpack("<Q", head[8:16])[0]
        data = np.frombuffer(f.read(), dtype)
    return data.reshape(n, width) if width > 1 else data


@pytest.mark.skipif(not os.environ.get("VOLLEY_BINARY"), reason="VOLLEY_BINARY (the volley command) not set")
def test_same_answers_as_the_command_line_bit_for_bit(tmp_path):
    exe = os.environ["VOLLEY_BINARY"]
    mesh = tmp_path / "box.obj"
    with open(mesh, "w") as f:
        f.writelines(f"v {x} {y} {z}\n" for x, y, z in BOX_V)
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in BOX_T)
    v, t = volley.read_triangle_mesh(str(mesh))
    s = volley.RaycastingScene()
    s.add_triangles(v, t)
    rng = np.random.default_rng(5)
    o = rng.uniform(-1, 2, (2000, 3))
    d = rng.normal(size=(2000, 3))
    rays6 = np.hstack([o, d]).astype(np.float32)
    vray = np.hstack([o, np.zeros((2000, 1)), d, np.full((2000, 1), np.inf)]).astype(np.float32)
    write_vray(tmp_path / "r.vray", vray)
    subprocess.run([exe, "trace", str(mesh), "--rays", str(tmp_path / "r.vray"), "--reps", "1", "-o", str(tmp_path / "r.vhit")],
                   check=True, capture_output=True)
    hits = read_records(tmp_path / "r.vhit", np.dtype([("t", "<f4"), ("u", "<f4"), ("v", "<f4"), ("prim", "<u4"),
                                                      ("geom", "<u4"), ("inst", "<u4")]))
    a = s.cast_rays(rays6)
    np.testing.assert_array_equal(a["t_hit"], hits["t"])
    np.testing.assert_array_equal(a["primitive_ids"], hits["prim"])
    subprocess.run([exe, "trace", str(mesh), "--rays", str(tmp_path / "r.vray"), "--reps", "1", "--count",
                    "-o", str(tmp_path / "r.vcnt")], check=True, capture_output=True)
    np.testing.assert_array_equal(s.count_intersections(rays6), read_records(tmp_path / "r.vcnt", "<u4"))
    pts = rng.uniform(-0.5, 1.5, (3000, 3)).astype(np.float32)
    write_vpts(tmp_path / "p.vpts", pts)
    subprocess.run([exe, "query", str(mesh), "--points", str(tmp_path / "p.vpts"), "--op", "signed-distance", "--reps", "1",
                    "-o", str(tmp_path / "p.vdst")], check=True, capture_output=True)
    np.testing.assert_array_equal(s.compute_signed_distance(pts), read_records(tmp_path / "p.vdst", "<f4"))
    subprocess.run([exe, "query", str(mesh), "--points", str(tmp_path / "p.vpts"), "--op", "contains", "--reps", "1",
                    "-o", str(tmp_path / "p.vocc")], check=True, capture_output=True)
    np.testing.assert_array_equal(s.compute_occupancy(pts), read_records(tmp_path / "p.vocc", "u1").astype(np.float32))


def test_a_thousand_scenes_leak_nothing_and_outlive_their_arrays():
    def cycle():
        v = BOX_V.copy()
        s = volley.RaycastingScene()
        s.add_triangles(v, BOX_T.copy())
        del v  # the scene keeps its own copy
        s.cast_rays(np.array([[0.5, 0.5, 2, 0, 0, -1]], np.float32))
        s.compute_distance(np.zeros((10, 3), np.float32))
        return s.count_intersections(np.array([[0.5, 0.5, 2, 0, 0, -1]], np.float32))[0]

    for _ in range(100):  # warm up allocators and caches
        cycle()
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    for _ in range(1000):
        assert cycle() == 2
    grown_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before
    assert grown_kib < 2048, f"1000 create/commit/query/destroy cycles grew the peak RSS by {grown_kib} KiB"
