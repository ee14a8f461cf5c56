#!/usr/bin/env python3
"""A batch job over many meshes on a Dask cluster: each task loads a mesh, builds a scene
and measures its volume by occupancy sampling and its mean surface distance of random
points. LocalCluster runs the workers as processes on this machine; point --scheduler at a
real cluster's address to spread the same job over many (the scene is picklable too, so a
built one can be sent to workers instead of a path).

    python3 examples/batch_dask.py scenes/downloads/stanford-bunny.obj scenes/downloads/dragon_100k.obj
    (scenes/fetch downloads the meshes; any .obj, .ply or scene .json will do)
"""
import argparse
import time

import numpy as np

import volley


def measure(path, samples, seed):
    vertices, triangles = volley.read_triangle_mesh(path)
    scene = volley.RaycastingScene()
    scene.add_triangles(vertices, triangles)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    pts = np.random.default_rng(seed).uniform(lo, hi, (samples, 3)).astype(np.float32)
    inside = scene.compute_occupancy(pts, nthreads=1)
    volume = float(inside.mean() * np.prod(hi - lo))
    distance = float(scene.compute_distance(pts, nthreads=1).mean())
    return {"mesh": path, "triangles": len(triangles), "volume": volume, "mean_distance": distance}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--samples", type=int, default=100000, help="points per mesh")
    ap.add_argument("--workers", type=int, default=2, help="local worker processes (without --scheduler)")
    ap.add_argument("--scheduler", help="address of an existing Dask scheduler (tcp://host:8786)")
    a = ap.parse_args()
    from dask.distributed import Client, LocalCluster

    t0 = time.perf_counter()
    if a.scheduler:
        client = Client(a.scheduler)
    else:
        client = Client(LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True, dashboard_address=None))
    with client:
        futures = [client.submit(measure, m, a.samples, i) for i, m in enumerate(a.meshes)]
        for r in client.gather(futures):
            print(f"{r['mesh']}: {r['triangles']} triangles, volume {r['volume']:.6g}, "
                  f"mean distance of {a.samples} points {r['mean_distance']:.6g}")
    print(f"{len(a.meshes)} meshes in {time.perf_counter() - t0:.1f} s")


if __name__ == "__main__":
    main()
