// A packet of rays against triangle blocks or one triangle of a block (the packet walks'
// leaves and the standalone kernels), closest hit and any hit. Semantics as in
// block_kernels.h.
#pragma once
#include <bit>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "simd/triangle/kernel_forms.h"
#include "simd/triangle/paired_lanes.h"

namespace volley::simd {

namespace detail {

/// The nearest hit of kLanes<Arch> ray lanes over triangles broadcast one at a time, in
/// block order (the closest-hit packet kernel's loop; the stream walk's leaf lists too).
/// Hits only shrink `upper`; a lane's winner keeps u, v (det-scaled tests: u det, v det
/// and det, divided by finish()) and prim. `any`: the lanes some triangle hit.
template <class Arch, class T>
struct NearestLanes {
  using B = FloatB<Arch>;
  using M = MaskB<Arch>;
  static constexpr bool kScaled = kDetScaled<T>;
  B upper, u, v, den = B(1.0f), prim;  // (not den{1.0f}: xsimd takes braces as a list of lanes)
  M any = M(false);

  [[gnu::always_inline]] NearestLanes(B upper_, B u_, B v_, B prim_) : upper(upper_), u(u_), v(v_), prim(prim_) {}

  template <class Block>
  [[gnu::always_inline]] void triangle(const typename T::Rays& r, const Block& block, int j) {
    const auto cand = T::test(r, T::broadcast_tri(block, j, r), upper);
    if (xsimd::none(cand.valid)) return;
    const B t = cand_t<T>(cand);
    const M hit = confirmed<T>(r, cand, t, upper);
    upper = xsimd::select(hit, t, upper);
    u = xsimd::select(hit, cand.u, u);
    v = xsimd::select(hit, cand.v, v);
    if constexpr (kScaled) den = xsimd::select(hit, cand.den, den);
    prim = xsimd::select(hit, broadcast_id<Arch>(block.prim[j]), prim);
    any = any | hit;
  }
  /// blocks[0 .. count), the last one's first `last` triangles only: whole blocks with a
  /// fixed trip count, then the last cut short (one loop with a variable bound ran 2% more
  /// instructions on whole blocks: perf/reports/rays.md).
  template <class Block>
  [[gnu::always_inline]] void blocks(const typename T::Rays& r, const Block* blocks, std::uint32_t count,
                                     int last) {
    constexpr int W = static_cast<int>(std::extent_v<decltype(Block::prim)>);
    const std::uint32_t whole = last < W && count != 0 ? count - 1 : count;
    for (std::uint32_t b = 0; b < whole; ++b)
      for (int j = 0; j < W; ++j) triangle(r, blocks[b], j);
    if (whole != count)
      for (int j = 0; j < last; ++j) triangle(r, blocks[whole], j);
  }
  /// u and v of the winners (lanes without a hit keep theirs: divided by 1).
  [[gnu::always_inline]] void finish() {
    if constexpr (kScaled) u = u / den, v = v / den;
  }
};

}  // namespace detail

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
  /// RayBlockKernels::intersect, per lane), the last block's first `last` triangles only
  /// (a sparse last block: its padding untested).
  static void intersect(const PreparedPacket<K>& rays, const Block* blocks, std::uint32_t count, HitPacket<K>& hits,
                        int last = BW);
  /// Closest hit of every active lane against triangle j of `block` alone.
  static void intersect_triangle(const PreparedPacket<K>& rays, const Block& block, int j, HitPacket<K>& hits);
  /// The lanes of `active` (ANDed with rays.rays.active) that some triangle of
  /// blocks[0 .. count) occludes (tmin <= t < tmax), the last block's first `last`
  /// triangles only (a sparse last block: its padding untested). Stops as soon as all are
  /// occluded.
  static std::uint32_t occluded(const PreparedPacket<K>& rays, const Block* blocks, std::uint32_t count,
                                std::uint32_t active, int last = BW);
  /// Every triangle of blocks[0 .. count) that the lanes of `active` (ANDed with
  /// rays.rays.active) hit with tmin <= t < tmax by the crossing test
  /// (detail::CrossingTestOf): sink(lane, prim, t, u, v) for each, triangle by triangle.
  template <class Sink>
  static void all(const PreparedPacket<K>& rays, const Block* blocks, std::uint32_t count, std::uint32_t active,
                  Sink& sink);
};

template <class Arch, TriangleTest Test, int K, int BW>
template <class Sink>
void PacketKernels<Arch, Test, K, BW>::all(const PreparedPacket<K>& prepared, const Block* blocks, std::uint32_t count,
                                           std::uint32_t active, Sink& sink) {
  using T = detail::CrossingTestOf<Arch, Test>;
  using B = detail::FloatB<Arch>;
  using M = detail::MaskB<Arch>;
  const RayPacket<K>& rays = prepared.rays;
  active &= rays.active;
  for (int c = 0; c < K; c += L) {
    const std::uint32_t act_bits = (active >> c) & ((2u << (L - 1)) - 1u);
    if (act_bits == 0) continue;
    const M act = detail::mask_from_bits<Arch>(act_bits);
    const auto r = T::template load<K>(prepared, c);
    const B upper = xsimd::select(act, B::load_aligned(rays.tmax + c), B(-std::numeric_limits<float>::infinity()));
    for (std::uint32_t b = 0; b < count; ++b) {
      const Block& block = blocks[b];
      for (int j = 0; j < W && block.prim[j] != kInvalidPrim; ++j) {
        const auto cand = T::test(r, T::broadcast_tri(block, j, r), upper);
        if (xsimd::none(cand.valid)) continue;
        const B t = detail::cand_t<T>(cand);
        std::uint32_t bits = detail::bits_from_mask<Arch>(detail::confirmed<T>(r, cand, t, upper)) & act_bits;
        if (bits == 0) continue;
        B u = cand.u, v = cand.v;
        if constexpr (detail::kDetScaled<T>) u = u / cand.den, v = v / cand.den;
        alignas(64) float ts[L], us[L], vs[L];
        t.store_aligned(ts), u.store_aligned(us), v.store_aligned(vs);
        for (; bits != 0; bits &= bits - 1) {
          const int lane = std::countr_zero(bits);
          sink(c + lane, block.prim[j], ts[lane], us[lane], vs[lane]);
        }
      }
    }
  }
}

// ---------------------------------------------------------------------------------------

template <class Arch, TriangleTest Test, int K, int BW>
void PacketKernels<Arch, Test, K, BW>::prepare(const RayPacket<K>& rays, PreparedPacket<K>& out) {
  detail::TestOf<Arch, Test>::template prepare<K>(rays, out);
}

template <class Arch, TriangleTest Test, int K, int BW>
void PacketKernels<Arch, Test, K, BW>::intersect(const PreparedPacket<K>& prepared, const Block* blocks,
                                                 std::uint32_t count, HitPacket<K>& hits, int last) {
  using T = detail::TestOf<Arch, Test>;
  using B = detail::FloatB<Arch>;
  using M = detail::MaskB<Arch>;
  static_assert(B::size == L, "kLanes<Arch> must be the float lane count");
  const RayPacket<K>& rays = prepared.rays;
  for (int c = 0; c < K; c += L) {
    const std::uint32_t act_bits = (rays.active >> c) & ((2u << (L - 1)) - 1u);
    if (act_bits == 0) continue;
    const M act = detail::mask_from_bits<Arch>(act_bits);
    // Inactive lanes search [tmin, -inf): never hit.
    detail::NearestLanes<Arch, T> near(
        xsimd::select(act, detail::upper_bound(B::load_aligned(hits.t + c), B::load_aligned(rays.tmax + c)),
                      B(-std::numeric_limits<float>::infinity())),
        B::load_aligned(hits.u + c), B::load_aligned(hits.v + c), detail::load_ids<Arch>(hits.prim + c));
    near.blocks(T::template load<K>(prepared, c), blocks, count, last);
    if (xsimd::none(near.any)) continue;
    xsimd::select(near.any, near.upper, B::load_aligned(hits.t + c)).store_aligned(hits.t + c);
    near.finish();
    near.u.store_aligned(hits.u + c);
    near.v.store_aligned(hits.v + c);
    near.prim.store_aligned(reinterpret_cast<float*>(hits.prim + c));
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

namespace detail {

/// The any-hit test of one chunk of lanes against the triangles of `count` blocks of W,
/// the last ending at its `last` triangle: the lanes of `act` that some triangle hits in
/// [tmin, upper). Any hit ends a lane; the chunk ends when every active lane has one.
/// Uniform: one axis permutation for the packet, known for the whole loop (whose registers
/// then hold no per-lane permutation), and its rays and triangles in the any-hit form
/// (WatertightTest::any_hit_uniform). Watertight: lanes surely in [tmin, tmax) hit with no
/// division (`sure`, as the single-ray form); a triangle is divided only when it has other
/// candidates. No exit after the edge test: for shadow rays whether some lane passes
/// inside is a coin toss, and the range prefilter, which almost never passes, is the one
/// branch (perf/reports/rays.md, "occlusion without the edge-test branch").
template <class T, bool Uniform, int W, class Block, class Rays, class B, class M, class Sure>
[[gnu::always_inline]] inline M occluded_chunk(const Rays& r, const Block* blocks, std::uint32_t count, int last,
                                               const B& upper, const Sure& sure, const M& act) {
  M hit(false);
  for (std::uint32_t b = 0; b < count; ++b) {
    const Block& block = blocks[b];
    const int used = b + 1 == count ? last : W;
    for (int j = 0; j < used; ++j) {
      if constexpr (T::kDecision == Decision::quotient) {
        const auto tri = [&] {
          if constexpr (Uniform)
            return T::any_hit_uniform(block, j, r);
          else
            return T::broadcast_tri(block, j, r);
        }();
        const auto d = T::template depth<false>(r, tri);
        const M cand = T::prefilter(r, d, upper) & ~hit;
        if (xsimd::none(cand)) continue;
        const M now = T::sure_hit(d, sure) & cand;
        hit = hit | now;
        const M rest = cand & ~now;
        if (xsimd::any(rest)) hit = hit | T::confirm(r, {rest, d.ts, d.u, d.v, d.det}, d.ts / d.det, upper);
      } else {
        const auto cand = T::test(r, T::broadcast_tri(block, j, r), upper);
        if (xsimd::any(cand.valid)) hit = hit | confirmed<T>(r, cand, cand_t<T>(cand), upper);
      }
    }
    if (xsimd::all(hit | ~act)) break;
  }
  return hit;
}

}  // namespace detail

template <class Arch, TriangleTest Test, int K, int BW>
std::uint32_t PacketKernels<Arch, Test, K, BW>::occluded(const PreparedPacket<K>& prepared, const Block* blocks,
                                                         std::uint32_t count, std::uint32_t active, int last) {
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
    // (Watertight) sure_hit lanes are prefilter lanes (lo > tmin_lo, hi < upper).
    [[maybe_unused]] const auto sure = [&] {
      if constexpr (T::kDecision == detail::Decision::quotient)
        return T::sure_range(B::load_aligned(rays.tmin + c), upper);
      else
        return 0;
    }();
    if constexpr (detail::kPairedLanes<Arch, Test, BW>) {
      // Few lanes: two triangles per register, on AVX2 four for two lanes and eight for
      // one (paired_lanes.h).
      const int n = std::popcount(act_bits);
      if (r.uniform && n <= L / 2 && (count > 1 || last > 1)) {
        if constexpr (L == 8 && BW == 8) {
          if (n == 1 && (count > 1 || last > 4)) {
            result |= detail::occluded_groups<Arch, BW, 8>(r, upper, sure, act_bits, blocks, count, last) << c;
            continue;
          }
          if (n <= 2 && (count > 1 || last > 2)) {
            result |= detail::occluded_groups<Arch, BW, 4>(r, upper, sure, act_bits, blocks, count, last) << c;
            continue;
          }
        }
        result |= detail::occluded_groups<Arch, BW, 2>(r, upper, sure, act_bits, blocks, count, last) << c;
        continue;
      }
    }
    M hit;
    if constexpr (T::kDecision == detail::Decision::quotient)
      hit = r.uniform ? detail::occluded_chunk<T, true, W>(T::any_hit_rays(r), blocks, count, last, upper, sure, act)
                      : detail::occluded_chunk<T, false, W>(r, blocks, count, last, upper, sure, act);
    else
      hit = detail::occluded_chunk<T, false, W>(r, blocks, count, last, upper, sure, act);
    result |= detail::bits_from_mask<Arch>(hit & act) << c;
  }
  return result;
}

}  // namespace volley::simd
