"""The examples in examples/ run, on a small mesh, and write what they say."""
import importlib.util
import os
import subprocess
import sys

import pytest

SOURCE = os.environ.get("VOLLEY_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
EXAMPLES = os.path.join(SOURCE, "examples")
SPHERE = os.path.join(SOURCE, "scenes", "meshes", "sphere.obj")


def run(script, *args):
    out = subprocess.run([sys.executable, os.path.join(EXAMPLES, script), *args], capture_output=True, text=True,
                         env=dict(os.environ), timeout=300)
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_sdf_slice_writes_a_png(tmp_path):
    png = tmp_path / "sdf.png"
    text = run("sdf_slice.py", SPHERE, "-o", str(png), "--size", "64")
    assert png.read_bytes().startswith(b"\x89PNG")
    assert "cells inside" in text


def test_depth_image_writes_a_png(tmp_path):
    png = tmp_path / "depth.png"
    text = run("depth_image.py", SPHERE, "-o", str(png), "--width", "64", "--height", "48")
    assert png.read_bytes().startswith(b"\x89PNG")
    assert "hits" in text


@pytest.mark.skipif(importlib.util.find_spec("distributed") is None, reason="python3-distributed (Dask) not installed")
def test_batch_over_dask_workers():
    text = run("batch_dask.py", SPHERE, SPHERE, "--samples", "2000", "--workers", "1")
    assert text.count("volume") == 2
    assert "2 meshes" in text
