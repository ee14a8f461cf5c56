// The watertight test's closest-hit block test for the AVX-512 single-ray walk (Avx512Ymm:
// 8-wide blocks in ymm registers), in AVX-512VL mask registers: the xsimd AVX2 code it
// stands for compares with VEX instructions on ymm0-15 into vector masks. The same
// operations in the same order, so the same lanes and values. Included by watertight.h.
#pragma once
#include <immintrin.h>

#include <cstdint>
#include <limits>
#include <type_traits>

#include "simd/triangle/watertight.h"

namespace volley::simd::detail {

/// BlockTest for the walk's leaves (EarlyExit = false) of the watertight test on Avx512Ymm,
/// with or without the crossing rule (which only the fallback's lanes differ by).
template <class Arch, bool Crossing>
  requires std::is_same_v<Arch, Avx512Ymm>
struct BlockTest<Arch, WatertightTest<Arch, Crossing>, false> {
  using T = WatertightTest<Arch, Crossing>;
  using B = typename T::B;

  [[gnu::always_inline]] inline static void run(const typename T::Rays& r, const typename T::Block& block, B upper,
                                                typename T::Cand& cand, std::uint32_t& bits) {
    const auto tri = T::load_block(block, r);
    if (!masked(r, tri, upper, cand, bits)) [[unlikely]] {
      // A lane with an edge function exactly 0: the generic test, which redoes it in double.
      cand = T::template test<false>(r, tri, upper);
      bits = bits_from_mask<Arch>(cand.valid);
    }
  }

 private:
  /// T::test<false>() in mask registers. Returns false, computing nothing, when some lane
  /// has an edge function exactly 0.
  [[gnu::always_inline]] inline static bool masked(const typename T::Rays& r, const typename T::Tris& tri, B upper,
                                                   typename T::Cand& out, std::uint32_t& bits) {
    static_assert(T::W == 8 && T::kFused, "the AVX-512 8-lane leaf of the single-ray walk");
    typename T::Sheared s;
    const typename T::Edges e = T::edge_functions(r, tri, s);
    const __m256 eu = e.u, ev = e.v, ew = e.w, zero = _mm256_setzero_ps();
    constexpr int kNeqUnordered = 0x04, kLe = 0x12, kGe = 0x1d;
    // all_nonzero(), same_sign_bit() and test()'s and_cmp chain, in mask registers.
    __mmask8 nz = _mm256_cmp_ps_mask(eu, zero, kNeqUnordered);
    nz = _mm256_mask_cmp_ps_mask(nz, ev, zero, kNeqUnordered);
    nz = _mm256_mask_cmp_ps_mask(nz, ew, zero, kNeqUnordered);
    if (nz != 0xff) [[unlikely]]
      return false;
    const __m256i signs = _mm256_castps_si256(_mm256_or_ps(_mm256_xor_ps(eu, ev), _mm256_xor_ps(eu, ew)));
    const __mmask8 inside = _mm256_cmpgt_epi32_mask(signs, _mm256_set1_epi32(-1));
    const B det = e.u + e.v + e.w;
    const B ad = xsimd::abs(det);
    __mmask8 valid = _mm256_mask_cmp_ps_mask(inside, ad, _mm256_set1_ps(std::numeric_limits<float>::max()), kLe);
    const B ts = T::depth_sum(e, r.sz * tri.akz, r.sz * tri.bkz, r.sz * tri.ckz);
    const B ts_s = ts ^ (det & B(-0.0f));
    valid = _mm256_mask_cmp_ps_mask(valid, ts_s, r.tmin_lo * ad, kGe);
    valid = _mm256_mask_cmp_ps_mask(valid, ts_s, upper * ad, kLe);
    bits = valid;
    out.t = ts, out.u = e.v, out.v = e.w, out.den = det;
    return true;
  }
};

}  // namespace volley::simd::detail
