// Packets of 16 rays: the entries that screen a packet, prepare it for the triangle test
// and hand it with its query (queries.h) to the walk its lanes allow (frustum or per lane).
#pragma once
#include <bit>
#include <cstdint>

#include "simd/wide/kernels.h"
#include "simd/wide/packet_queries.h"

namespace volley::simd {

template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query, class Leaves>
std::uint32_t WideKernels<Arch, Test, Robust, PK>::trace_packet_query(const WideView<Leaves>& bvh, const RayPacket<K>& rays,
                                                                  Query& query) {
  static_assert(detail::PacketQuery<Query, WideKernels, Leaves>, "the packet walks take a PacketQuery (query_protocol.h)");
  if (bvh.root == wide_ref::kEmptyRef || (rays.active & static_cast<std::uint32_t>((std::uint64_t{1} << K) - 1u)) == 0) return 0;
  PreparedPacket<K> prep;
  prep.rays = rays;
  detail::PacketSetup<K> setup;
  screen_inline(prep.rays, setup);
  if (setup.valid == 0) return 0;
  PacketKernels<Arch, Test, K, W>::prepare(prep.rays, prep);
  // (A tree that is one leaf gains nothing from the frustum's set-up.)
  const bool frustum = setup.walk == detail::PacketWalk::frustum ||
                       (setup.walk == detail::PacketWalk::spread_frustum && detail::spread_frustum<Query>());
  if (frustum && !(bvh.root & wide_ref::kLeafBit)) return trace_frustum(bvh, prep, setup, query);
  if (setup.walk == detail::PacketWalk::mixed_octants) return trace_packet<Query, false, false>(bvh, prep, setup, query);
  if constexpr (detail::kFusedLanes<Arch> || !Query::kNearFirst)
    if (setup.walk != detail::PacketWalk::one_octant) return trace_packet<Query, true, true>(bvh, prep, setup, query);
  return trace_packet<Query, true, false>(bvh, prep, setup, query);
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
std::uint32_t WideKernels<Arch, Test, Robust, PK>::walk_instances(const InstanceView& top, const RayPacket<K>& rays,
                                                              InstancePacketVisit visit, InstanceWalk mode) {
  if (mode == InstanceWalk::any) {
    detail::InstancesPacket<WideKernels, true> query{visit};
    query.hit = trace_packet_query(top, rays, query);
    return query.hit;
  }
  detail::InstancesPacket<WideKernels, false> query{visit};
  trace_packet_query(top, rays, query);
  return query.hit;
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
void WideKernels<Arch, Test, Robust, PK>::intersect(const View& bvh, const RayPacket<K>& rays, HitPacket<K>& hits) {
  detail::ClosestHitPacket<WideKernels> query{hits};
  trace_packet_query(bvh, rays, query);
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
std::uint32_t WideKernels<Arch, Test, Robust, PK>::occluded(const View& bvh, const RayPacket<K>& rays) {
  detail::AnyHitPacket<WideKernels> query;
  return trace_packet_query(bvh, rays, query);
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
void WideKernels<Arch, Test, Robust, PK>::all_hits(const View& bvh, const RayPacket<K>& rays, std::vector<Hit>* out) {
  auto sink = [out](int lane, std::uint32_t prim, float t, float u, float v) { append_hit(out[lane], Hit{t, u, v, prim}); };
  detail::AllHitsPacket<WideKernels, decltype(sink)> query{sink};
  trace_packet_query(bvh, rays, query);
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
void WideKernels<Arch, Test, Robust, PK>::screen(RayPacket<K>& rays, detail::PacketSetup<K>& setup) {
  screen_inline(rays, setup);
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
void WideKernels<Arch, Test, Robust, PK>::screen_inline(RayPacket<K>& rays, detail::PacketSetup<K>& setup) {
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
    // Finite: x - x is 0, NaN for Inf and NaN, so the sum of the six is 0 only when all are
    // finite (summed as a tree: one compare instead of a chain of six). Not NaN: x == x.
    const B finite = (((ox - ox) + (oy - oy)) + ((oz - oz) + (dx - dx))) + ((dy - dy) + (dz - dz));
    const M ok = (detail::mask_from_bits<Arch>((rays.active >> o) & kChunkBits) & (finite == zero)) &
                 ((tmin == tmin) & (tmax == tmax));
    // The oracle's reciprocal (1 / ±0 = ±inf).
    const B ix = B(1.0f) / dx, iy = B(1.0f) / dy, iz = B(1.0f) / dz;
    ix.store_aligned(setup.inv[0] + o);
    iy.store_aligned(setup.inv[1] + o);
    iz.store_aligned(setup.inv[2] + o);
    const std::uint32_t okb = detail::bits_from_mask<Arch>(ok);
    valid |= okb << o;
    // The oracle's octant, the sign of 1 / d: d's sign bit (-0 included), read from d so
    // that it need not wait for the division.
    negx |= (detail::sign_bits<Arch>(dx) & okb) << o;
    negy |= (detail::sign_bits<Arch>(dy) & okb) << o;
    negz |= (detail::sign_bits<Arch>(dz) & okb) << o;
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
  setup.walk = !one_octant     ? detail::PacketWalk::mixed_octants
               : zeros != 0        ? detail::PacketWalk::one_octant
               : other_origin == 0 ? detail::PacketWalk::frustum
                                   : detail::PacketWalk::spread_frustum;
}

}  // namespace volley::simd
