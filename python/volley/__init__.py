"""volley for Python: a SIMD ray tracing kernel with Open3D's RaycastingScene API.

    import numpy as np, volley
    scene = volley.RaycastingScene()
    scene.add_triangles(*volley.read_triangle_mesh("bunny.obj"))
    rays = volley.RaycastingScene.create_rays_pinhole(60, [0, 0.1, 0], [0, 0.1, 0.4], [0, 1, 0], 640, 480)
    ans = scene.cast_rays(rays)
    ans["t_hit"], ans["geometry_ids"], ans["primitive_ids"]

Code written for Open3D's o3d.t.geometry.RaycastingScene runs with the import changed and
.numpy() dropped: the answers are NumPy arrays.
"""
from ._volley import INVALID_ID, __version__, read_triangle_mesh
from .raycasting_scene import RaycastingScene

__all__ = ["INVALID_ID", "RaycastingScene", "read_triangle_mesh", "__version__"]
