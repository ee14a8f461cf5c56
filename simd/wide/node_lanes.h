// Eight float lanes, one per child of a WideNode<8>, on every ISA: the node tests of the
// walks (single_walk.h, frustum_walk.h) are written once against this shim.
#pragma once
#include <immintrin.h>

#include <bit>
#include <cstdint>

#include "simd/wide/kernels.h"

namespace volley::simd {

namespace detail {

/// The children a node test found entered: bit j of `bits` for child j, and the first one's
/// reference (0 when none). With mask registers (AVX-512) the entered lanes stay in one and
/// the node's references in a vector, so the first reference is one vpcompressd: the next
/// node's address does not wait for movemask, bit scan and a load indexed by it, the
/// longest chain of the walk (perf/reports/traversal.md).
template <class Arch, bool Masks = kHasMaskRegisters<Arch>>
struct ChildHits {
  std::uint32_t bits;
  std::uint32_t first_ref;
};
template <class Arch>
struct ChildHits<Arch, true> {
  std::uint32_t bits;
  std::uint32_t first_ref;
  __mmask8 k;
  __m256i refs;
};

/// The hits of entered children `bits` without mask registers: the first reference read
/// at the first bit.
template <class Arch>
[[gnu::always_inline]] inline ChildHits<Arch> child_hits(std::uint32_t bits, const std::uint32_t* child) {
  ChildHits<Arch> hits{bits, 0};
  if (bits) hits.first_ref = child[std::countr_zero(bits)];
  return hits;
}

/// Eight float lanes, one per child of a WideNode<8>: one AVX register (AVX2 and AVX-512,
/// whose 16 lanes would be half empty), or two SSE registers. Raw intrinsics (always
/// inlined, no symbols) inside members of a class templated on Arch.
template <class Arch, bool Avx = (kLanes<Arch> >= 8)>
struct Lanes8;

template <class Arch>
struct Lanes8<Arch, true> {
  using V = __m256;
  static V load(const float* p) { return _mm256_load_ps(p); }
  static V set1(float x) { return _mm256_set1_ps(x); }
  /// Lane L of v in every lane, from the register (no store and reload).
  template <int L>
  static V lane(__m128 v) {
    return _mm256_broadcastss_ps(L == 0 ? v : _mm_shuffle_ps(v, v, L * 0x55));
  }
  static V sub(V a, V b) { return _mm256_sub_ps(a, b); }
  static V add(V a, V b) { return _mm256_add_ps(a, b); }
  static V mul(V a, V b) { return _mm256_mul_ps(a, b); }
  /// The ISA has FMA (AVX2 + FMA, AVX-512): slab distances in one rounding (walk).
  static constexpr bool kFma = true;
  /// a b - c, rounded once.
  static V fmsub(V a, V b, V c) { return _mm256_fmsub_ps(a, b, c); }
  /// maxps(a, b): b when either is NaN.
  static V max(V a, V b) { return _mm256_max_ps(a, b); }
  /// minps(a, b): b when either is NaN.
  static V min(V a, V b) { return _mm256_min_ps(a, b); }
  /// Bit i set when a[i] <= b[i] (false for NaN).
  static std::uint32_t le(V a, V b) {
    return static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_cmp_ps(a, b, _CMP_LE_OQ)));
  }
  static void store(float* p, V a) { _mm256_store_ps(p, a); }
  /// The children with entry <= exit (false for NaN); `child`: the node's references.
  static ChildHits<Arch> entered(V entry, V exit, const std::uint32_t* child) {
    if constexpr (kHasMaskRegisters<Arch>) {
      const __mmask8 k = _mm256_cmp_ps_mask(entry, exit, _CMP_LE_OQ);
      const __m256i refs = _mm256_load_si256(reinterpret_cast<const __m256i*>(child));
      const auto first = static_cast<std::uint32_t>(
          _mm_cvtsi128_si32(_mm256_castsi256_si128(_mm256_maskz_compress_epi32(k, refs))));
      return {k, first, k, refs};
    } else {
      return child_hits<Arch>(le(entry, exit), child);
    }
  }
  /// Mask registers: the second entered child's reference, and the first two entered
  /// children's entry distances, compressed from registers (not reloaded from memory).
  static void second_and_distances(const ChildHits<Arch>& hits, V entry, std::uint32_t& second, float& d0,
                                   float& d1) {
    static_assert(kHasMaskRegisters<Arch>);
    const __m128 d = _mm256_castps256_ps128(_mm256_maskz_compress_ps(hits.k, entry));
    second = static_cast<std::uint32_t>(
        _mm_extract_epi32(_mm256_castsi256_si128(_mm256_maskz_compress_epi32(hits.k, hits.refs)), 1));
    d0 = _mm_cvtss_f32(d);
    d1 = _mm_cvtss_f32(_mm_movehdup_ps(d));
  }
};

template <class Arch>
struct Lanes8<Arch, false> {
  struct V {
    __m128 a, b;
  };
  static V load(const float* p) { return {_mm_load_ps(p), _mm_load_ps(p + 4)}; }
  static V set1(float x) { return {_mm_set1_ps(x), _mm_set1_ps(x)}; }
  template <int L>
  static V lane(__m128 v) {
    const __m128 b = _mm_shuffle_ps(v, v, L * 0x55);
    return {b, b};
  }
  static V sub(V x, V y) { return {_mm_sub_ps(x.a, y.a), _mm_sub_ps(x.b, y.b)}; }
  static V add(V x, V y) { return {_mm_add_ps(x.a, y.a), _mm_add_ps(x.b, y.b)}; }
  static V mul(V x, V y) { return {_mm_mul_ps(x.a, y.a), _mm_mul_ps(x.b, y.b)}; }
  static constexpr bool kFma = false;
  static V max(V x, V y) { return {_mm_max_ps(x.a, y.a), _mm_max_ps(x.b, y.b)}; }
  static V min(V x, V y) { return {_mm_min_ps(x.a, y.a), _mm_min_ps(x.b, y.b)}; }
  static std::uint32_t le(V x, V y) {
    return static_cast<std::uint32_t>(_mm_movemask_ps(_mm_cmple_ps(x.a, y.a)) |
                                      (_mm_movemask_ps(_mm_cmple_ps(x.b, y.b)) << 4));
  }
  static void store(float* p, V x) {
    _mm_store_ps(p, x.a);
    _mm_store_ps(p + 4, x.b);
  }
  static ChildHits<Arch> entered(V entry, V exit, const std::uint32_t* child) {
    return child_hits<Arch>(le(entry, exit), child);
  }
};

}  // namespace detail

}  // namespace volley::simd
