"""Open3D's ray casting tutorial (docs/jupyter/geometry/ray_casting.ipynb) with volley's
scene: the tutorial's code with `o3d.t.geometry.RaycastingScene` changed to
`volley.RaycastingScene` and `.numpy()` dropped (Open3D still makes the meshes), the plots
written to PNG files. One line needs NumPy's spelling: the tensor method
`ans['t_hit'].isfinite()` is `np.isfinite(ans['t_hit'])`. A local check:

    PYTHONPATH=build/release/python /usr/bin/python3 python/open3d_adapter/tutorial_ray_casting.py out/tutorial
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import open3d as o3d

import volley

out = sys.argv[1] if len(sys.argv) > 1 else "out/tutorial"
os.makedirs(out, exist_ok=True)

cube = o3d.geometry.TriangleMesh.create_box().translate([0, 0, 0])
cube = o3d.t.geometry.TriangleMesh.from_legacy(cube)
scene = volley.RaycastingScene()
cube_id = scene.add_triangles(cube)
print(cube_id)
rays = o3d.core.Tensor([[0.5, 0.5, 10, 0, 0, -1], [-1, -1, -1, 0, 0, -1]], dtype=o3d.core.Dtype.Float32)
ans = scene.cast_rays(rays)
print(ans.keys())
print(ans['t_hit'], ans['geometry_ids'])
assert ans['t_hit'][0] == 9 and ans['geometry_ids'][1] == scene.INVALID_ID

cube = o3d.geometry.TriangleMesh.create_box().translate([0, 0, 0])
cube = o3d.t.geometry.TriangleMesh.from_legacy(cube)
torus = o3d.geometry.TriangleMesh.create_torus().translate([0, 0, 2])
torus = o3d.t.geometry.TriangleMesh.from_legacy(torus)
sphere = o3d.geometry.TriangleMesh.create_sphere(radius=0.5).translate([1, 2, 3])
sphere = o3d.t.geometry.TriangleMesh.from_legacy(sphere)
scene = volley.RaycastingScene()
scene.add_triangles(cube)
scene.add_triangles(torus)
_ = scene.add_triangles(sphere)
rays = volley.RaycastingScene.create_rays_pinhole(fov_deg=90, center=[0, 0, 2], eye=[2, 3, 0], up=[0, 1, 0],
                                                  width_px=640, height_px=480)
ans = scene.cast_rays(rays)
plt.imshow(ans['t_hit'])
plt.savefig(os.path.join(out, "t_hit.png"))
plt.imshow(np.abs(ans['primitive_normals']))
plt.savefig(os.path.join(out, "normals.png"))
plt.imshow(ans['geometry_ids'], vmax=3)
plt.savefig(os.path.join(out, "geometry_ids.png"))
hit = np.isfinite(ans['t_hit'])
points = rays[hit][:, :3] + rays[hit][:, 3:] * ans['t_hit'][hit].reshape((-1, 1))
pcd = o3d.t.geometry.PointCloud(o3d.core.Tensor(points))
print(f"{len(points)} points on the three meshes -> {out}/t_hit.png, normals.png, geometry_ids.png")
