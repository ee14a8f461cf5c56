// The walks' stacks: entries of the single-ray and frustum walks, the stable near-to-far
// sort of a few entries in registers, lane reductions, and the stack's bound.
#pragma once
#include <immintrin.h>

#include <bit>
#include <cstdint>

#include "simd/wide/kernels.h"

namespace volley::simd {

namespace detail {

/// A stack entry of single-ray traversal: a subtree and the ray's entry distance into it.
template <class Arch>
struct WideStackItem {
  std::uint32_t ref;
  float entry;
};
static_assert(sizeof(WideStackItem<xsimd::avx2>) == 8 && offsetof(WideStackItem<xsimd::avx2>, entry) == 4,
              "stack_word packs an item as one little-endian 64-bit word");

/// A stack entry of the frustum walk: a subtree, the packet's lower bound of the entry
/// distances into it, the lanes that may enter it (leaves: those whose own box test
/// passed at the push), and where its box is (slot `slot` of node `parent`), for the lanes'
/// test again when it is popped.
template <class Arch>
struct FrustumItem {
  std::uint32_t ref;
  float entry;
  std::uint32_t lanes;
  std::uint32_t parent;
  std::uint32_t slot;
};

/// Smallest lane of v (no lane NaN).
template <class Arch>
float reduce_min(FloatB<Arch> v) {
  __m128 m;
  if constexpr (kLanes<Arch> == 16) {
    const __m256 h = _mm256_min_ps(_mm512_castps512_ps256(v), _mm512_extractf32x8_ps(v, 1));
    m = _mm_min_ps(_mm256_castps256_ps128(h), _mm256_extractf128_ps(h, 1));
  } else if constexpr (kLanes<Arch> == 8) {
    m = _mm_min_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  } else {
    m = v;
  }
  m = _mm_min_ps(m, _mm_movehl_ps(m, m));
  m = _mm_min_ss(m, _mm_shuffle_ps(m, m, 1));
  return _mm_cvtss_f32(m);
}

/// Largest lane of v (no lane NaN).
template <class Arch>
float reduce_max(FloatB<Arch> v) {
  __m128 m;
  if constexpr (kLanes<Arch> == 16) {
    const __m256 h = _mm256_max_ps(_mm512_castps512_ps256(v), _mm512_extractf32x8_ps(v, 1));
    m = _mm_max_ps(_mm256_castps256_ps128(h), _mm256_extractf128_ps(h, 1));
  } else if constexpr (kLanes<Arch> == 8) {
    m = _mm_max_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  } else {
    m = v;
  }
  m = _mm_max_ps(m, _mm_movehl_ps(m, m));
  m = _mm_max_ss(m, _mm_shuffle_ps(m, m, 1));
  return _mm_cvtss_f32(m);
}

/// A stack item (WideStackItem: ref, then entry) as one 64-bit word: ref in the low half,
/// the entry's bits in the high.
[[gnu::always_inline]] inline std::uint64_t stack_word(std::uint32_t ref, float entry) {
  return (std::uint64_t{std::bit_cast<std::uint32_t>(entry)} << 32) | ref;
}

/// Sorts stack words far to near, stably (odd-even transposition: compare-exchanges of
/// neighbours, swapping only when strictly out of order, as the insertion sort): w[0] is
/// the farthest.
template <int Count>
[[gnu::always_inline]] inline void sort_far_first(std::uint64_t* w) {
  auto entry = [](std::uint64_t x) { return std::bit_cast<float>(static_cast<std::uint32_t>(x >> 32)); };
  for (int round = 0; round < Count; ++round) {
    for (int k = round & 1; k + 1 < Count; k += 2) {
      const bool swap = entry(w[k]) < entry(w[k + 1]);
      const std::uint64_t a = swap ? w[k + 1] : w[k], b = swap ? w[k] : w[k + 1];
      w[k] = a, w[k + 1] = b;
    }
  }
}

/// Pushes `item` into the run stack[base .. size), which is kept sorted far to near (the
/// nearest on top, popped first).
template <class Item>
[[gnu::always_inline]] inline void insert_far_to_near(Item* stack, int& size, int base, const Item& item) {
  int k = size++;
  for (; k > base && stack[k - 1].entry < item.entry; --k) stack[k] = stack[k - 1];
  stack[k] = item;
}

/// Pops the next entry into `top`; where Prune, skips those whose entry distance is past
/// `bound` (a hit nearer than their boxes has ruled them out; `bound` is the upper end padded
/// as the exit distances, since the entries were computed with rounding). False when the
/// stack is empty.
template <bool Prune, class Item>
[[gnu::always_inline]] inline bool pop_within(const Item* stack, int& size, float bound, Item& top) {
  for (;;) {
    if (size == 0) return false;
    --size;
    if (!Prune || stack[size].entry <= bound) break;
  }
  top = stack[size];
  return true;
}

/// Entries a traversal stack needs: every wide level pushes at most N - 1 entries more
/// than it pops, and a wide BVH is no deeper than its binary BVH (< kBvhMaxDepth).
inline constexpr int kWideStack = (kWideN - 1) * core::kBvhMaxDepth + 1;

}  // namespace detail

}  // namespace volley::simd
