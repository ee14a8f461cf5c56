"""volley's binary files as NumPy arrays: the rays `volley rays` writes, the answers
`volley trace -o` and `volley query -o` write, and the points `volley points` writes.

Reading goes through volley's own C++ readers, so a bad file gets the same checks and the
same message as on the command line (an OSError naming the file and the fault). Records
come back as structured arrays where a record has fields:

    .vray  read_rays       RAY_DTYPE: org (3,) f4, tmin f4, dir (3,) f4, tmax f4
    .vhit  read_hits       HIT_DTYPE: t, u, v f4; prim, geom, inst u4 (a miss: t inf, prim 2**32 - 1)
    .vpts  read_points     (N, 3) float32
    .vcnt  read_counts     (N,) uint32 crossings per ray
    .vocc  read_occupancy  (N,) bool, True inside
    .vdst  read_distances  (N,) float32
    .vclp  read_closest    CLOSEST_DTYPE: point (3,) f4, geometry u4, primitive u4
    .vall  read_hit_lists  dict of ray_splits (rays + 1,) uint64 and hits (HIT_DTYPE)

Each write_KIND(path, values) writes the same format (creating the folder). write_rays also
takes Open3D's (..., 6) rays (origin, direction: tmin 0, tmax inf) and (..., 8) rows.
"""
import os

import numpy as np

from . import _volley
from .raycasting_scene import as_array

RAY_DTYPE = np.dtype([("org", "<f4", (3,)), ("tmin", "<f4"), ("dir", "<f4", (3,)), ("tmax", "<f4")])
HIT_DTYPE = np.dtype([("t", "<f4"), ("u", "<f4"), ("v", "<f4"), ("prim", "<u4"), ("geom", "<u4"), ("inst", "<u4")])
CLOSEST_DTYPE = np.dtype([("point", "<f4", (3,)), ("geometry", "<u4"), ("primitive", "<u4")])


def _path(path):
    return os.fspath(path)


def _rows(values):
    """The bytes of contiguous records as (count, record size) uint8, for the C++ writers."""
    values = np.ascontiguousarray(values)
    return values.reshape(-1).view(np.uint8).reshape(values.size, values.dtype.itemsize)


def _structured(values, dtype, name):
    a = as_array(values, name)
    if a.dtype.names is None:
        raise ValueError(f"{name}: expected a structured array of {dtype.descr}, got dtype {a.dtype}")
    missing = [f for f in dtype.names if f not in a.dtype.names]
    if missing:
        raise ValueError(f"{name}: the records lack the field(s) {', '.join(missing)} (expected {list(dtype.names)})")
    out = np.empty(a.shape, dtype)
    for field in dtype.names:
        out[field] = a[field]
    return out.reshape(-1)


def _plain(values, dtype, name, width=None):
    a = as_array(values, name)
    if a.dtype.kind not in "fiub":
        raise ValueError(f"{name}: expected numbers, got dtype {a.dtype}")
    if width is not None and (a.ndim < 1 or a.shape[-1] != width):
        raise ValueError(f"{name}: expected shape (..., {width}), got {a.shape}")
    return np.ascontiguousarray(a, dtype).reshape(-1)


def read_rays(path):
    """A .vray file as RAY_DTYPE records."""
    return _volley._read_rays(_path(path)).view(RAY_DTYPE).reshape(-1)


def write_rays(path, rays):
    """Writes rays as a .vray file: RAY_DTYPE records, (..., 8) rows (org, tmin, dir, tmax)
    or Open3D's (..., 6) rays (origin, direction; tmin 0, tmax inf)."""
    a = as_array(rays, "rays")
    if a.dtype.names is not None:
        records = _structured(a, RAY_DTYPE, "rays")
    elif a.ndim >= 1 and a.shape[-1] == 6:
        six = _plain(a, np.float32, "rays", 6).reshape(-1, 6)
        records = np.empty(len(six), RAY_DTYPE)
        records["org"], records["dir"] = six[:, :3], six[:, 3:]
        records["tmin"], records["tmax"] = 0.0, np.inf
    else:
        records = _plain(a, np.float32, "rays", 8).reshape(-1, 8).view(RAY_DTYPE).reshape(-1)
    _volley._write_rays(_path(path), _rows(records))


def read_hits(path):
    """A .vhit file as HIT_DTYPE records (version 1 files read as geometry 0)."""
    return _volley._read_hits(_path(path)).view(HIT_DTYPE).reshape(-1)


def write_hits(path, hits):
    """Writes HIT_DTYPE records as a .vhit file."""
    _volley._write_hits(_path(path), _rows(_structured(hits, HIT_DTYPE, "hits")))


def read_points(path):
    """A .vpts file as (N, 3) float32."""
    return _volley._read_points(_path(path)).view(np.float32).reshape(-1, 3)


def write_points(path, points):
    """Writes (..., 3) points as a .vpts file."""
    _volley._write_points(_path(path), _rows(_plain(points, np.float32, "points", 3)))


def read_counts(path):
    """A .vcnt file: (N,) uint32, the crossings of each ray."""
    return _volley._read_counts(_path(path)).view(np.uint32).reshape(-1)


def write_counts(path, counts):
    """Writes crossing counts (non-negative integers) as a .vcnt file."""
    a = as_array(counts, "counts")
    if a.dtype.kind not in "iu" or (a.size and a.min() < 0):
        raise ValueError("counts: expected non-negative integers")
    _volley._write_counts(_path(path), _rows(_plain(a, np.uint32, "counts")))


def read_occupancy(path):
    """A .vocc file: (N,) bool, True for a point inside."""
    return _volley._read_occupancy(_path(path)).reshape(-1).astype(bool)


def write_occupancy(path, inside):
    """Writes inside/outside answers (bools, or 0 and 1) as a .vocc file."""
    a = as_array(inside, "inside")
    if a.dtype.kind not in "biuf" or not np.isin(a, (0, 1)).all():
        raise ValueError("inside: expected booleans (or 0 and 1)")
    _volley._write_occupancy(_path(path), _rows(np.ascontiguousarray(a, np.uint8).reshape(-1)))


def read_distances(path):
    """A .vdst file: (N,) float32 (signed or not, as written)."""
    return _volley._read_distances(_path(path)).view(np.float32).reshape(-1)


def write_distances(path, distances):
    """Writes distances as a .vdst file."""
    _volley._write_distances(_path(path), _rows(_plain(distances, np.float32, "distances")))


def read_closest(path):
    """A .vclp file as CLOSEST_DTYPE records (nothing found: point inf, ids 2**32 - 1)."""
    return _volley._read_closest(_path(path)).view(CLOSEST_DTYPE).reshape(-1)


def write_closest(path, closest):
    """Writes CLOSEST_DTYPE records as a .vclp file."""
    _volley._write_closest(_path(path), _rows(_structured(closest, CLOSEST_DTYPE, "closest")))


def read_hit_lists(path):
    """A .vall file: dict of ray_splits (rays + 1,) uint64 (ray i's hits are
    hits[ray_splits[i]:ray_splits[i + 1]]) and hits (HIT_DTYPE), nearest first per ray."""
    offsets, rows = _volley._read_hit_lists(_path(path))
    return {"ray_splits": offsets, "hits": rows.view(HIT_DTYPE).reshape(-1)}


def write_hit_lists(path, ray_splits, hits):
    """Writes every hit of every ray as a .vall file: ray_splits from 0, never decreasing,
    ending at len(hits)."""
    splits = np.ascontiguousarray(as_array(ray_splits, "ray_splits"))
    if splits.ndim != 1 or splits.size < 1 or splits.dtype.kind not in "iu":
        raise ValueError("ray_splits: expected a 1-d integer array of rays + 1 offsets")
    records = _structured(hits, HIT_DTYPE, "hits")
    if splits[0] != 0 or splits[-1] != len(records) or (np.diff(splits.astype(np.int64)) < 0).any():
        raise ValueError(f"ray_splits: expected offsets from 0 to len(hits) = {len(records)}, never decreasing")
    _volley._write_hit_lists(_path(path), splits.astype(np.uint64), _rows(records))
