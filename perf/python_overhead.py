#!/usr/bin/env python3
"""The Python package's overhead against the C++ API on the same rays and points, each
call against its C++ twin (the same answers):

  cast_rays           volley trace --mode stream --normals (Accel::intersect on a ray
                      array, then Accel::geometric_normals: Open3D's dictionary has normals),
                      and without --normals (the hits alone: 24 bytes a ray against the
                      dictionary's 32 and no normals)
  test_occlusions     volley trace --mode stream --occluded (Accel::occluded on a ray array)
  count_intersections volley trace --mode stream --count (Accel::count_intersections on a
                      ray array)
  compute_distance    volley query --op distance (Accel::distances)
  with --all-points also compute_signed_distance, compute_occupancy (Accel::contains) and
  compute_closest_points (Accel::closest_points) against `volley query --op ...`

With --threads above 1 the stream calls become `--mode batch` (the same call on a thread
count). Best of --reps each, alternating, at each thread count of --threads (one by
default; "1,2,4,8,16" gives the scaling of both sides). Prints a markdown table with the
CPU model.

  PYTHONPATH=build/release/python /usr/bin/python3 perf/python_overhead.py ../shared/scenes/stanford-bunny.obj
"""
import argparse
import os
import subprocess
import tempfile
import time

import numpy as np

import volley


def read_records(path, magic, dtype, width):
    with open(path, "rb") as f:
        head = f.read(16)
        assert head[:4] == magic, path
        n = int.from_bytes(head[8:16], "little")
        return np.frombuffer(f.read(), dtype).reshape(n, width)


def best_line(exe, args):
    out = subprocess.run([exe] + args, check=True, capture_output=True, text=True).stdout
    line = next(l for l in out.splitlines() if l.startswith(("trace:", "query:")))
    return float(dict(kv.split("=", 1) for kv in line.split()[1:])["best_s"])


def thread_counts(text):
    try:
        counts = [int(t) for t in text.split(",")]
    except ValueError:
        counts = []
    if not counts or min(counts) < 1:
        raise argparse.ArgumentTypeError(f"expected thread counts >= 1 separated by commas, got {text!r}")
    return counts


def cpu_model():
    with open("/proc/cpuinfo") as f:
        return next((l.split(":", 1)[1].strip() for l in f if l.startswith("model name")), "unknown CPU")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh")
    ap.add_argument("--volley", default="build/release/volley")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=3, help="alternations of the C++ and the Python runs")
    ap.add_argument("--threads", default=[1], type=thread_counts,
                    help="comma-separated thread counts, each 1 or more (nthreads on the Python side)")
    ap.add_argument("--workload", default="primary", choices=["primary", "diffuse"],
                    help="the rays (diffuse: their tmin offset moved into the origin on both sides)")
    ap.add_argument("--all-points", action="store_true",
                    help="also compute_signed_distance, compute_occupancy and compute_closest_points")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="volley_py_")
    rays_file, pts_file = os.path.join(tmp, "r.vray"), os.path.join(tmp, "p.vpts")
    subprocess.run([a.volley, "rays", a.mesh, "--workload", a.workload, "--width", "1024", "--height", "1024", "-o",
                    rays_file], check=True, capture_output=True)
    subprocess.run([a.volley, "points", a.mesh, "-n", "1000000", "-o", pts_file], check=True, capture_output=True)
    vray = read_records(rays_file, b"VRAY", np.float32, 8).copy()
    # Open3D-style rays span [0, inf): a tmin offset moves into the origin, for both sides.
    vray[:, 0:3] += vray[:, 3:4] * vray[:, 4:7]
    vray[:, 3] = 0
    vray[:, 7] = np.inf
    with open(rays_file, "wb") as f:
        f.write(b"VRAY" + (1).to_bytes(4, "little") + len(vray).to_bytes(8, "little") + vray.astype("<f4").tobytes())
    rays = np.ascontiguousarray(np.hstack([vray[:, 0:3], vray[:, 4:7]]))
    pts = np.ascontiguousarray(read_records(pts_file, b"VPTS", np.float32, 3))

    vertices, triangles = volley.read_triangle_mesh(a.mesh)
    scene = volley.RaycastingScene()
    scene.add_triangles(vertices, triangles)
    scene.cast_rays(rays[:16], nthreads=1)  # build

    def py_best(fn):
        times = []
        for _ in range(a.reps):
            t0 = time.perf_counter()
            fn()
            times.append(time.perf_counter() - t0)
        return min(times)

    threads = a.threads
    rays_args = [a.mesh, "--rays", rays_file, "--reps", str(a.reps)]
    pts_args = [a.mesh, "--points", pts_file, "--reps", str(a.reps)]

    def stream(t):
        return ["--mode", "stream" if t == 1 else "batch", "--threads", str(t)]

    # (label, the C++ command's arguments for t threads, the Python call for t threads)
    calls = [
        ("cast_rays vs intersect + geometric_normals", lambda t: ["trace"] + rays_args + stream(t) + ["--normals"],
         lambda t: scene.cast_rays(rays, nthreads=t)),
        ("cast_rays vs intersect (no normals)", lambda t: ["trace"] + rays_args + stream(t),
         lambda t: scene.cast_rays(rays, nthreads=t)),
        ("test_occlusions vs occluded", lambda t: ["trace"] + rays_args + stream(t) + ["--occluded"],
         lambda t: scene.test_occlusions(rays, nthreads=t)),
        ("count_intersections vs count_intersections", lambda t: ["trace"] + rays_args + stream(t) + ["--count"],
         lambda t: scene.count_intersections(rays, nthreads=t)),
        ("compute_distance vs distances", lambda t: ["query"] + pts_args + ["--op", "distance", "--threads", str(t)],
         lambda t: scene.compute_distance(pts, nthreads=t)),
    ]
    if a.all_points:
        calls += [
            ("compute_signed_distance vs distances", lambda t: ["query"] + pts_args + ["--op", "signed-distance",
                                                                                      "--threads", str(t)],
             lambda t: scene.compute_signed_distance(pts, nthreads=t)),
            ("compute_occupancy vs contains", lambda t: ["query"] + pts_args + ["--op", "contains", "--threads", str(t)],
             lambda t: scene.compute_occupancy(pts, nthreads=t)),
            ("compute_closest_points vs closest_points", lambda t: ["query"] + pts_args + ["--op", "closest",
                                                                                          "--threads", str(t)],
             lambda t: scene.compute_closest_points(pts, nthreads=t)),
        ]
    best = {(c[0], t): ([], []) for c in calls for t in threads}  # C++ times, Python times
    for _ in range(a.rounds):
        for t in threads:
            for label, cpp_args, py_call in calls:
                cpp, py = best[(label, t)]
                cpp.append(best_line(a.volley, cpp_args(t)))
                py.append(py_best(lambda: py_call(t)))
    print(f"CPU: {cpu_model()} ({os.cpu_count()} cores); mesh {a.mesh} ({len(triangles)} triangles); {len(rays)} "
          f"{a.workload} rays / 1M points; best of {a.reps} x {a.rounds} alternating rounds\n")
    print("| call | threads | C++ ms | Python ms | Python overhead | C++ speedup | Python speedup |")
    print("|---|---|---|---|---|---|---|")
    for c, _, _ in calls:
        c1, p1 = (min(x) for x in best[(c, threads[0])])
        for t in threads:
            cpp, py = (min(x) for x in best[(c, t)])
            print(f"| {c} | {t} | {cpp * 1e3:.1f} | {py * 1e3:.1f} | {100 * (py / cpp - 1):+.1f}% | "
                  f"{c1 / cpp:.2f}x | {p1 / py:.2f}x |")


if __name__ == "__main__":
    main()
