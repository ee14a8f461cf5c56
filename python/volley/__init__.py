"""volley for Python: a SIMD ray tracing kernel with Open3D's RaycastingScene API.

    import numpy as np, volley
    scene = volley.RaycastingScene()
    scene.add_triangles(*volley.read_triangle_mesh("bunny.obj"))
    rays = volley.RaycastingScene.create_rays_pinhole(60, [0, 0.1, 0], [0, 0.1, 0.4], [0, 1, 0], 640, 480)
    ans = scene.cast_rays(rays)
    ans["t_hit"], ans["geometry_ids"], ans["primitive_ids"]

Code written for Open3D's o3d.t.geometry.RaycastingScene runs with the import changed and
.numpy() dropped: the answers are NumPy arrays. volley's own files (.vray, .vhit, .vpts,
.vcnt, .vocc, .vdst, .vclp, .vall) read and write as NumPy arrays: volley.read_rays, ...
"""
from ._volley import INVALID_ID, __version__, read_triangle_mesh
from .files import (CLOSEST_DTYPE, HIT_DTYPE, RAY_DTYPE, read_closest, read_counts, read_distances, read_hit_lists,
                    read_hits, read_occupancy, read_points, read_rays, write_closest, write_counts, write_distances,
                    write_hit_lists, write_hits, write_occupancy, write_points, write_rays)
from .raycasting_scene import RaycastingScene

__all__ = ["INVALID_ID", "RaycastingScene", "read_triangle_mesh", "__version__",
           "RAY_DTYPE", "HIT_DTYPE", "CLOSEST_DTYPE",
           "read_rays", "write_rays", "read_hits", "write_hits", "read_points", "write_points",
           "read_counts", "write_counts", "read_occupancy", "write_occupancy", "read_distances", "write_distances",
           "read_closest", "write_closest", "read_hit_lists", "write_hit_lists"]
