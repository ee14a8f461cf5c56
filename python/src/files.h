// volley's binary files (.vray, .vhit, .vpts, .vcnt, .vocc, .vdst, .vclp, .vall) from Python:
// the module's _read_* and _write_* functions (python/src/files.cpp, python/volley/files.py).
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

namespace volley::python {

namespace py = pybind11;

/// Adds _read_KIND(path) and _write_KIND(path, rows) for every file kind to the module.
void bind_files(py::module_& m);

}  // namespace volley::python
