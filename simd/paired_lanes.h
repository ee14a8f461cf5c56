// Any hit of at most half a packet chunk's lanes, two triangles per register: the active
// rays are gathered into lane pairs (lanes 2s and 2s + 1 both hold the s-th active ray),
// and each register tests triangles j and j + 1 of a block, one in each lane of a pair.
// Half as many triangle tests as the one-triangle-per-register form when a leaf is
// reached by half a chunk's lanes or fewer. Every lane runs the same operations on the
// same ray and triangle as in that form, so the answers are the same bit for bit.
// Watertight test with one axis permutation for the packet (uniform) only; AVX-512 (8 pairs
// of 16 lanes) and AVX2 (4 pairs of 8).
#pragma once
#include <immintrin.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include "simd/watertight.h"

namespace volley::simd::detail {

/// Whether PacketKernels::occluded hands chunks of few lanes to occluded_pairs: AVX-512 and
/// AVX2, where it was measured (Avx512Ymm's packet kernels serve no walk).
template <class Arch, TriangleTest Test, int BW>
inline constexpr bool kPairedLanes = (kLanes<Arch> == 16 || std::is_same_v<Arch, Avx2>) &&
                                     Test == TriangleTest::watertight && BW % 2 == 0;

/// What differs between AVX-512 and AVX2: the s-th lane of `act` into lanes 2s and 2s + 1
/// (pick), a triangle pair's two floats into every pair of lanes (broadcast), and back from
/// the pairs' hits to the rays' lanes (to_rays).
template <class Arch>
struct PairLanes;

template <class Arch>
  requires(kLanes<Arch> == 16)
struct PairLanes<Arch> {
  __m512i from;
  explicit PairLanes(std::uint32_t act) {
    const __m512i rank = _mm512_maskz_compress_epi32(
        static_cast<__mmask16>(act), _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15));
    from = _mm512_permutexvar_epi32(_mm512_setr_epi32(0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7), rank);
  }
  FloatB<Arch> pick(FloatB<Arch> v) const { return FloatB<Arch>(_mm512_permutexvar_ps(from, v)); }
  static FloatB<Arch> broadcast(double two) { return FloatB<Arch>(_mm512_castpd_ps(_mm512_set1_pd(two))); }
  /// Bit 2s of `per_pair` (pair s blocked) to the s-th lane of `act`.
  static std::uint32_t to_rays(std::uint32_t per_pair, std::uint32_t act) {
    const __m512i pairs = _mm512_movm_epi32(static_cast<__mmask16>(per_pair));
    const __m512i per_ray = _mm512_maskz_compress_epi32(0x5555, pairs);
    return _mm512_movepi32_mask(_mm512_maskz_expand_epi32(static_cast<__mmask16>(act), per_ray)) & act;
  }
};

template <class Arch>
  requires(kLanes<Arch> == 8)
struct PairLanes<Arch> {
  __m256i from;
  explicit PairLanes(std::uint32_t act) {
    // At most four lanes: their indices written by hand (AVX2 has no compress).
    alignas(32) std::int32_t lanes[8] = {};
    int s = 0;
    for (std::uint32_t a = act; a != 0; a &= a - 1, ++s) lanes[2 * s] = lanes[2 * s + 1] = std::countr_zero(a);
    from = _mm256_load_si256(reinterpret_cast<const __m256i*>(lanes));
  }
  FloatB<Arch> pick(FloatB<Arch> v) const { return FloatB<Arch>(_mm256_permutevar8x32_ps(v, from)); }
  static FloatB<Arch> broadcast(double two) { return FloatB<Arch>(_mm256_castpd_ps(_mm256_set1_pd(two))); }
  static std::uint32_t to_rays(std::uint32_t per_pair, std::uint32_t act) {
    std::uint32_t out = 0;
    for (std::uint32_t a = act; a != 0; a &= a - 1, per_pair >>= 2)
      if (per_pair & 1u) out |= a & (0u - a);
    return out;
  }
};

/// The lanes of `act` (at most half the lanes) that some triangle of blocks[0 .. count) occludes,
/// the last block's first `last` triangles only. `upper` is tmax on the active lanes (-inf elsewhere) and
/// `sure` the sure-hit factors of that upper end, as PacketKernels::occluded holds them.
template <class Arch, int BW>
std::uint32_t occluded_pairs(const typename WatertightTest<Arch>::Rays& r, FloatB<Arch> upper,
                             const typename WatertightTest<Arch>::SureRange& sure, std::uint32_t act,
                             const WatertightBlock<BW>* blocks, std::uint32_t count, int last) {
  using T = WatertightTest<Arch>;
  using B = FloatB<Arch>;
  using M = MaskB<Arch>;
  const int n = std::popcount(act);
  // Lanes 2s and 2s + 1: the s-th active ray (lanes past 2n hold a copy of lane 0 and
  // an upper end of -inf, which fails every test).
  const PairLanes<Arch> lanes(act);
  typename T::Rays p = r;
  p.okx = lanes.pick(r.okx), p.oky = lanes.pick(r.oky), p.okz = lanes.pick(r.okz);
  p.sx = lanes.pick(r.sx), p.sy = lanes.pick(r.sy), p.sz = -lanes.pick(r.sz);  // negated: the pairs below
  p.tmin = lanes.pick(r.tmin), p.tmin_lo = lanes.pick(r.tmin_lo);
  const std::uint32_t live = (1u << (2 * n)) - 1u;
  const B up = xsimd::select(mask_from_bits<Arch>(live), lanes.pick(upper), B(-std::numeric_limits<float>::infinity()));
  const typename T::SureRange s{lanes.pick(sure.lo), lanes.pick(sure.hi)};
  // Triangles j and j + 1 (j even) in the two lanes of every pair: the two floats
  // broadcast as one double, which is a plain load (a float pair broadcast takes a
  // shuffle more), origin minus vertex as WatertightTest::broadcast_negated.
  const auto pair = [&p](const WatertightBlock<BW>& b, int j) {
    const auto at = [&b, j](int k, int axis) {
      double two;
      std::memcpy(&two, &b.p[k][axis][j], sizeof two);
      return PairLanes<Arch>::broadcast(two);
    };
    return typename T::Tris{p.okx - at(0, p.kx), p.oky - at(0, p.ky), p.okz - at(0, p.kz),
                            p.okx - at(1, p.kx), p.oky - at(1, p.ky), p.okz - at(1, p.kz),
                            p.okx - at(2, p.kx), p.oky - at(2, p.ky), p.okz - at(2, p.kz)};
  };
  // Bit 2s: either lane of pair s.
  const auto either = [](std::uint32_t h) { return (h | (h >> 1)) & 0x5555u; };
  const std::uint32_t rays_mask = live & 0x5555u;
  M hit(false);
  for (std::uint32_t b = 0; b < count; ++b) {
    const WatertightBlock<BW>& block = blocks[b];
    const int used = b + 1 == count ? last : BW;
    for (int j = 0; j < used; j += 2) {
      // The steps of PacketKernels::occluded's watertight form, on the pairs.
      const auto d = T::template depth<false>(p, pair(block, j));
      M cand = T::prefilter(p, d, up) & ~hit;
      if (j + 1 == used) cand = cand & mask_from_bits<Arch>(0x5555u);  // no triangle j + 1
      if (xsimd::none(cand)) continue;
      const M now = T::sure_hit(d, s) & cand;
      hit = hit | now;
      const M rest = cand & ~now;
      if (xsimd::any(rest)) hit = hit | T::confirm(p, {rest, d.ts, d.u, d.v, d.det}, d.ts / d.det, up);
    }
    if (either(bits_from_mask<Arch>(hit)) == rays_mask) break;
  }
  // A ray is occluded when either lane of its pair is: bit 2s of the pairs to bit s, then
  // to the ray's own lane.
  return PairLanes<Arch>::to_rays(either(bits_from_mask<Arch>(hit)), act);
}

}  // namespace volley::simd::detail
