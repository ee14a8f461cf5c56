"""Runs Open3D's own RaycastingScene tests against volley (a local check, not part of the
package or of `make test`): Open3D (Debian's python3-open3d) still supplies its tensors and
meshes, and only o3d.t.geometry.RaycastingScene is replaced by volley's, with volley's
NumPy answers turned into o3d.core.Tensor, as the tests expect. Usage:

    cp OPEN3D/python/test/t/geometry/test_raycasting_scene.py python/open3d_adapter/
    PYTHONPATH=build/release/python /usr/bin/python3 -m pytest -q python/open3d_adapter
"""
import numpy as np
import open3d as o3d

import volley


def _tensor(value):
    if isinstance(value, dict):
        return {k: _tensor(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        return o3d.core.Tensor.from_numpy(np.ascontiguousarray(value))
    return value


class RaycastingScene(volley.RaycastingScene):
    """volley's scene with Open3D's tensor type on the way out (and nothing else)."""


for _name in ("cast_rays", "test_occlusions", "count_intersections", "list_intersections", "compute_closest_points",
              "compute_distance", "compute_signed_distance", "compute_occupancy"):
    def _wrap(method):
        def call(self, *args, **kwargs):
            return _tensor(method(self, *args, **kwargs))
        return call
    setattr(RaycastingScene, _name, _wrap(getattr(volley.RaycastingScene, _name)))
RaycastingScene.create_rays_pinhole = staticmethod(
    lambda *args, **kwargs: _tensor(volley.RaycastingScene.create_rays_pinhole(*args, **kwargs)))

o3d.t.geometry.RaycastingScene = RaycastingScene
