// The kernel forms, generic over the triangle test (moller.h, plane.h, watertight.h):
//  - one ray x blocks (single-ray traversal of incoherent rays), closest hit and any hit;
//  - a packet of K rays x one triangle, and x blocks (coherent packets), closest and any.
// Bodies are templated on Arch and instantiated only in the per-ISA files
// (isa_sse42.cpp, isa_avx2.cpp, isa_avx512.cpp); the extern template declarations at the
// end keep every other file from instantiating them.
//
// Closest-hit semantics, all forms: triangles are taken in block order, lane order, and a
// triangle replaces the current hit when it is hit with tmin <= t < upper, where upper
// starts as (hit.t < ray.tmax ? hit.t : ray.tmax) and becomes t of each accepted hit. That
// is the scalar oracle's loop exactly (ties keep the earlier triangle unless the test
// itself says otherwise), so the kernels agree with it triangle by triangle.
#pragma once
#include <bit>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "simd/arch.h"
#include "simd/kernel_common.h"
#include "simd/moller.h"
#include "simd/plane.h"
#include "simd/prepared_packet.h"
#include "simd/prepared_ray.h"
#include "simd/ray_packet.h"
#include "simd/triangle_blocks.h"
#include "simd/triangle_test.h"
#include "simd/watertight.h"
#include "volley/options.h"
#include "volley/ray.h"

namespace volley::simd {

namespace detail {
template <class Arch, TriangleTest Test>
struct TestOfT;
template <class Arch>
struct TestOfT<Arch, TriangleTest::moller> {
  using type = MollerTest<Arch>;
};
template <class Arch>
struct TestOfT<Arch, TriangleTest::plane> {
  using type = PlaneTest<Arch>;
};
template <class Arch>
struct TestOfT<Arch, TriangleTest::watertight> {
  using type = WatertightTest<Arch>;
};
/// The vectorized test of `Test` on Arch (a TriangleTestLanes: triangle_test.h).
template <class Arch, TriangleTest Test>
using TestOf = typename TestOfT<Arch, Test>::type;

/// The valid lanes of `c` that hit, given their quotient t (cand_t) and the upper end.
template <class T>
[[gnu::always_inline]] inline auto confirmed(const typename T::Rays& r, const typename T::Cand& c,
                                             const decltype(c.t)& t, const decltype(c.t)& upper) {
  if constexpr (T::kDecision != Decision::direct)
    return T::confirm(r, c, t, upper);
  else
    return c.valid;
}

/// t of the candidate lanes (a true division for a det-scaled test).
template <class T>
[[gnu::always_inline]] inline auto cand_t(const typename T::Cand& c) {
  if constexpr (kDetScaled<T>)
    return c.t / c.den;
  else
    return c.t;
}
}  // namespace detail

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
  /// (wide_traverse.h), which saves the call, the stack realignment and the ray's
  /// broadcasts at every leaf (AVX-512: diffuse +0.5-3%, shadow rays +0-2%).
  /// EarlyExit = false runs each block's test to the end instead of leaving it once no lane
  /// passes the edge tests: the walk's choice. A leaf the walk reaches holds triangles near
  /// the ray, so that branch goes either way and mispredicts; without it diffuse rays ran
  /// 1-4% faster (AVX2 2-5%). With random blocks, as in the kernel benchmarks, the exit
  /// wins by 4-20%, so the standalone forms keep it.
  template <bool EarlyExit = true>
  [[gnu::always_inline]] inline static void intersect_inline(const PreparedRay& ray, const Block* blocks,
                                                             std::uint32_t count, Hit& hit);
  /// True when some triangle of blocks[0 .. count) is hit with tmin <= t < ray.tmax.
  static bool occluded(const PreparedRay& ray, const Block* blocks, std::uint32_t count);
  /// The same, inlined into the caller (as intersect_inline).
  [[gnu::always_inline]] inline static bool occluded_inline(const PreparedRay& ray, const Block* blocks,
                                                            std::uint32_t count);
};

/// A packet of K rays (K a multiple of kLanes<Arch>) against triangles in blocks of BW
/// (the lane count, except on AVX-512, whose wide BVH stores blocks of 8: SingleRayArch).
/// The packet is prepared once (prepare) and then reused for every call. Only lanes whose
/// `active` bit is set are tested and written.
template <class Arch, TriangleTest Test, int K, int BW = kLanes<Arch>>
struct PacketKernels {
  static constexpr int W = BW;
  static constexpr int L = kLanes<Arch>;
  static_assert(K % L == 0, "K rays per packet must be a multiple of the lane count");
  using Block = BlockFor<Test, W>;

  /// Per-lane precomputation of Test for `rays` (the Woop shear for watertight).
  static void prepare(const RayPacket<K>& rays, PreparedPacket<K>& out);
  /// Closest hit of every active lane over blocks[0 .. count) (semantics as in
  /// RayBlockKernels::intersect, per lane).
  static void intersect(const PreparedPacket<K>& rays, const Block* blocks, std::uint32_t count, HitPacket<K>& hits);
  /// Closest hit of every active lane against triangle j of `block` alone.
  static void intersect_triangle(const PreparedPacket<K>& rays, const Block& block, int j, HitPacket<K>& hits);
  /// The lanes of `active` (ANDed with rays.rays.active) that some triangle of
  /// blocks[0 .. count) occludes (tmin <= t < tmax). Stops as soon as all are occluded.
  static std::uint32_t occluded(const PreparedPacket<K>& rays, const Block* blocks, std::uint32_t count,
                                std::uint32_t active);
};

// ---------------------------------------------------------------------------------------

template <class Arch, TriangleTest Test>
void RayBlockKernels<Arch, Test>::intersect(const PreparedRay& ray, const Block* blocks, std::uint32_t count,
                                            Hit& hit) {
  intersect_inline(ray, blocks, count, hit);
}

template <class Arch, TriangleTest Test>
template <bool EarlyExit>
void RayBlockKernels<Arch, Test>::intersect_inline(const PreparedRay& ray, const Block* blocks,
                                                   std::uint32_t count, Hit& hit) {
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
bool RayBlockKernels<Arch, Test>::occluded_inline(const PreparedRay& ray, const Block* blocks, std::uint32_t count) {
  using T = detail::TestOf<Arch, Test>;
  using B = detail::FloatB<Arch>;
  const auto rays = T::broadcast(ray);
  const B upper(ray.ray.tmax);
  if constexpr (T::kDecision == detail::Decision::quotient) {
    // Any hit decides on det-scaled values: a lane surely in [tmin, tmax) ends the search
    // with no division; only lanes within a few ulps of either end (rare) are divided. The
    // sure range comes prepared with the ray (formed per call, it cost 8% at AVX-512).
    const auto sure = T::sure_range(ray);
    for (std::uint32_t b = 0; b < count; ++b) {
      const auto d = T::depth(rays, T::load_block(blocks[b], rays));
      if (xsimd::none(d.inside)) continue;
      if (xsimd::any(T::sure_hit(d, sure))) return true;
      std::uint32_t bits = detail::bits_from_mask<Arch>(T::prefilter(rays, d, upper));
      if (bits == 0) continue;
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
      const auto cand = T::test(rays, T::load_block(blocks[b], rays), upper);
      if (xsimd::none(cand.valid)) continue;
      if (xsimd::any(detail::confirmed<T>(rays, cand, detail::cand_t<T>(cand), upper))) return true;
    }
    return false;
  }
}

template <class Arch, TriangleTest Test, int K, int BW>
void PacketKernels<Arch, Test, K, BW>::prepare(const RayPacket<K>& rays, PreparedPacket<K>& out) {
  detail::TestOf<Arch, Test>::template prepare<K>(rays, out);
}

template <class Arch, TriangleTest Test, int K, int BW>
void PacketKernels<Arch, Test, K, BW>::intersect(const PreparedPacket<K>& prepared, const Block* blocks,
                                                 std::uint32_t count, HitPacket<K>& hits) {
  using T = detail::TestOf<Arch, Test>;
  using B = detail::FloatB<Arch>;
  using M = detail::MaskB<Arch>;
  static_assert(B::size == L, "kLanes<Arch> must be the float lane count");
  constexpr bool kScaled = detail::kDetScaled<T>;
  const RayPacket<K>& rays = prepared.rays;
  for (int c = 0; c < K; c += L) {
    const std::uint32_t act_bits = (rays.active >> c) & ((2u << (L - 1)) - 1u);
    if (act_bits == 0) continue;
    const M act = detail::mask_from_bits<Arch>(act_bits);
    const auto r = T::template load<K>(prepared, c);
    // Inactive lanes search [tmin, -inf): never hit.
    B upper = xsimd::select(act, detail::upper_bound(B::load_aligned(hits.t + c), B::load_aligned(rays.tmax + c)),
                            B(-std::numeric_limits<float>::infinity()));
    // u, v of each lane's winner (det-scaled tests: u det, v det and |det|, divided at the end).
    B hu = B::load_aligned(hits.u + c), hv = B::load_aligned(hits.v + c), hden(1.0f);
    B hp = detail::load_ids<Arch>(hits.prim + c);
    M any_hit(false);
    // Triangles in block order, each broadcast to all lanes; hits only shrink upper.
    for (std::uint32_t b = 0; b < count; ++b) {
      const Block& block = blocks[b];
      for (int j = 0; j < W; ++j) {
        const auto cand = T::test(r, T::broadcast_tri(block, j, r), upper);
        if (xsimd::none(cand.valid)) continue;
        const B t = detail::cand_t<T>(cand);
        const M hit = detail::confirmed<T>(r, cand, t, upper);
        upper = xsimd::select(hit, t, upper);
        hu = xsimd::select(hit, cand.u, hu);
        hv = xsimd::select(hit, cand.v, hv);
        if constexpr (kScaled) hden = xsimd::select(hit, cand.den, hden);
        hp = xsimd::select(hit, detail::broadcast_id<Arch>(block.prim[j]), hp);
        any_hit = any_hit | hit;
      }
    }
    if (xsimd::none(any_hit)) continue;
    xsimd::select(any_hit, upper, B::load_aligned(hits.t + c)).store_aligned(hits.t + c);
    if constexpr (kScaled) {
      // Lanes without a hit keep their stored u, v (divided by 1: unchanged).
      hu = hu / hden, hv = hv / hden;
    }
    hu.store_aligned(hits.u + c);
    hv.store_aligned(hits.v + c);
    hp.store_aligned(reinterpret_cast<float*>(hits.prim + c));
  }
}

template <class Arch, TriangleTest Test, int K, int BW>
void PacketKernels<Arch, Test, K, BW>::intersect_triangle(const PreparedPacket<K>& prepared, const Block& block, int j,
                                                          HitPacket<K>& hits) {
  using T = detail::TestOf<Arch, Test>;
  using B = detail::FloatB<Arch>;
  using M = detail::MaskB<Arch>;
  const RayPacket<K>& rays = prepared.rays;
  for (int c = 0; c < K; c += L) {
    const std::uint32_t act_bits = (rays.active >> c) & ((2u << (L - 1)) - 1u);
    if (act_bits == 0) continue;
    const M act = detail::mask_from_bits<Arch>(act_bits);
    const auto r = T::template load<K>(prepared, c);
    const B ht = B::load_aligned(hits.t + c);
    const B upper = xsimd::select(act, detail::upper_bound(ht, B::load_aligned(rays.tmax + c)),
                                  B(-std::numeric_limits<float>::infinity()));
    const auto cand = T::test(r, T::broadcast_tri(block, j, r), upper);
    if (xsimd::none(cand.valid)) continue;
    const B t = detail::cand_t<T>(cand);
    const M hit = detail::confirmed<T>(r, cand, t, upper);
    if constexpr (T::kDecision != detail::Decision::direct)
      if (xsimd::none(hit)) continue;
    xsimd::select(hit, t, ht).store_aligned(hits.t + c);
    B u = cand.u, v = cand.v;
    if constexpr (detail::kDetScaled<T>) u = u / cand.den, v = v / cand.den;
    xsimd::select(hit, u, B::load_aligned(hits.u + c)).store_aligned(hits.u + c);
    xsimd::select(hit, v, B::load_aligned(hits.v + c)).store_aligned(hits.v + c);
    xsimd::select(hit, detail::broadcast_id<Arch>(block.prim[j]), detail::load_ids<Arch>(hits.prim + c))
        .store_aligned(reinterpret_cast<float*>(hits.prim + c));
  }
}

template <class Arch, TriangleTest Test, int K, int BW>
std::uint32_t PacketKernels<Arch, Test, K, BW>::occluded(const PreparedPacket<K>& prepared, const Block* blocks,
                                                         std::uint32_t count, std::uint32_t active) {
  using T = detail::TestOf<Arch, Test>;
  using B = detail::FloatB<Arch>;
  using M = detail::MaskB<Arch>;
  const RayPacket<K>& rays = prepared.rays;
  std::uint32_t result = 0;
  active &= rays.active;
  for (int c = 0; c < K; c += L) {
    const std::uint32_t act_bits = (active >> c) & ((2u << (L - 1)) - 1u);
    if (act_bits == 0) continue;
    const M act = detail::mask_from_bits<Arch>(act_bits);
    const auto r = T::template load<K>(prepared, c);
    const B upper = xsimd::select(act, B::load_aligned(rays.tmax + c), B(-std::numeric_limits<float>::infinity()));
    M hit(false);
    // Watertight: lanes surely in [tmin, tmax) hit with no division (see the single-ray
    // form); a triangle is divided only when it has other candidates.
    [[maybe_unused]] const auto sure = [&] {
      if constexpr (T::kDecision == detail::Decision::quotient)
        return T::sure_range(B::load_aligned(rays.tmin + c), upper);
      else
        return 0;
    }();
    // Any hit ends a lane; the chunk ends when every active lane has one.
    for (std::uint32_t b = 0; b < count; ++b) {
      const Block& block = blocks[b];
      for (int j = 0; j < W; ++j) {
        if constexpr (T::kDecision == detail::Decision::quotient) {
          const auto d = T::depth(r, T::broadcast_tri(block, j, r));
          if (xsimd::none(d.inside)) continue;
          hit = hit | T::sure_hit(d, sure);
          const M rest = T::prefilter(r, d, upper) & ~hit;
          if (xsimd::any(rest)) hit = hit | T::confirm(r, {rest, d.ts, d.u, d.v, d.det}, d.ts / d.det, upper);
        } else {
          const auto cand = T::test(r, T::broadcast_tri(block, j, r), upper);
          if (xsimd::any(cand.valid)) hit = hit | detail::confirmed<T>(r, cand, detail::cand_t<T>(cand), upper);
        }
      }
      if (xsimd::all(hit | ~act)) break;
    }
    result |= detail::bits_from_mask<Arch>(hit & act) << c;
  }
  return result;
}

// Explicit instantiation declarations: the definitions live in the per-ISA files only
// (one line there per line here). K = every packet size that is a multiple of the lanes.
extern template struct RayBlockKernels<Sse42, TriangleTest::moller>;
extern template struct RayBlockKernels<Sse42, TriangleTest::plane>;
extern template struct RayBlockKernels<Sse42, TriangleTest::watertight>;
extern template struct PacketKernels<Sse42, TriangleTest::moller, 4>;
extern template struct PacketKernels<Sse42, TriangleTest::moller, 8>;
extern template struct PacketKernels<Sse42, TriangleTest::moller, 16>;
extern template struct PacketKernels<Sse42, TriangleTest::plane, 4>;
extern template struct PacketKernels<Sse42, TriangleTest::plane, 8>;
extern template struct PacketKernels<Sse42, TriangleTest::plane, 16>;
extern template struct PacketKernels<Sse42, TriangleTest::watertight, 4>;
extern template struct PacketKernels<Sse42, TriangleTest::watertight, 8>;
extern template struct PacketKernels<Sse42, TriangleTest::watertight, 16>;

extern template struct RayBlockKernels<Avx2, TriangleTest::moller>;
extern template struct RayBlockKernels<Avx2, TriangleTest::plane>;
extern template struct RayBlockKernels<Avx2, TriangleTest::watertight>;
extern template struct PacketKernels<Avx2, TriangleTest::moller, 8>;
extern template struct PacketKernels<Avx2, TriangleTest::moller, 16>;
extern template struct PacketKernels<Avx2, TriangleTest::plane, 8>;
extern template struct PacketKernels<Avx2, TriangleTest::plane, 16>;
extern template struct PacketKernels<Avx2, TriangleTest::watertight, 8>;
extern template struct PacketKernels<Avx2, TriangleTest::watertight, 16>;

extern template struct RayBlockKernels<Avx512, TriangleTest::moller>;
extern template struct RayBlockKernels<Avx512, TriangleTest::plane>;
extern template struct RayBlockKernels<Avx512, TriangleTest::watertight>;
extern template struct PacketKernels<Avx512, TriangleTest::moller, 16>;
extern template struct PacketKernels<Avx512, TriangleTest::plane, 16>;
extern template struct PacketKernels<Avx512, TriangleTest::watertight, 16>;
extern template struct PacketKernels<Avx512, TriangleTest::moller, 16, 8>;
extern template struct PacketKernels<Avx512, TriangleTest::plane, 16, 8>;
extern template struct PacketKernels<Avx512, TriangleTest::watertight, 16, 8>;

extern template struct RayBlockKernels<Avx512Ymm, TriangleTest::moller>;
extern template struct RayBlockKernels<Avx512Ymm, TriangleTest::plane>;
extern template struct RayBlockKernels<Avx512Ymm, TriangleTest::watertight>;
extern template struct PacketKernels<Avx512Ymm, TriangleTest::moller, 8>;
extern template struct PacketKernels<Avx512Ymm, TriangleTest::moller, 16>;
extern template struct PacketKernels<Avx512Ymm, TriangleTest::plane, 8>;
extern template struct PacketKernels<Avx512Ymm, TriangleTest::plane, 16>;
extern template struct PacketKernels<Avx512Ymm, TriangleTest::watertight, 8>;
extern template struct PacketKernels<Avx512Ymm, TriangleTest::watertight, 16>;

}  // namespace volley::simd
