"""volley for Python: a SIMD ray tracing kernel with Open3D's RaycastingScene API.

    import numpy as np, volley
    scene = volley.RaycastingScene()
    scene.add_triangles(*volley.read_triangle_mesh("bunny.obj"))
    ans = scene.cast_rays(np.array([[0, 0, 5, 0, 0, -1]], dtype=np.float32))
    ans["t_hit"], ans["geometry_ids"], ans["primitive_ids"]

Everything is in the extension module _volley; this package re-exports it.
"""
from ._volley import INVALID_ID, RaycastingScene, __version__, read_triangle_mesh

__all__ = ["INVALID_ID", "RaycastingScene", "read_triangle_mesh", "__version__"]
