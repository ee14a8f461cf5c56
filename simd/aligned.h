// 64-byte aligned heap storage for SoA blocks and packets (docs/style.md rule 4).
// Baseline code only: per-ISA files must not instantiate these (they are not tagged
// with an arch, see check_weak_symbols.sh).
#pragma once
#include <cstddef>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/large_alloc.h"  // declarations only

namespace volley::simd {

/// Cache-line (and AVX-512 register) alignment of every SoA buffer.
inline constexpr std::size_t kAlign = 64;

/// Whether arrays of T are read by every ray's walk (wide nodes, triangle blocks: the
/// specialisations beside those types): such arrays go on huge pages from
/// core::kWalkedAllocBytes, others from core::kLargeAllocBytes.
template <class T>
inline constexpr bool kWalkedByRays = false;

/// std::allocator that returns kAlign-aligned memory; large arrays on huge pages
/// (core::allocate_large; the threshold by kWalkedByRays).
template <class T>
struct AlignedAllocator {
  using value_type = T;
  static constexpr std::size_t kHugeFrom = kWalkedByRays<T> ? core::kWalkedAllocBytes : core::kLargeAllocBytes;
  AlignedAllocator() noexcept = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    return static_cast<T*>(core::allocate_large(n * sizeof(T), kAlign, kHugeFrom));
  }
  void deallocate(T* p, std::size_t n) noexcept { core::free_large(p, n * sizeof(T), kAlign, kHugeFrom); }
  /// resize() and the count constructor default-initialise: trivial elements (nodes, triangle
  /// blocks) are left to their writer, which fills them in parallel (a serial zero fill
  /// showed in build profiles: perf/reports/build.md); types with a
  /// constructor (BBox) still run it.
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <class U>
  bool operator==(const AlignedAllocator<U>&) const noexcept { return true; }
};

/// A std::vector whose data() is kAlign-aligned.
template <class T>
using AlignedVector = std::vector<T, AlignedAllocator<T>>;

}  // namespace volley::simd
