// Storage for the large arrays of a build (items, boxes, nodes, triangle blocks) on
// transparent huge pages. A build of a million triangles touches about 150 MB of fresh
// memory; faulted in 4 KiB pages that cost a fifth of a one-thread build (about 1.8 us in
// the kernel per page here), in 2 MiB pages almost nothing. Embree maps its large arrays
// the same way.
#pragma once
#include <cstddef>
#include <cstdint>
#include <new>
#include <type_traits>

namespace volley::core {

/// Arrays this large or larger are mapped in whole 2 MiB pages.
inline constexpr std::size_t kLargeAllocBytes = std::size_t{4} << 20;
/// The same for the arrays every ray's walk reads (wide nodes, triangle blocks): their
/// TLB reach pays from 1 MiB on, while the build's scratch arrays of that size are faster
/// reused from the heap when a scene is rebuilt (perf/reports/rays.md, "deferred hand-offs on trees past the caches").
inline constexpr std::size_t kWalkedAllocBytes = std::size_t{1} << 20;

/// `bytes` of storage aligned to `align` (a power of two, at most 4096): operator new below
/// `huge_from`; from there on, an anonymous mapping aligned to 2 MiB with MADV_HUGEPAGE (the
/// kernel still decides; its pages come zeroed). Throws std::bad_alloc.
void* allocate_large(std::size_t bytes, std::size_t align, std::size_t huge_from = kLargeAllocBytes);

/// Frees storage from allocate_large, given the same bytes, align and huge_from.
void free_large(void* p, std::size_t bytes, std::size_t align, std::size_t huge_from = kLargeAllocBytes) noexcept;

/// A fixed number of trivial T on allocate_large storage, left uninitialised (a build's
/// scratch tables, written before they are read).
template <class T>
class LargeArray {
  static_assert(std::is_trivially_default_constructible_v<T> && std::is_trivially_destructible_v<T>);

 public:
  explicit LargeArray(std::size_t n) : n_(n), data_(static_cast<T*>(allocate_large(bytes(n), alignof(T)))) {}
  ~LargeArray() { free_large(data_, bytes(n_), alignof(T)); }
  LargeArray(const LargeArray&) = delete;
  LargeArray& operator=(const LargeArray&) = delete;

  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  T* get() { return data_; }
  const T* get() const { return data_; }
  std::size_t size() const { return n_; }

 private:
  static std::size_t bytes(std::size_t n) {
    if (n > SIZE_MAX / sizeof(T)) throw std::bad_alloc();
    return n * sizeof(T);
  }
  std::size_t n_;
  T* data_;
};

}  // namespace volley::core
