// One ray against runs of triangle blocks (the single-ray walk's leaves and the
// standalone kernels), closest hit and any hit. Semantics as in block_kernels.h.
#pragma once
#include <bit>
#include <cstdint>

#include "simd/triangle/kernel_forms.h"

namespace volley::simd {

/// One ray against runs of blocks of W = kLanes<Arch> triangles.
/// Thread-safe (pure functions of their arguments). `blocks` must be 64-byte aligned.
template <class Arch, TriangleTest Test>
struct RayBlockKernels {
  static constexpr int W = kLanes<Arch>;
  using Block = BlockFor<Test, W>;

  /// Closest hit over blocks[0 .. count): updates `hit` (t, u, v, prim) for each triangle
  /// hit with tmin <= t < min(hit.t, ray.tmax); leaves it untouched otherwise.
  static void intersect(const PreparedRay& ray, const Block* blocks, std::uint32_t count, Hit& hit);
  /// The same, inlined into the caller: the single-ray walk of the wide BVH
  /// (simd/wide/single_walk.h), which saves the call, the stack realignment and the ray's
  /// broadcasts at every leaf.
  /// EarlyExit = false runs each block's test to the end instead of leaving it once no lane
  /// passes the edge tests: the walk's choice, since a leaf the walk reaches holds triangles
  /// near the ray and that branch mispredicts; with random blocks, as in the kernel
  /// benchmarks, the exit wins, so the standalone forms keep it (perf/reports/traversal.md).
  /// Excludes: the triangle whose id is `excluded` is never hit (the excluding queries).
  template <bool EarlyExit = true, bool Excludes = false>
  [[gnu::always_inline]] inline static void intersect_inline(const PreparedRay& ray, const Block* blocks,
                                                             std::uint32_t count, Hit& hit,
                                                             std::uint32_t excluded = kInvalidPrim);
  /// True when some triangle of blocks[0 .. count) is hit with tmin <= t < ray.tmax.
  static bool occluded(const PreparedRay& ray, const Block* blocks, std::uint32_t count);
  /// The same, inlined into the caller (as intersect_inline; Excludes as there).
  template <bool Excludes = false>
  [[gnu::always_inline]] inline static bool occluded_inline(const PreparedRay& ray, const Block* blocks,
                                                            std::uint32_t count, std::uint32_t excluded = kInvalidPrim);
  /// Every triangle of blocks[0 .. count) hit with tmin <= t < ray.tmax by the crossing
  /// test (detail::CrossingTestOf): calls sink(prim, t, u, v) for each, in lane order.
  template <class Sink>
  [[gnu::always_inline]] inline static void all_inline(const PreparedRay& ray, const Block* blocks,
                                                       std::uint32_t count, Sink& sink);
};

template <class Arch, TriangleTest Test>
template <class Sink>
void RayBlockKernels<Arch, Test>::all_inline(const PreparedRay& ray, const Block* blocks, std::uint32_t count,
                                             Sink& sink) {
  using T = detail::CrossingTestOf<Arch, Test>;
  using B = detail::FloatB<Arch>;
  constexpr bool kScaled = detail::kDetScaled<T>;
  const auto rays = T::broadcast(ray);
  const B upper(ray.ray.tmax);
  const float tmin = ray.ray.tmin, tmax = ray.ray.tmax;
  for (std::uint32_t b = 0; b < count; ++b) {
    // The walk's leaf form (no early exit: leaves near the ray; AVX-512VL's mask registers).
    typename T::Cand cand;
    std::uint32_t bits;
    detail::BlockTest<Arch, T, false>::run(rays, blocks[b], upper, cand, bits);
    if (bits == 0) continue;
    alignas(64) float ts[W], us[W], vs[W], dens[W];
    cand.t.store_aligned(ts);
    cand.u.store_aligned(us);
    cand.v.store_aligned(vs);
    if constexpr (kScaled) cand.den.store_aligned(dens);
    for (; bits != 0; bits &= bits - 1) {
      const int lane = std::countr_zero(bits);
      // Det-scaled tests decide on the quotient, as the closest-hit loop does.
      const float t = kScaled ? ts[lane] / dens[lane] : ts[lane];
      if (kScaled && !(tmin <= t && t < tmax)) continue;
      sink(blocks[b].prim[lane], t, kScaled ? us[lane] / dens[lane] : us[lane], kScaled ? vs[lane] / dens[lane] : vs[lane]);
    }
  }
}

// ---------------------------------------------------------------------------------------

template <class Arch, TriangleTest Test>
void RayBlockKernels<Arch, Test>::intersect(const PreparedRay& ray, const Block* blocks, std::uint32_t count,
                                            Hit& hit) {
  intersect_inline(ray, blocks, count, hit);
}

template <class Arch, TriangleTest Test>
template <bool EarlyExit, bool Excludes>
void RayBlockKernels<Arch, Test>::intersect_inline(const PreparedRay& ray, const Block* blocks,
                                                   std::uint32_t count, Hit& hit, std::uint32_t excluded) {
  using T = detail::TestOf<Arch, Test>;
  using B = detail::FloatB<Arch>;
  static_assert(B::size == W, "kLanes<Arch> must be the float lane count");
  static_assert(detail::TriangleTestLanes<T>, "a triangle test of one of the three kinds (triangle_test.h)");
  constexpr bool kScaled = detail::kDetScaled<T>;
  const auto rays = T::broadcast(ray);
  float upper = hit.t < ray.ray.tmax ? hit.t : ray.ray.tmax;
  B upper_b(upper);
  // The winner so far: u, v (det-scaled tests: u det, v det and |det|, divided at the end).
  float win_u = 0.0f, win_v = 0.0f, win_den = 1.0f;
  std::uint32_t win_prim = kInvalidPrim;
  for (std::uint32_t b = 0; b < count; ++b) {
    const Block& block = blocks[b];
    // Test all W triangles against the current upper end.
    typename T::Cand cand;
    std::uint32_t bits;
    detail::BlockTest<Arch, T, EarlyExit>::run(rays, block, upper_b, cand, bits);
    if constexpr (Excludes) bits &= detail::bits_from_mask<Arch>(detail::lanes_other_than<Arch>(block, excluded));
    if (bits == 0) continue;
    alignas(64) float ts[W], us[W], vs[W], dens[W];
    cand.t.store_aligned(ts);
    cand.u.store_aligned(us);
    cand.v.store_aligned(vs);
    if constexpr (kScaled) cand.den.store_aligned(dens);
    // Take hits in lane order, shrinking upper after each (the oracle's loop); a lane
    // hit against a larger upper may no longer be once an earlier lane shrank it.
    if constexpr (T::kDecision == detail::Decision::quotient) {
      // Candidates only: each is divided and confirmed on its quotient in turn (the
      // divisions are independent, so they overlap).
      int win_lane = -1;
      const float tmin = ray.ray.tmin;
      for (; bits != 0; bits &= bits - 1) {
        const int lane = std::countr_zero(bits);
        const float t = ts[lane] / dens[lane];
        if (tmin <= t && t < upper) upper = t, win_lane = lane;
      }
      if (win_lane < 0) continue;
      upper_b = B(upper);
      win_u = us[win_lane], win_v = vs[win_lane], win_den = dens[win_lane];
      win_prim = block.prim[win_lane];
    } else {
      int win_lane = -1;
      const float tmin = ray.ray.tmin;
      while (bits != 0) {
        const int lane = std::countr_zero(bits);
        bits &= ~((2u << lane) - 1u);  // lanes after `lane`
        const float t = kScaled ? ts[lane] / dens[lane] : ts[lane];
        // A det-scaled decision is checked on its quotient too (MollerTest::confirm).
        if (kScaled && !(tmin <= t && t < upper)) continue;
        upper = t, win_lane = lane;
        upper_b = B(upper);
        if (bits != 0) bits &= detail::bits_from_mask<Arch>(T::accept(cand, upper_b));
      }
      if (win_lane < 0) continue;
      win_u = us[win_lane], win_v = vs[win_lane];
      if constexpr (kScaled) win_den = dens[win_lane];
      win_prim = block.prim[win_lane];
    }
  }
  if (win_prim == kInvalidPrim) return;
  hit.t = upper;
  hit.u = kScaled ? win_u / win_den : win_u;
  hit.v = kScaled ? win_v / win_den : win_v;
  hit.prim = win_prim;
}

template <class Arch, TriangleTest Test>
bool RayBlockKernels<Arch, Test>::occluded(const PreparedRay& ray, const Block* blocks, std::uint32_t count) {
  return occluded_inline(ray, blocks, count);
}

template <class Arch, TriangleTest Test>
template <bool Excludes>
bool RayBlockKernels<Arch, Test>::occluded_inline(const PreparedRay& ray, const Block* blocks, std::uint32_t count,
                                                  std::uint32_t excluded) {
  using T = detail::TestOf<Arch, Test>;
  using B = detail::FloatB<Arch>;
  const auto rays = T::broadcast(ray);
  const B upper(ray.ray.tmax);
  if constexpr (T::kDecision == detail::Decision::quotient) {
    // Any hit decides on det-scaled values: a lane surely in [tmin, tmax) ends the search
    // with no division; only lanes within a few ulps of either end (rare) are divided. The
    // sure range comes prepared with the ray (formed per call it was measurably slower).
    // One branch per block, on the range prefilter, as the packet form (no exit after the
    // edge test, whose outcome the predictor cannot learn for shadow rays).
    const auto sure = T::sure_range(ray);
    for (std::uint32_t b = 0; b < count; ++b) {
      const auto d = T::template depth<false>(rays, T::load_block(blocks[b], rays));
      auto cand = T::prefilter(rays, d, upper);
      if constexpr (Excludes) {
        cand = cand & detail::lanes_other_than<Arch>(blocks[b], excluded);
        if (xsimd::none(cand)) continue;
        if (xsimd::any(T::sure_hit(d, sure) & cand)) return true;
      } else {
        if (xsimd::none(cand)) continue;
        if (xsimd::any(T::sure_hit(d, sure))) return true;
      }
      std::uint32_t bits = detail::bits_from_mask<Arch>(cand);
      alignas(64) float ts[W], dens[W];
      d.ts.store_aligned(ts);
      d.det.store_aligned(dens);
      for (; bits != 0; bits &= bits - 1) {
        const int lane = std::countr_zero(bits);
        const float t = ts[lane] / dens[lane];
        if (ray.ray.tmin <= t && t < ray.ray.tmax) return true;
      }
    }
    return false;
  } else {
    for (std::uint32_t b = 0; b < count; ++b) {
      if constexpr (Excludes) {
        auto cand = T::test(rays, T::load_block(blocks[b], rays), upper);
        cand.valid = cand.valid & detail::lanes_other_than<Arch>(blocks[b], excluded);
        if (xsimd::none(cand.valid)) continue;
        if (xsimd::any(detail::confirmed<T>(rays, cand, detail::cand_t<T>(cand), upper) & cand.valid)) return true;
      } else {
        const auto cand = T::test(rays, T::load_block(blocks[b], rays), upper);
        if (xsimd::none(cand.valid)) continue;
        if (xsimd::any(detail::confirmed<T>(rays, cand, detail::cand_t<T>(cand), upper))) return true;
      }
    }
    return false;
  }
}

}  // namespace volley::simd
