#!/usr/bin/env python3
"""volley's point and crossing queries against Open3D's RaycastingScene (Embree inside).

Same mesh, same points or rays, same thread count; each side's best of --reps after a
warm-up call (Open3D builds its BVH at the first query, volley before its timed loop).
volley is timed by `volley query` / `volley trace` (their best_s), Open3D in this
process. Prints a markdown table with the CPU model and the answers' agreement.

  python3 perf/open3d_compare.py ../shared/scenes/stanford-bunny.obj --threads 1 2

Needs Debian's python3-open3d (0.16) and NumPy; not a test dependency.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

try:
    import open3d as o3d
except ImportError:
    sys.exit("open3d not found: apt-get install python3-open3d (and run Debian's /usr/bin/python3)")


def read_records(path, magic, dtype, width):
    with open(path, "rb") as f:
        head = f.read(16)
        if head[:4] != magic:
            sys.exit(f"{path}: not a {magic.decode()} file")
        count = int.from_bytes(head[8:16], "little")
        data = np.frombuffer(f.read(), dtype=dtype)
    return data.reshape(count, width) if width > 1 else data


def cpu_model():
    with open("/proc/cpuinfo") as f:
        for line in f:
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return "unknown CPU"


def best_of(fn, reps):
    fn()  # warm-up: Open3D commits its scene here
    times = []
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def volley(binary, args):
    out = subprocess.run([binary] + args, check=True, capture_output=True, text=True).stdout
    line = next(l for l in out.splitlines() if l.startswith(("query:", "trace:")))
    return dict(kv.split("=", 1) for kv in line.split()[1:])


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh", help="mesh file (.obj or .ply) both sides load")
    ap.add_argument("--volley", default="build/release/volley", help="the volley binary")
    ap.add_argument("--points", type=int, default=200000, help="query points (volley points, 50%% near the surface)")
    ap.add_argument("--threads", type=int, nargs="+", default=[1], help="thread counts to compare")
    ap.add_argument("--reps", type=int, default=5)
    ap.add_argument("--ops", nargs="+", default=["distance", "signed-distance", "contains", "count"],
                    choices=["distance", "signed-distance", "contains", "count"])
    a = ap.parse_args()

    tmp = tempfile.mkdtemp(prefix="volley_o3d_")
    pts_file = os.path.join(tmp, "p.vpts")
    subprocess.run([a.volley, "points", a.mesh, "-n", str(a.points), "-o", pts_file], check=True, capture_output=True)
    pts = np.ascontiguousarray(read_records(pts_file, b"VPTS", np.float32, 3))
    rays_file = os.path.join(tmp, "d.vray")
    subprocess.run([a.volley, "rays", a.mesh, "--workload", "diffuse", "--width", "512", "--height", "512", "-o", rays_file],
                   check=True, capture_output=True)
    vray = read_records(rays_file, b"VRAY", np.float32, 8)
    # Open3D's rays: origin and direction, all of [0, inf) (volley's diffuse rays start at tmin > 0: the same offset
    # moved into the origin, so both sides trace the same segment).
    o3d_rays = np.ascontiguousarray(np.hstack([vray[:, 0:3] + vray[:, 3:4] * vray[:, 4:7], vray[:, 4:7]]))
    t_rays = os.path.join(tmp, "d0.vray")
    shifted = vray.copy()
    shifted[:, 0:3] = o3d_rays[:, 0:3]
    shifted[:, 3] = 0.0
    with open(t_rays, "wb") as f:
        f.write(b"VRAY" + (1).to_bytes(4, "little") + len(shifted).to_bytes(8, "little") + shifted.astype("<f4").tobytes())

    legacy = o3d.io.read_triangle_mesh(a.mesh)
    scene = o3d.t.geometry.RaycastingScene()
    scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(legacy))
    p = o3d.core.Tensor(pts)
    r = o3d.core.Tensor(o3d_rays)

    # volley's Python package, in this process, when it imports (PYTHONPATH=build/release/python).
    try:
        import volley as vpy
        vs = vpy.RaycastingScene()
        vs.add_triangles(*vpy.read_triangle_mesh(a.mesh))
    except ImportError:
        vs = None

    rows = []
    for op in a.ops:
        for t in a.threads:
            if op == "count":
                o3d_s = best_of(lambda: scene.count_intersections(r, nthreads=t), a.reps)
                kv = volley(a.volley, ["trace", a.mesh, "--rays", t_rays, "--count", "--threads", str(t), "--reps", str(a.reps),
                                       "-o", os.path.join(tmp, "c.vcnt")])
                ours = read_records(os.path.join(tmp, "c.vcnt"), b"VCNT", np.uint32, 1)
                theirs = scene.count_intersections(r, nthreads=t).numpy()
                agree = f"{np.count_nonzero(ours != theirs)} of {len(ours)} rays differ"
                n = len(o3d_rays)
            else:
                call = {"distance": scene.compute_distance, "signed-distance": scene.compute_signed_distance,
                        "contains": scene.compute_occupancy}[op]
                o3d_s = best_of(lambda: call(p, nthreads=t), a.reps)
                out = os.path.join(tmp, "o")
                kv = volley(a.volley, ["query", a.mesh, "--points", pts_file, "--op", op, "--threads", str(t),
                                       "--reps", str(a.reps), "-o", out])
                theirs = call(p, nthreads=t).numpy()
                if op == "contains":
                    ours = read_records(out, b"VOCC", np.uint8, 1)
                    agree = f"{np.count_nonzero(ours != (theirs > 0.5))} of {len(ours)} points differ"
                else:
                    ours = read_records(out, b"VDST", np.float32, 1)
                    agree = f"max |difference| {np.max(np.abs(ours - theirs)):.3g}"
                n = len(pts)
            v_s = float(kv["best_s"])
            py_s = None
            if vs is not None:
                call = {"distance": vs.compute_distance, "signed-distance": vs.compute_signed_distance,
                        "contains": vs.compute_occupancy, "count": vs.count_intersections}[op]
                py_s = best_of(lambda: call(r.numpy() if op == "count" else pts, nthreads=t), a.reps)
            rows.append((op, t, n, o3d_s, v_s, py_s, agree))

    print(f"CPU: {cpu_model()}; mesh {a.mesh} ({len(legacy.triangles)} triangles); Open3D {o3d.__version__}; "
          f"best of {a.reps}\n")
    print("| query | threads | items | Open3D ms | volley ms | volley / Open3D speed | volley Python ms (speed) | answers |")
    print("|---|---|---|---|---|---|---|---|")
    for op, t, n, o, v, p, agree in rows:
        py = f"{p * 1e3:.1f} ({o / p:.2f}x)" if p else "-"
        print(f"| {op} | {t} | {n} | {o * 1e3:.1f} | {v * 1e3:.1f} | {o / v:.2f}x | {py} | {agree} |")


if __name__ == "__main__":
    main()
