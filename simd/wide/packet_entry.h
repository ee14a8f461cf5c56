// Packets of 16 rays: the entries that screen a packet and pick its walk (frustum or
// per lane), and the leaf step both packet walks share (the block kernels on the lanes a
// leaf's box test kept).
#pragma once
#include <bit>
#include <cstdint>

#include "simd/wide/kernels.h"

namespace volley::simd {

template <class Arch, TriangleTest Test, bool Robust>
void WideKernels<Arch, Test, Robust>::intersect(const View& bvh, const RayPacket<K>& rays, HitPacket<K>& hits) {
  if (bvh.root == wide_ref::kEmptyRef || (rays.active & ((1u << K) - 1u)) == 0) return;
  PreparedPacket<K> prep;
  prep.rays = rays;
  detail::PacketSetup<K> setup;
  screen(prep.rays, setup);
  if (setup.valid == 0) return;
  PacketKernels<Arch, Test, K, W>::prepare(prep.rays, prep);
  if (setup.walk == detail::PacketWalk::frustum)
    trace_frustum<false>(bvh, prep, setup, hits);
  else if (setup.walk == detail::PacketWalk::one_octant)
    trace_packet<false, true>(bvh, prep, setup, hits);
  else
    trace_packet<false, false>(bvh, prep, setup, hits);
}

template <class Arch, TriangleTest Test, bool Robust>
std::uint32_t WideKernels<Arch, Test, Robust>::occluded(const View& bvh, const RayPacket<K>& rays) {
  if (bvh.root == wide_ref::kEmptyRef || (rays.active & ((1u << K) - 1u)) == 0) return 0;
  PreparedPacket<K> prep;
  prep.rays = rays;
  detail::PacketSetup<K> setup;
  screen(prep.rays, setup);
  if (setup.valid == 0) return 0;
  PacketKernels<Arch, Test, K, W>::prepare(prep.rays, prep);
  HitPacket<K> unused;
  if (setup.walk == detail::PacketWalk::frustum) return trace_frustum<true>(bvh, prep, setup, unused);
  return setup.walk == detail::PacketWalk::one_octant ? trace_packet<true, true>(bvh, prep, setup, unused)
                                                      : trace_packet<true, false>(bvh, prep, setup, unused);
}

template <class Arch, TriangleTest Test, bool Robust>
void WideKernels<Arch, Test, Robust>::screen(RayPacket<K>& rays, detail::PacketSetup<K>& setup) {
  using B = detail::FloatB<Arch>;
  using M = detail::MaskB<Arch>;
  constexpr int C = K / L;
  const B zero(0.0f);
  std::uint32_t valid = 0, negx = 0, negy = 0, negz = 0, zeros = 0, other_origin = 0;
  for (int c = 0; c < C; ++c) {
    const int o = c * L;
    const B ox = B::load_aligned(rays.ox + o), oy = B::load_aligned(rays.oy + o), oz = B::load_aligned(rays.oz + o);
    const B dx = B::load_aligned(rays.dx + o), dy = B::load_aligned(rays.dy + o), dz = B::load_aligned(rays.dz + o);
    const B tmin = B::load_aligned(rays.tmin + o), tmax = B::load_aligned(rays.tmax + o);
    // Finite: x - x is 0, NaN for Inf and NaN. Not NaN: x == x.
    const M ok = detail::mask_from_bits<Arch>((rays.active >> o) & kChunkBits) & ((ox - ox) == zero) &
                 ((oy - oy) == zero) & ((oz - oz) == zero) & ((dx - dx) == zero) & ((dy - dy) == zero) &
                 ((dz - dz) == zero) & (tmin == tmin) & (tmax == tmax);
    // The oracle's reciprocal and octant (sign bit of 1 / dir: 1 / -0 = -inf < 0).
    const B ix = B(1.0f) / dx, iy = B(1.0f) / dy, iz = B(1.0f) / dz;
    ix.store_aligned(setup.inv[0] + o);
    iy.store_aligned(setup.inv[1] + o);
    iz.store_aligned(setup.inv[2] + o);
    const std::uint32_t okb = detail::bits_from_mask<Arch>(ok);
    valid |= okb << o;
    negx |= (detail::bits_from_mask<Arch>(ix < zero) & okb) << o;
    negy |= (detail::bits_from_mask<Arch>(iy < zero) & okb) << o;
    negz |= (detail::bits_from_mask<Arch>(iz < zero) & okb) << o;
    zeros |= (detail::bits_from_mask<Arch>((dx == zero) | (dy == zero) | (dz == zero)) & okb) << o;
    // Rejected lanes become inert: org = dir = 0, tmin = 0, tmax = -inf.
    if (okb != kChunkBits) {
      xsimd::select(ok, ox, zero).store_aligned(rays.ox + o);
      xsimd::select(ok, oy, zero).store_aligned(rays.oy + o);
      xsimd::select(ok, oz, zero).store_aligned(rays.oz + o);
      xsimd::select(ok, dx, zero).store_aligned(rays.dx + o);
      xsimd::select(ok, dy, zero).store_aligned(rays.dy + o);
      xsimd::select(ok, dz, zero).store_aligned(rays.dz + o);
      xsimd::select(ok, tmin, zero).store_aligned(rays.tmin + o);
      xsimd::select(ok, tmax, B(-std::numeric_limits<float>::infinity())).store_aligned(rays.tmax + o);
    }
  }
  // The common origin of the frustum walk: the first valid lane's (a rejected lane, NaN
  // origin or not, would make every other lane differ).
  const int first = std::countr_zero(valid | (1u << (K - 1)));
  const B fx(rays.ox[first]), fy(rays.oy[first]), fz(rays.oz[first]);
  for (int c = 0; c < C; ++c) {
    const int o = c * L;
    const B ox = B::load_aligned(rays.ox + o), oy = B::load_aligned(rays.oy + o), oz = B::load_aligned(rays.oz + o);
    other_origin |= (detail::bits_from_mask<Arch>((ox != fx) | (oy != fy) | (oz != fz)) & (valid >> o) & kChunkBits)
                    << o;
  }
  rays.active = valid;
  setup.valid = valid;
  const bool one_octant = (negx == 0 || negx == valid) && (negy == 0 || negy == valid) && (negz == 0 || negz == valid);
  setup.walk = one_octant ? (zeros == 0 && other_origin == 0 ? detail::PacketWalk::frustum : detail::PacketWalk::one_octant)
                          : detail::PacketWalk::mixed_octants;
}

template <class Arch, TriangleTest Test, bool Robust>
int WideKernels<Arch, Test, Robust>::used_lanes(const Block& block) {
  using I = detail::IntB<SingleArch>;
  const I ids = I::load_aligned(reinterpret_cast<const std::int32_t*>(block.prim));
  const auto used = xsimd::bool_cast(ids != I(static_cast<std::int32_t>(kInvalidPrim)));
  return std::popcount(detail::bits_from_mask<SingleArch>(used));
}

template <class Arch, TriangleTest Test, bool Robust>
void WideKernels<Arch, Test, Robust>::leaf_intersect(const PreparedPacket<K>& prep, const Block* blocks,
                                                     std::uint32_t count, HitPacket<K>& hits) {
  using LeafPacket = PacketKernels<Arch, Test, K, W>;
  const Block& last = blocks[count - 1];
  const int used = used_lanes(last);
  if (used > W / 2) return LeafPacket::intersect(prep, blocks, count, hits);
  if (count > 1) LeafPacket::intersect(prep, blocks, count - 1, hits);
  for (int j = 0; j < used; ++j) LeafPacket::intersect_triangle(prep, last, j, hits);
}

template <class Arch, TriangleTest Test, bool Robust>
std::uint32_t WideKernels<Arch, Test, Robust>::leaf_occluded(PreparedPacket<K>& prep, const Block* blocks,
                                                             std::uint32_t count, std::uint32_t lanes) {
  using LeafPacket = PacketKernels<Arch, Test, K, W>;
  const Block& last = blocks[count - 1];
  const int used = used_lanes(last);
  if (used > W / 2) return LeafPacket::occluded(prep, blocks, count, lanes);
  std::uint32_t hit = count > 1 ? LeafPacket::occluded(prep, blocks, count - 1, lanes) : 0u;
  if (hit == lanes) return hit;
  // Any hit within [tmin, tmax) of a lane: a closest-hit test against a fresh +inf bound.
  HitPacket<K> scratch;
  for (int i = 0; i < K; ++i) scratch.t[i] = std::numeric_limits<float>::infinity(), scratch.prim[i] = kInvalidPrim;
  const std::uint32_t saved = prep.rays.active;
  prep.rays.active = lanes & ~hit;
  for (int j = 0; j < used; ++j) LeafPacket::intersect_triangle(prep, last, j, scratch);
  prep.rays.active = saved;
  for (int i = 0; i < K; ++i)
    if (scratch.prim[i] != kInvalidPrim) hit |= 1u << i;
  return hit & lanes;
}

}  // namespace volley::simd
