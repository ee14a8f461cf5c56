#!/usr/bin/env python3
"""Ray casting a depth image of a mesh with a pinhole camera, saved as a PNG.

    python3 examples/depth_image.py scenes/downloads/stanford-bunny.obj -o out/bunny_depth.png
    (scenes/fetch downloads the meshes; any .obj, .ply or scene .json will do)
"""
import argparse
import time

import numpy as np

import volley
from png import write_png


def camera_rays(eye, look_at, up, fov_deg, width, height):
    """Open3D-style rays (..., 6) of a pinhole camera: origin and unit direction per pixel."""
    w = look_at - eye
    w /= np.linalg.norm(w)
    r = np.cross(w, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, w)
    half = np.tan(np.radians(fov_deg) / 2)
    xs = (np.arange(width) + 0.5) / width * 2 - 1
    ys = 1 - (np.arange(height) + 0.5) / height * 2
    d = w + half * (xs[None, :, None] * r * width / height + ys[:, None, None] * u)
    d /= np.linalg.norm(d, axis=2, keepdims=True)
    rays = np.empty((height, width, 6), np.float32)
    rays[..., :3] = eye
    rays[..., 3:] = d
    return rays


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mesh")
    ap.add_argument("-o", "--output", default="out/depth.png")
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    a = ap.parse_args()

    vertices, triangles = volley.read_triangle_mesh(a.mesh)
    scene = volley.RaycastingScene()
    scene.add_triangles(vertices, triangles)
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    centre, size = (lo + hi) / 2, np.linalg.norm(hi - lo)
    eye = centre + size * np.array([0.2, 0.3, 1.2])
    rays = camera_rays(eye, centre, np.array([0.0, 1.0, 0.0]), 45, a.width, a.height)
    t0 = time.perf_counter()
    ans = scene.cast_rays(rays)
    seconds = time.perf_counter() - t0
    depth = ans["t_hit"]
    hit = np.isfinite(depth)
    near, far = depth[hit].min(), depth[hit].max()
    image = np.where(hit, 1.0 - 0.8 * (depth - near) / max(far - near, 1e-12), 0.0)
    write_png(a.output, image)
    print(f"{a.mesh}: {a.width}x{a.height} rays, {int(hit.sum())} hits, cast in {seconds * 1e3:.1f} ms "
          f"({rays.size // 6 / seconds / 1e6:.2f} Mrays/s) -> {a.output}")


if __name__ == "__main__":
    main()
