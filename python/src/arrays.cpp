#include "arrays.h"

#include <cmath>
#include <stdexcept>

namespace volley::python {

namespace {

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

}  // namespace

FloatArray as_float_rows(const py::handle& obj, const char* name, py::ssize_t width, std::vector<py::ssize_t>& leading) {
  const py::array raw = py::array::ensure(obj);
  if (!raw) throw py::value_error(std::string(name) + ": expected an array of shape (..., " + std::to_string(width) + ")");
  if (raw.dtype().kind() != 'f' && raw.dtype().kind() != 'i' && raw.dtype().kind() != 'u')
    throw py::value_error(std::string(name) + ": expected real numbers, got dtype " + std::string(py::str(raw.dtype())));
  if (raw.ndim() < 1 || raw.shape(raw.ndim() - 1) != width)
    throw py::value_error(std::string(name) + ": expected shape (..., " + std::to_string(width) + "), got " + shape_text(raw));
  FloatArray a = FloatArray::ensure(raw);
  leading.assign(a.shape(), a.shape() + a.ndim() - 1);
  return a;
}

IndexArray as_triangles(const py::handle& obj, const char* name, std::size_t limit) {
  const py::array raw = py::array::ensure(obj);
  if (!raw || raw.ndim() != 2 || raw.shape(1) != 3)
    throw py::value_error(std::string(name) + ": expected shape (M, 3)" + (raw ? ", got " + shape_text(raw) : std::string()));
  if (raw.dtype().kind() != 'i' && raw.dtype().kind() != 'u')
    throw py::value_error(std::string(name) + ": expected integer vertex indices, got dtype " +
                          std::string(py::str(raw.dtype())));
  // Negative or too large indices, checked before the conversion wraps them.
  const py::array_t<long long, py::array::c_style | py::array::forcecast> wide = raw;
  const long long* p = wide.data();
  for (py::ssize_t i = 0; i < wide.size(); ++i)
    if (p[i] < 0 || static_cast<unsigned long long>(p[i]) >= limit)
      throw py::value_error(std::string(name) + ": index " + std::to_string(p[i]) + " at row " + std::to_string(i / 3) +
                            " is out of range (the vertices have " + std::to_string(limit) + " rows)");
  return IndexArray::ensure(raw);
}

}  // namespace volley::python
