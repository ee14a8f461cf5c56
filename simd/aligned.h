// 64-byte aligned heap storage for SoA blocks and packets (STYLE rule 4).
// Baseline code only: per-ISA files must not instantiate these (they are not tagged
// with an arch, see check_weak_symbols.sh).
#pragma once
#include <cstddef>
#include <new>
#include <vector>

namespace volley::simd {

/// Cache-line (and AVX-512 register) alignment of every SoA buffer.
inline constexpr std::size_t kAlign = 64;

/// std::allocator that returns kAlign-aligned memory (operator new with align_val_t).
template <class T>
struct AlignedAllocator {
  using value_type = T;
  AlignedAllocator() noexcept = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    return static_cast<T*>(::operator new(n * sizeof(T), std::align_val_t(kAlign)));
  }
  void deallocate(T* p, std::size_t) noexcept { ::operator delete(p, std::align_val_t(kAlign)); }
  template <class U>
  bool operator==(const AlignedAllocator<U>&) const noexcept { return true; }
};

/// A std::vector whose data() is kAlign-aligned.
template <class T>
using AlignedVector = std::vector<T, AlignedAllocator<T>>;

}  // namespace volley::simd
