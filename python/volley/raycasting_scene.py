"""volley.RaycastingScene: Open3D's ``open3d.t.geometry.RaycastingScene``, call for call.

Code written for Open3D runs with the import changed: the same constructor, methods,
keywords, defaults, answer dictionaries, dtypes and shapes. The answers are NumPy arrays
(drop Open3D's ``.numpy()``). Inputs may be NumPy arrays, anything with ``__array__`` or
DLPack (Open3D and PyTorch CPU tensors, read without a copy where the layout allows),
nested lists, and Open3D meshes (tensor or legacy) for ``add_triangles``. volley's own
options (``test``, ``isa``, ``quality``) are keyword-only.
"""
import math

import numpy as np

from . import _volley

_INF = math.inf


def as_array(value, name):
    """`value` as a NumPy array without a copy where its layout allows: NumPy arrays and
    lists as they are, DLPack producers (PyTorch, Open3D) through np.from_dlpack, anything
    else with __array__ or a .numpy() method (Open3D tensors)."""
    if isinstance(value, np.ndarray):
        return value
    if hasattr(value, "__dlpack__"):
        try:
            return np.from_dlpack(value)
        except (TypeError, RuntimeError, BufferError):
            pass  # a device NumPy cannot read, or a dtype it has not: try the other ways
    if hasattr(value, "__array__"):
        return np.asarray(value)
    if callable(getattr(value, "numpy", None)):
        return np.asarray(value.numpy())
    if isinstance(value, (list, tuple)):
        return np.asarray(value)
    raise TypeError(f"{name}: expected an array (NumPy, a tensor, nested lists), got {type(value).__name__}")


def _check_device(device):
    if device is None:
        return
    text = str(device).strip().lower()
    if text in ("cpu", "cpu:0"):
        return
    raise ValueError(f"device: volley runs on the CPU (device 'CPU:0'), got {device!s}")


def _check_threads(name, nthreads):
    if isinstance(nthreads, bool) or not isinstance(nthreads, (int, np.integer)):
        raise TypeError(f"{name}: expected an int (0 for all cores), got {type(nthreads).__name__}")
    if nthreads < 0:
        raise ValueError(f"{name}: expected 0 (all cores) or a positive count, got {nthreads}")


def _check_samples(nsamples):
    if isinstance(nsamples, bool) or not isinstance(nsamples, (int, np.integer)):
        raise TypeError(f"nsamples: expected an odd int >= 1, got {type(nsamples).__name__}")
    if nsamples < 1 or nsamples % 2 != 1:
        raise ValueError(f"nsamples: expected an odd number >= 1 (Open3D's rule), got {nsamples}")


def _ray_arguments(rays, nthreads, masks):
    """What every ray query checks and converts: (rays as an array, masks or None)."""
    _check_threads("nthreads", nthreads)
    rays = as_array(rays, "rays")
    return rays, _ray_masks(masks, rays)


def _ray_exclusions(exclude, rays):
    """None, or `exclude` as a C-ordered (n, 3) uint32 array of (geometry, primitive,
    instance) per ray of `rays` (..., 6): from a dict with geometry_ids and primitive_ids
    (such as cast_rays' answer) and optionally instance_ids, each of shape (...)."""
    if exclude is None:
        return None
    if not hasattr(exclude, "__getitem__") or isinstance(exclude, (str, bytes)):
        raise ValueError("exclude: expected a dict with geometry_ids and primitive_ids "
                         "(a cast_rays answer), got " + type(exclude).__name__)
    lead = np.shape(rays)[:-1]
    columns = []
    for key, needed in (("geometry_ids", True), ("primitive_ids", True), ("instance_ids", False)):
        try:
            column = exclude[key]
        except (KeyError, IndexError, TypeError):
            if needed:
                raise ValueError(f"exclude: no {key} (pass a cast_rays answer, or a dict of "
                                 "geometry_ids and primitive_ids, one per ray)") from None
            column = np.full(lead, _volley.INVALID_ID, np.uint32)
        c = as_array(column, f"exclude['{key}']")
        if c.dtype.kind not in "iu":
            raise ValueError(f"exclude['{key}']: expected integer ids, got dtype {c.dtype}")
        if c.shape != lead:
            raise ValueError(f"exclude['{key}']: expected one id per ray, shape {lead}, got {c.shape}")
        if c.size and (int(c.min()) < 0 or int(c.max()) > 0xFFFFFFFF):
            raise ValueError(f"exclude['{key}']: expected ids in [0, 2**32 - 1] (INVALID_ID: none)")
        columns.append(np.asarray(c, np.uint32).reshape(-1))
    return np.ascontiguousarray(np.stack(columns, axis=1))


def _ray_masks(masks, rays):
    """None, or `masks` as a C-ordered uint32 array of one mask per ray of `rays` (..., 6)."""
    if masks is None:
        return None
    m = as_array(masks, "masks")
    if m.dtype.kind not in "iu":
        raise ValueError(f"masks: expected integers in [0, 2**32 - 1], got dtype {m.dtype}")
    lead = np.shape(rays)[:-1]
    if m.shape != lead:
        raise ValueError(f"masks: expected one mask per ray, shape {lead}, got {m.shape}")
    if m.size and (int(m.min()) < 0 or int(m.max()) > 0xFFFFFFFF):
        bad = m[(m < 0) | (m > 0xFFFFFFFF)].reshape(-1)[0]
        raise ValueError(f"masks: expected values in [0, 2**32 - 1], got {bad}")
    return np.ascontiguousarray(m, np.uint32)


def mesh_arrays(mesh):
    """(vertex positions, triangle indices) of an Open3D mesh, without importing Open3D:
    a tensor TriangleMesh (vertex.positions, triangle.indices) or a legacy one (vertices,
    triangles)."""
    vertex, triangle = getattr(mesh, "vertex", None), getattr(mesh, "triangle", None)
    if vertex is not None and triangle is not None and hasattr(vertex, "positions") and hasattr(triangle, "indices"):
        return as_array(vertex.positions, "mesh.vertex.positions"), as_array(triangle.indices, "mesh.triangle.indices")
    if hasattr(mesh, "vertices") and hasattr(mesh, "triangles"):
        return as_array(mesh.vertices, "mesh.vertices"), as_array(mesh.triangles, "mesh.triangles")
    raise TypeError("mesh: expected an Open3D TriangleMesh (tensor: vertex.positions and triangle.indices; legacy: "
                    f"vertices and triangles), got {type(mesh).__name__}")


def _is_mesh(value):
    return hasattr(value, "triangle") or (hasattr(value, "vertices") and hasattr(value, "triangles"))


class RaycastingScene:
    """Ray casting and point queries on triangle meshes, Open3D's RaycastingScene API.

    Add meshes with add_triangles, then cast rays or query points; the scene builds its
    structure before the first query after a change. Rays are arrays (..., 6) of origin
    and direction, points (..., 3), of any real dtype. Misses: t_hit inf, ids INVALID_ID.
    Every call on an array releases the GIL and runs on all cores (nthreads=0) or on
    nthreads threads, with the same answers for any count.

    Args:
        nthreads: threads that build the structure (0, the default: all cores).
        device: accepted for Open3D's API: None or the CPU ("CPU:0", an
            open3d.core.Device of the CPU); any other device is a ValueError.
        test: (keyword only) the ray/triangle test: "watertight" (default: no cracks
            between triangles that share an edge; shared edges and vertices counted once),
            "moller" (Moller-Trumbore) or "plane" (plane, then edge half-planes).
        isa: (keyword only) "auto" (default: the widest the CPU has), "scalar",
            "sse4.2", "avx2" or "avx512".
        quality: (keyword only) "medium" (binned SAH, default) or "high" (also spatial
            splits: a slower build, faster rays where triangles are long).
    """

    INVALID_ID = _volley.INVALID_ID

    def __init__(self, nthreads=0, device=None, *, test="watertight", isa="auto", quality="medium"):
        _check_threads("nthreads", nthreads)
        _check_device(device)
        self._engine = _volley.Engine(test, isa, quality, int(nthreads))

    # --- Building -------------------------------------------------------------------
    def add_triangles(self, vertex_positions=None, triangle_indices=None, mesh=None):
        """Adds a triangle mesh; returns its geometry id (0, 1, 2, ...).

        Two forms, as Open3D's: add_triangles(vertex_positions, triangle_indices) and
        add_triangles(mesh).

        Args:
            vertex_positions: (N, 3) vertex coordinates, any real dtype; finite.
            triangle_indices: (M, 3) vertex indices (integers in [0, N)).
            mesh: an Open3D TriangleMesh, tensor (vertex.positions, triangle.indices) or
                legacy (vertices, triangles); Open3D need not be imported by volley.
        """
        if mesh is None and triangle_indices is None and vertex_positions is not None and _is_mesh(vertex_positions):
            mesh, vertex_positions = vertex_positions, None
        if mesh is not None:
            if vertex_positions is not None or triangle_indices is not None:
                raise TypeError("add_triangles: pass either a mesh or vertex_positions and triangle_indices, not both")
            vertex_positions, triangle_indices = mesh_arrays(mesh)
        elif vertex_positions is None or triangle_indices is None:
            raise TypeError("add_triangles: expected (vertex_positions, triangle_indices) or (mesh)")
        return self._engine.add_triangles(as_array(vertex_positions, "vertex_positions"),
                                          as_array(triangle_indices, "triangle_indices"))

    def add_instance(self, prototype, transform):
        """Places another scene under an affine transform ((3, 4) or (4, 4), [A | t] row by
        row) as a geometry of this one (the prototype's structure is shared); returns its
        geometry id. Hits through it report this id."""
        if not isinstance(prototype, RaycastingScene):
            raise TypeError(f"prototype: expected a volley.RaycastingScene, got {type(prototype).__name__}")
        return self._engine.add_instance(prototype._engine, as_array(transform, "transform"))

    def update_vertices(self, geometry_id, vertex_positions):
        """Moves the vertices of mesh `geometry_id` (same count, same triangles); the next
        query refits the structure instead of building it anew."""
        return self._engine.update_vertices(geometry_id, as_array(vertex_positions, "vertex_positions"))

    def set_geometry_mask(self, geometry_id, mask):
        """Sets the 32-bit mask of a geometry (default 0xFFFFFFFF): a ray with a mask (the
        `masks` argument of the ray queries) sees it when the two share a bit."""
        if isinstance(mask, bool) or not isinstance(mask, (int, np.integer)) or not 0 <= int(mask) <= 0xFFFFFFFF:
            raise ValueError(f"mask: expected an integer in [0, 2**32 - 1], got {mask!r}")
        return self._engine.set_geometry_mask(geometry_id, int(mask))

    def disable_geometry(self, geometry_id):
        """Hides a geometry from every query until enable_geometry (its id stays)."""
        return self._engine.disable_geometry(geometry_id)

    def enable_geometry(self, geometry_id):
        """Shows a geometry that disable_geometry hid."""
        return self._engine.enable_geometry(geometry_id)

    # --- Ray queries ----------------------------------------------------------------
    def cast_rays(self, rays, nthreads=0, *, masks=None, exclude=None):
        """The closest hit of each ray.

        Args:
            rays: (..., 6) origin and direction (not necessarily unit length).
            nthreads: 0 (default) for all cores, or a thread count.
            masks: (keyword only) one 32-bit mask per ray, shape (...): a ray sees the
                geometries whose mask (set_geometry_mask) shares a bit with its own.
            exclude: (keyword only) one primitive per ray that the ray passes over: a dict
                of geometry_ids and primitive_ids of shape (...), such as the cast_rays
                answer whose hit points the rays start from (an INVALID_ID primitive leaves
                nothing out). Secondary rays then need no offset of their origins.

        Returns:
            dict of t_hit (...) float32 (inf for a miss; in units of the direction's
            length), geometry_ids (...) uint32, primitive_ids (...) uint32 (INVALID_ID for
            a miss), primitive_uvs (..., 2) float32 and primitive_normals (..., 3) float32
            (zeros for a miss).
        """
        rays, masks = _ray_arguments(rays, nthreads, masks)
        return self._engine.cast_rays(rays, nthreads, masks, _ray_exclusions(exclude, rays))

    def test_occlusions(self, rays, tnear=0.0, tfar=_INF, nthreads=0, *, masks=None, exclude=None):
        """Whether anything lies on each ray between tnear and tfar.

        Args:
            rays: (..., 6) origin and direction.
            tnear: start of the interval along each ray (inclusive), in units of the
                direction's length.
            tfar: end of the interval (exclusive).
            nthreads: 0 (default) for all cores, or a thread count.
            masks: (keyword only) one 32-bit mask per ray, shape (...): a ray sees the
                geometries whose mask (set_geometry_mask) shares a bit with its own.
            exclude: (keyword only) one primitive per ray that the ray passes over, as
                cast_rays' (shadow rays from hit points with tnear = 0).

        Returns:
            (...) bool.
        """
        rays, masks = _ray_arguments(rays, nthreads, masks)
        return self._engine.test_occlusions(rays, float(tnear), float(tfar), nthreads, masks,
                                            _ray_exclusions(exclude, rays))

    def count_intersections(self, rays, nthreads=0, *, masks=None):
        """The number of surface crossings along each ray, an edge or vertex shared by
        triangles counted once (with the default watertight test).

        Args:
            rays, nthreads, masks: as in cast_rays.

        Returns:
            (...) int32.
        """
        rays, masks = _ray_arguments(rays, nthreads, masks)
        return self._engine.count_intersections(rays, nthreads, masks)

    def list_intersections(self, rays, nthreads=0, *, masks=None):
        """Every hit along each ray, nearest first.

        Args:
            rays, nthreads, masks: as in cast_rays.

        Returns:
            dict of ray_splits (rays + 1,) uint32 (ray i's hits are ray_splits[i] to
            ray_splits[i + 1]), ray_ids, geometry_ids, primitive_ids (hits,) uint32,
            primitive_uvs (hits, 2) float32 and t_hit (hits,) float32.
        """
        rays, masks = _ray_arguments(rays, nthreads, masks)
        return self._engine.list_intersections(rays, nthreads, masks)

    # --- Point queries --------------------------------------------------------------
    def compute_closest_points(self, query_points, nthreads=0):
        """The nearest surface point to each query point.

        Returns:
            dict of points (..., 3) float32 (inf where the scene is empty), geometry_ids,
            primitive_ids (...) uint32, primitive_uvs (..., 2) and primitive_normals
            (..., 3) float32.
        """
        _check_threads("nthreads", nthreads)
        return self._engine.compute_closest_points(as_array(query_points, "query_points"), nthreads)

    def compute_distance(self, query_points, nthreads=0):
        """Distance from each point to the nearest surface: (...) float32."""
        _check_threads("nthreads", nthreads)
        return self._engine.compute_distance(as_array(query_points, "query_points"), nthreads)

    def compute_signed_distance(self, query_points, nthreads=0, nsamples=1):
        """Distance to the surface, negative inside: (...) float32.

        Inside and outside are decided by the parity of the crossings of one ray, which
        the watertight test makes exact: a ray through a shared edge or vertex crosses
        once. Open3D votes over `nsamples` jittered rays because its test can miss or
        double-count there; the argument is accepted (odd, >= 1, as Open3D asks) and
        changes nothing here.
        """
        _check_threads("nthreads", nthreads)
        _check_samples(nsamples)
        return self._engine.compute_signed_distance(as_array(query_points, "query_points"), nthreads, 1)

    def compute_occupancy(self, query_points, nthreads=0, nsamples=1):
        """1.0 for a point inside the closed surfaces, 0.0 outside: (...) float32. One
        ray's crossing parity, exact (see compute_signed_distance for `nsamples`)."""
        _check_threads("nthreads", nthreads)
        _check_samples(nsamples)
        return self._engine.compute_occupancy(as_array(query_points, "query_points"), nthreads, 1)

    # --- Cameras --------------------------------------------------------------------
    @staticmethod
    def create_rays_pinhole(*args, **kwargs):
        """Rays of a pinhole camera, one per pixel centre: (height_px, width_px, 6) float32.

        Two forms, as Open3D's:
            create_rays_pinhole(intrinsic_matrix, extrinsic_matrix, width_px, height_px)
                intrinsic_matrix: (3, 3) upper triangular K; extrinsic_matrix: (4, 4)
                world-to-camera [R | t].
            create_rays_pinhole(fov_deg, center, eye, up, width_px, height_px)
                fov_deg: horizontal field of view; center: the point looked at; eye: the
                camera position; up: the up direction.
        The origins are the camera centre; the directions are not normalized (unit depth
        along the optical axis, so t_hit is the depth).
        """
        if "fov_deg" in kwargs or len(args) + len(kwargs) == 6:
            return pinhole_rays_from_fov(*args, **kwargs)
        return pinhole_rays_from_matrices(*args, **kwargs)

    # --- Beyond Open3D ----------------------------------------------------------------
    def info(self):
        """Facts about the built structure: triangles, geometries, nodes, bytes, depth,
        SAH cost, build seconds, test, isa, quality, ..."""
        return self._engine.info()

    def save(self, path):
        """Writes the built structure to `path`; RaycastingScene.load maps it back."""
        return self._engine.save(str(path))

    @staticmethod
    def load(path):
        """A scene from a file that save wrote, ready to query (geometry arrays are not
        kept, so it cannot be pickled)."""
        scene = RaycastingScene.__new__(RaycastingScene)
        scene._engine = _volley.Engine.load(str(path))
        return scene

    def __getstate__(self):
        return {"engine": self._engine}

    def __setstate__(self, state):
        self._engine = state["engine"]

    def __repr__(self):
        return f"volley.RaycastingScene({self._engine.geometry_count()} geometries)"


def _vector3(value, name):
    v = np.asarray(as_array(value, name), dtype=np.float64).reshape(-1)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{name}: expected 3 finite numbers, got {value!r}")
    return v


def _pixels(value, name):
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not 1 <= value <= 65536:
        raise ValueError(f"{name}: expected a pixel count from 1 to 65536, got {value!r}")
    return int(value)


def pinhole_rays_from_matrices(intrinsic_matrix, extrinsic_matrix, width_px, height_px):
    """create_rays_pinhole's matrix form: (height_px, width_px, 6) float32 rays through
    the pixel centres (x + 0.5, y + 0.5) of intrinsic K and world-to-camera [R | t]: origin
    the camera centre -R^T t, direction R^T K^-1 (x + 0.5, y + 0.5, 1)."""
    k = np.asarray(as_array(intrinsic_matrix, "intrinsic_matrix"), dtype=np.float64)
    e = np.asarray(as_array(extrinsic_matrix, "extrinsic_matrix"), dtype=np.float64)
    if k.shape != (3, 3) or not np.all(np.isfinite(k)):
        raise ValueError(f"intrinsic_matrix: expected a finite (3, 3) matrix, got shape {k.shape}")
    if e.shape != (4, 4) or not np.all(np.isfinite(e)):
        raise ValueError(f"extrinsic_matrix: expected a finite (4, 4) matrix, got shape {e.shape}")
    width, height = _pixels(width_px, "width_px"), _pixels(height_px, "height_px")
    try:
        k_inverse = np.linalg.inv(k)
    except np.linalg.LinAlgError:
        raise ValueError("intrinsic_matrix: singular (a focal length of 0?)") from None
    rotation_t = e[:3, :3].T
    to_world = (rotation_t @ k_inverse).astype(np.float32)
    rays = np.empty((height, width, 6), np.float32)
    rays[..., :3] = (-rotation_t @ e[:3, 3]).astype(np.float32)
    x, y = np.meshgrid(np.arange(width, dtype=np.float32) + 0.5, np.arange(height, dtype=np.float32) + 0.5)
    pixels = np.stack([x, y, np.ones_like(x)], axis=-1)
    rays[..., 3:] = pixels @ to_world.T
    return rays


def pinhole_rays_from_fov(fov_deg, center, eye, up, width_px, height_px):
    """create_rays_pinhole's look-at form: a horizontal field of view fov_deg, the camera
    at `eye` looking at `center` with `up` up, the principal point in the image centre."""
    fov = float(fov_deg)
    if not 0 < fov < 180:
        raise ValueError(f"fov_deg: expected a field of view between 0 and 180 degrees, got {fov_deg!r}")
    width, height = _pixels(width_px, "width_px"), _pixels(height_px, "height_px")
    c, o, u = _vector3(center, "center"), _vector3(eye, "eye"), _vector3(up, "up")
    forward = c - o
    if np.linalg.norm(forward) == 0:
        raise ValueError("center: must differ from eye")
    focal = 0.5 * width / math.tan(math.radians(0.5 * fov))
    k = np.array([[focal, 0, 0.5 * width], [0, focal, 0.5 * height], [0, 0, 1]])
    z = forward / np.linalg.norm(forward)
    x = np.cross(u / np.linalg.norm(u), z)
    if np.linalg.norm(x) == 0:
        raise ValueError("up: must not be parallel to center - eye")
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    rotation = np.stack([x, y, z])
    extrinsic = np.eye(4)
    extrinsic[:3, :3], extrinsic[:3, 3] = rotation, -rotation @ o
    return pinhole_rays_from_matrices(k, extrinsic, width, height)
