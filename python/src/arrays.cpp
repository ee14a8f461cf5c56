#include "arrays.h"

#include <cmath>
#include <cstdlib>
#include <mutex>
#include <new>
#include <stdexcept>

namespace volley::python {

namespace {

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

/// The buffers freed answer arrays left, by size. Never destroyed: an array may be freed
/// after the module's statics are gone.
struct BufferCache {
  static constexpr std::size_t kMaxBuffers = 8;
  static constexpr std::size_t kMaxBytes = std::size_t{256} << 20;
  std::mutex mutex;
  std::vector<void*> kept;
  std::size_t bytes = 0;
};
BufferCache& cache() {
  static BufferCache* c = new BufferCache;
  return *c;
}

/// Each buffer starts with a 64-byte header that holds its size; the data follows.
constexpr std::size_t kHeader = 64;
std::size_t size_of(void* block) { return *static_cast<std::size_t*>(block); }

}  // namespace

void* take_buffer(std::size_t bytes) {
  BufferCache& c = cache();
  {
    const std::lock_guard<std::mutex> lock(c.mutex);
    for (std::size_t i = 0; i < c.kept.size(); ++i) {
      if (size_of(c.kept[i]) != bytes) continue;
      void* block = c.kept[i];
      c.kept.erase(c.kept.begin() + static_cast<std::ptrdiff_t>(i));
      c.bytes -= bytes;
      return static_cast<char*>(block) + kHeader;
    }
  }
  void* block = std::aligned_alloc(64, (kHeader + bytes + 63) / 64 * 64);
  if (!block) throw std::bad_alloc();
  *static_cast<std::size_t*>(block) = bytes;
  return static_cast<char*>(block) + kHeader;
}

void release_buffer(void* data) {
  void* block = static_cast<char*>(data) - kHeader;
  const std::size_t bytes = size_of(block);
  BufferCache& c = cache();
  {
    const std::lock_guard<std::mutex> lock(c.mutex);
    if (c.kept.size() < BufferCache::kMaxBuffers && c.bytes + bytes <= BufferCache::kMaxBytes) {
      c.kept.push_back(block);
      c.bytes += bytes;
      return;
    }
  }
  std::free(block);
}

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
