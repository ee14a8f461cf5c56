#!/usr/bin/env python3
"""Occupancy and signed distance of a mesh on a grid, saved as a PNG slice plot.

    python3 examples/sdf_slice.py scenes/downloads/stanford-bunny.obj -o out/bunny_sdf.png
    (scenes/fetch downloads the meshes; any .obj, .ply or scene .json will do)

The middle slice of a grid over the mesh's box (widened 10%): left, occupancy (black
inside); right, signed distance (blue inside, red outside, white on the surface).
"""
import argparse
import time

import numpy as np

import volley
from png import diverging, write_png


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh")
    ap.add_argument("-o", "--output", default="out/sdf_slice.png")
    ap.add_argument("--size", type=int, default=256, help="grid cells per side of the slice")
    ap.add_argument("--axis", type=int, default=2, choices=[0, 1, 2], help="the axis the slice is across")
    a = ap.parse_args()

    vertices, triangles = volley.read_triangle_mesh(a.mesh)
    scene = volley.RaycastingScene()
    scene.add_triangles(vertices, triangles)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    pad = 0.1 * (hi - lo)
    lo, hi = lo - pad, hi + pad
    u, v = [k for k in range(3) if k != a.axis]
    grid = np.zeros((a.size, a.size, 3), np.float32)
    grid[..., a.axis] = 0.5 * (lo[a.axis] + hi[a.axis])
    grid[..., u] = np.linspace(lo[u], hi[u], a.size)[None, :]
    grid[..., v] = np.linspace(hi[v], lo[v], a.size)[:, None]  # image rows top to bottom

    t0 = time.perf_counter()
    occupancy = scene.compute_occupancy(grid)
    sdf = scene.compute_signed_distance(grid)
    seconds = time.perf_counter() - t0
    image = np.concatenate([np.repeat(1.0 - occupancy[..., None], 3, axis=2), diverging(sdf, np.abs(sdf).max())], axis=1)
    write_png(a.output, image)
    print(f"{a.mesh}: {len(triangles)} triangles, {a.size}x{a.size} slice, {int(occupancy.sum())} cells inside, "
          f"occupancy + signed distance in {seconds * 1e3:.1f} ms -> {a.output}")


if __name__ == "__main__":
    main()
