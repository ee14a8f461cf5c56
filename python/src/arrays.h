// NumPy arrays in and out of the binding: any float dtype and layout in (converted once to
// C-contiguous float32), shapes checked with errors that name the argument, answers as
// fresh arrays shaped like the caller's leading dimensions.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <string>
#include <vector>

namespace volley::python {

namespace py = pybind11;

/// C-contiguous float32, converted from any real dtype and layout (a copy only when needed).
using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
/// C-contiguous uint32 (indices).
using IndexArray = py::array_t<std::uint32_t, py::array::c_style | py::array::forcecast>;

/// Converts `obj` to float32 with last dimension `width`; ValueError naming `name` and
/// the expected shape otherwise. `leading` gets the other dimensions (the answer's shape).
FloatArray as_float_rows(const py::handle& obj, const char* name, py::ssize_t width, std::vector<py::ssize_t>& leading);

/// The same for an (M, 3) index array of integers, each below `limit`.
IndexArray as_triangles(const py::handle& obj, const char* name, std::size_t limit);

/// Memory for an answer array of `bytes` (>= kReusedBytes): a buffer a freed answer array
/// left, when one of that size is kept, else a fresh one. Freed with release_buffer.
void* take_buffer(std::size_t bytes);
/// Keeps a buffer take_buffer gave for the next answer of its size (a few are kept, up to
/// 256 MiB in all), or frees it.
void release_buffer(void* data);
/// Answers this large go through take_buffer: a program that asks the same query again
/// writes into pages it already has, instead of pages the kernel must zero and map first
/// (perf/reports/queries.md: a fifth of cast_rays' time on 1M rays).
inline constexpr std::size_t kReusedBytes = std::size_t{1} << 20;

/// Scratch memory for `count` objects of an implicit-lifetime type T (contents undefined):
/// from take_buffer when large, so that a repeated call reuses pages instead of faulting in
/// fresh ones, else from the heap.
template <class T>
class Scratch {
 public:
  explicit Scratch(std::size_t count) : bytes_(count * sizeof(T)) {
    if (bytes_ >= kReusedBytes) {
      data_ = static_cast<T*>(take_buffer(bytes_));
    } else {
      small_.resize(count);
      data_ = small_.data();
    }
  }
  ~Scratch() {
    if (bytes_ >= kReusedBytes) release_buffer(data_);
  }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
  T* data() { return data_; }

 private:
  std::size_t bytes_;
  T* data_ = nullptr;
  std::vector<T> small_;
};

/// A new array of `leading` + `tail` dimensions (contents undefined).
template <class T>
py::array_t<T> new_array(const std::vector<py::ssize_t>& leading, std::initializer_list<py::ssize_t> tail = {}) {
  std::vector<py::ssize_t> shape = leading;
  shape.insert(shape.end(), tail.begin(), tail.end());
  std::size_t bytes = sizeof(T);
  for (py::ssize_t d : shape) bytes *= static_cast<std::size_t>(d);
  if (bytes < kReusedBytes) return py::array_t<T>(shape);
  void* data = take_buffer(bytes);
  py::capsule owner(data, [](void* p) { release_buffer(p); });
  return py::array_t<T>(shape, static_cast<T*>(data), owner);
}

/// The number of rows that `leading` describes.
inline std::size_t rows_of(const std::vector<py::ssize_t>& leading) {
  std::size_t n = 1;
  for (py::ssize_t d : leading) n *= static_cast<std::size_t>(d);
  return n;
}

}  // namespace volley::python
