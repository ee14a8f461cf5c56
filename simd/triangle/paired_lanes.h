// Any hit of at most half a packet chunk's lanes, several triangles per register: the
// active rays are gathered into groups of G lanes (lanes G s to G s + G - 1 all hold the
// s-th active ray), and each register tests triangles j to j + G - 1 of a block, one in
// each lane of a group. G = 2 (pairs) for up to half a chunk's lanes; on AVX2 also G = 4
// for up to two lanes and G = 8 (a whole register, the single-ray form) for one. 1 / G as
// many triangle tests as the one-triangle-per-register form. Every lane runs the same
// operations on the same ray and triangle as in that form, so the answers are the same bit
// for bit. Watertight test with one axis permutation for the chunk (uniform) only;
// AVX-512 (pairs: 8 of 16 lanes) and AVX2 (pairs, quads and the whole register).
#pragma once
#include <immintrin.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>

#include "simd/triangle/watertight.h"

namespace volley::simd::detail {

/// Whether PacketKernels::occluded hands chunks of few lanes to occluded_groups: AVX-512 and
/// AVX2, where it was measured (Avx512Ymm's packet kernels serve no walk).
template <class Arch, TriangleTest Test, int BW>
inline constexpr bool kPairedLanes = (kLanes<Arch> == 16 || std::is_same_v<Arch, Avx2>) &&
                                     Test == TriangleTest::watertight && BW % 2 == 0;

/// What differs between AVX-512 and AVX2: the s-th lane of `act` into lanes G s to G s +
/// G - 1 (pick), G floats of a triangle group into every group of lanes (broadcast), and
/// back from the groups' hits to the rays' lanes (to_rays).
template <class Arch, int G>
struct GroupLanes;

template <class Arch, int G>
  requires(kLanes<Arch> == 16 && G == 2)
struct GroupLanes<Arch, G> {
  __m512i from;
  explicit GroupLanes(std::uint32_t act) {
    const __m512i rank = _mm512_maskz_compress_epi32(
        static_cast<__mmask16>(act), _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15));
    // (maskz with every lane: GCC 12's header makes the unmasked forms warn, -Wuninitialized)
    from = _mm512_maskz_permutexvar_epi32(0xffff, _mm512_setr_epi32(0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7),
                                          rank);
  }
  FloatB<Arch> pick(FloatB<Arch> v) const { return FloatB<Arch>(_mm512_maskz_permutexvar_ps(0xffff, from, v)); }
  /// Triangles j and j + 1 of a row: the two floats broadcast as one double, a plain load
  /// (a float pair broadcast takes a shuffle more).
  static FloatB<Arch> broadcast(const float* row) {
    double two;
    std::memcpy(&two, row, sizeof two);
    return FloatB<Arch>(_mm512_castpd_ps(_mm512_set1_pd(two)));
  }
  /// Bit 2s of `per_pair` (pair s blocked) to the s-th lane of `act`.
  static std::uint32_t to_rays(std::uint32_t per_pair, std::uint32_t act) {
    const __m512i pairs = _mm512_movm_epi32(static_cast<__mmask16>(per_pair));
    const __m512i per_ray = _mm512_maskz_compress_epi32(0x5555, pairs);
    return _mm512_movepi32_mask(_mm512_maskz_expand_epi32(static_cast<__mmask16>(act), per_ray)) & act;
  }
};

template <class Arch, int G>
  requires(kLanes<Arch> == 8 && (G == 2 || G == 4 || G == 8))
struct GroupLanes<Arch, G> {
  __m256i from;
  explicit GroupLanes(std::uint32_t act) {
    // At most 8 / G lanes: their indices written by hand (AVX2 has no compress).
    alignas(32) std::int32_t lanes[8] = {};
    int s = 0;
    for (std::uint32_t a = act; a != 0; a &= a - 1, ++s)
      for (int g = 0; g < G; ++g) lanes[G * s + g] = std::countr_zero(a);
    from = _mm256_load_si256(reinterpret_cast<const __m256i*>(lanes));
  }
  FloatB<Arch> pick(FloatB<Arch> v) const { return FloatB<Arch>(_mm256_permutevar8x32_ps(v, from)); }
  /// Triangles j to j + G - 1 of a row (j a multiple of G) in every group of lanes: plain
  /// loads and broadcasts from memory.
  static FloatB<Arch> broadcast(const float* row) {
    if constexpr (G == 2) {
      double two;
      std::memcpy(&two, row, sizeof two);
      return FloatB<Arch>(_mm256_castpd_ps(_mm256_set1_pd(two)));
    } else if constexpr (G == 4) {
      return FloatB<Arch>(_mm256_broadcast_ps(reinterpret_cast<const __m128*>(row)));
    } else {
      return FloatB<Arch>(_mm256_loadu_ps(row));
    }
  }
  static std::uint32_t to_rays(std::uint32_t per_group, std::uint32_t act) {
    std::uint32_t out = 0;
    for (std::uint32_t a = act; a != 0; a &= a - 1, per_group >>= G)
      if (per_group & 1u) out |= a & (0u - a);
    return out;
  }
};

/// The lanes of `act` (at most kLanes / G of them) that some triangle of blocks[0 .. count)
/// occludes, the last block's first `last` triangles only. `upper` is tmax on the active
/// lanes (-inf elsewhere) and `sure` the sure-hit factors of that upper end, as
/// PacketKernels::occluded holds them.
template <class Arch, int BW, int G = 2>
std::uint32_t occluded_groups(const typename WatertightTest<Arch>::Rays& r, FloatB<Arch> upper,
                              const typename WatertightTest<Arch>::SureRange& sure, std::uint32_t act,
                              const WatertightBlock<BW>* blocks, std::uint32_t count, int last) {
  static_assert(BW % G == 0, "a block's triangles in whole groups");
  using T = WatertightTest<Arch>;
  using B = FloatB<Arch>;
  using M = MaskB<Arch>;
  constexpr int L = kLanes<Arch>;
  const int n = std::popcount(act);
  // Lanes G s to G s + G - 1: the s-th active ray (lanes past G n hold a copy of lane 0
  // and an upper end of -inf, which fails every test).
  const GroupLanes<Arch, G> lanes(act);
  typename T::Rays p = r;
  p.okx = lanes.pick(r.okx), p.oky = lanes.pick(r.oky), p.okz = lanes.pick(r.okz);
  p.sx = lanes.pick(r.sx), p.sy = lanes.pick(r.sy), p.sz = -lanes.pick(r.sz);  // negated: the groups below
  p.tmin = lanes.pick(r.tmin), p.tmin_lo = lanes.pick(r.tmin_lo);
  const std::uint32_t live = G * n >= 32 ? ~0u : (1u << (G * n)) - 1u;
  const B up = xsimd::select(mask_from_bits<Arch>(live), lanes.pick(upper), B(-std::numeric_limits<float>::infinity()));
  const typename T::SureRange s{lanes.pick(sure.lo), lanes.pick(sure.hi)};
  // Triangles j to j + G - 1 (j a multiple of G) in the lanes of every group, origin
  // minus vertex as WatertightTest::broadcast_negated.
  const auto group = [&p](const WatertightBlock<BW>& b, int j) {
    const auto at = [&b, j](int k, int axis) { return GroupLanes<Arch, G>::broadcast(&b.p[k][axis][j]); };
    return typename T::Tris{p.okx - at(0, p.kx), p.oky - at(0, p.ky), p.okz - at(0, p.kz),
                            p.okx - at(1, p.kx), p.oky - at(1, p.ky), p.okz - at(1, p.kz),
                            p.okx - at(2, p.kx), p.oky - at(2, p.ky), p.okz - at(2, p.kz)};
  };
  // The first lane of every group, and bit G s for a hit in any lane of group s.
  constexpr std::uint32_t kFirst = G == 2 ? 0x5555u : G == 4 ? 0x1111u : 0x0101u;
  const auto any_of_group = [](std::uint32_t h) {
    for (int k = 1; k < G; k <<= 1) h |= h >> k;
    return h & kFirst;
  };
  const std::uint32_t rays_mask = live & kFirst & ((1u << L) - 1u);
  M hit(false);
  for (std::uint32_t b = 0; b < count; ++b) {
    const WatertightBlock<BW>& block = blocks[b];
    const int used = b + 1 == count ? last : BW;
    for (int j = 0; j < used; j += G) {
      // The steps of PacketKernels::occluded's watertight form, on the groups.
      const auto d = T::template depth<false>(p, group(block, j));
      M cand = T::prefilter(p, d, up) & ~hit;
      if (j + G > used) {  // triangles past `used` in this group: none
        std::uint32_t keep = 0;
        for (int g = 0; g < used - j; ++g) keep |= kFirst << g;
        cand = cand & mask_from_bits<Arch>(keep);
      }
      if (xsimd::none(cand)) continue;
      const M now = T::sure_hit(d, s) & cand;
      hit = hit | now;
      const M rest = cand & ~now;
      if (xsimd::any(rest)) hit = hit | T::confirm(p, {rest, d.ts, d.u, d.v, d.det}, d.ts / d.det, up);
    }
    if (any_of_group(bits_from_mask<Arch>(hit)) == rays_mask) break;
  }
  // A ray is occluded when some lane of its group is: bit G s of the groups to bit s, then
  // to the ray's own lane.
  return GroupLanes<Arch, G>::to_rays(any_of_group(bits_from_mask<Arch>(hit)), act);
}

}  // namespace volley::simd::detail
