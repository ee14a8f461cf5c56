"""Builds the _volley extension with the project's CMake build (pip install --no-build-isolation .).

The extension is the CMake target _volley (python/CMakeLists.txt); this script configures
a Release build in build/pip (or reuses the tree named by VOLLEY_BUILD_DIR, e.g.
build/release after `make build`), builds that target only, and puts the module beside
python/volley/*.py in the wheel.
"""
import glob
import os
import shutil
import subprocess

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = os.path.dirname(os.path.abspath(__file__))


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = os.environ.get("VOLLEY_BUILD_DIR") or os.path.join(ROOT, "build", "pip")
        if not os.path.exists(os.path.join(build, "CMakeCache.txt")):
            subprocess.run(["cmake", "-S", ROOT, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DVOLLEY_BUILD_TESTS=OFF",
                            "-DVOLLEY_BUILD_BENCH=OFF", "-DVOLLEY_WITH_EMBREE=OFF", "-DVOLLEY_PYTHON=ON"], check=True)
        subprocess.run(["cmake", "--build", build, "--target", "_volley", "-j", str(os.cpu_count() or 1)], check=True)
        built = glob.glob(os.path.join(build, "python", "volley", "_volley*.so"))
        if not built:
            raise RuntimeError(f"{build}: the _volley module was not built (pybind11-dev and python3-dev installed?)")
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(built[0], target)


os.makedirs(os.path.join(ROOT, "build"), exist_ok=True)
setup(
    options={"egg_info": {"egg_base": "build"}},  # the metadata beside the other build outputs
    packages=["volley"],
    package_dir={"volley": "python/volley"},
    package_data={"volley": ["py.typed", "*.pyi"]},  # the type stub (PEP 561)
    ext_modules=[Extension("volley._volley", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
)
