"""A tiny PNG writer for the examples (8-bit grey or RGB from a NumPy array), so that they
need nothing beyond NumPy."""
import os
import struct
import zlib

import numpy as np


def write_png(path, image):
    """image: (H, W) or (H, W, 3) array of floats in [0, 1] or of uint8; the folder of
    `path` is created when missing."""
    a = np.asarray(image)
    if a.dtype != np.uint8:
        a = (np.clip(a, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
    h, w = a.shape[:2]
    color = 2 if a.ndim == 3 else 0
    raw = b"".join(b"\x00" + a[y].tobytes() for y in range(h))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, color, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 6)))
        f.write(chunk(b"IEND", b""))


def diverging(values, scale):
    """Blue (negative) to white (0) to red (positive) for signed distances."""
    v = np.clip(np.asarray(values) / scale, -1.0, 1.0)
    rgb = np.ones(v.shape + (3,))
    rgb[..., 0] = np.where(v < 0, 1 + v, 1)
    rgb[..., 1] = 1 - np.abs(v)
    rgb[..., 2] = np.where(v > 0, 1 - v, 1)
    return rgb
