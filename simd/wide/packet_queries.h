// The packet queries (the protocol: query_protocol.h): closest hits, every hit and any hit of
// a packet's lanes, and the instances of a top level. Lanes left to the single-ray walk are
// answered by the single-ray queries (queries.h).
#pragma once
#include <bit>
#include <cstdint>
#include <limits>

#include "simd/wide/kernels.h"
#include "simd/wide/queries.h"

namespace volley::simd {

namespace detail {

/// The instances a packet's walk of a top level reaches (WideKernels::walk_instances):
/// each leaf's instance ids to the visitor with the lanes that enter, a lane's bound
/// lowered by its hits (AnyHit: a lane is finished at its first hit). Lanes left to the
/// single-ray walk visit through the same visitor, one lane at a time.
template <class Kernels, bool AnyHit>
struct InstancesPacket {
  using B = typename Kernels::Float;
  static constexpr int K = Kernels::K, L = Kernels::L;
  static constexpr bool kNearFirst = !AnyHit;  // any hit: the node's slot order, as AnyHitPacket
  /// The frustum walk also for spread origins (primary rays from a block of the viewport):
  /// instance boxes are large next to that spread, +7% on instanced primary rays, shadow
  /// and diffuse rays unchanged (perf/reports/instances.md). The lanes are not tested again at each
  /// subtree popped: over the top level's few large boxes that cost 2-4%.
  static constexpr bool kSpreadFrustum = true;
  static constexpr bool kLanesOnPop = false;
  InstancePacketVisit visit;
  std::uint32_t hit = 0;  ///< lanes with a hit so far

  [[gnu::always_inline]] B bound(int, B tmax) const { return tmax; }

  [[gnu::always_inline]] LanesStep leaf(PreparedPacket<K>&, const std::uint32_t* instances, std::uint32_t count,
                                        std::uint32_t lanes, B* tfar) {
    alignas(64) float far[K];
    for (int c = 0; c < K / L; ++c) tfar[c].store_aligned(far + c * L);
    std::uint32_t now = 0;
    for (std::uint32_t k = 0; k < count && lanes != 0; ++k) {
      const std::uint32_t h = visit.visit(visit.context, instances[k], lanes, far);
      now |= h;
      if constexpr (AnyHit) lanes &= ~h;
    }
    if (now == 0) return {0, false};
    hit |= now;
    if constexpr (AnyHit)
      for (std::uint32_t b = now; b != 0; b &= b - 1)
        far[std::countr_zero(b)] = -std::numeric_limits<float>::infinity();
    for (int c = 0; c < K / L; ++c) tfar[c] = B::load_aligned(far + c * L);
    return {AnyHit ? now : 0u, true};
  }

  [[gnu::always_inline]] bool single(const InstanceView& top, const PreparedPacket<K>& prep,
                                     const PacketSetup<K>& setup, std::uint32_t start, int i, float& far) {
    struct Lane {
      InstancesPacket& packet;
      int i;
      float bound;  ///< the lane's bound after the last hit
    } lane{*this, i, far};
    auto one = [](void* context, std::uint32_t instance, float& bound) {
      Lane& l = *static_cast<Lane*>(context);
      alignas(64) float b[K];
      b[l.i] = bound;
      if (l.packet.visit.visit(l.packet.visit.context, instance, 1u << l.i, b) == 0) return false;
      bound = l.bound = b[l.i];
      return true;
    };
    InstancesRay<!AnyHit, AnyHit> q{{one, &lane}, far};
    if (!Kernels::trace_lane(top, prep, setup, i, start, q)) return false;
    hit |= 1u << i;
    far = AnyHit ? -std::numeric_limits<float>::infinity() : lane.bound;
    return AnyHit;
  }
};

/// Closest hits of a packet's lanes (hits.t on entry bounds each lane like tmax).
template <class Kernels>
struct ClosestHitPacket {
  using B = typename Kernels::Float;
  using Packet = typename Kernels::LeafPacket;
  static constexpr int K = Kernels::K, L = Kernels::L;
  static constexpr bool kNearFirst = true;
  /// The frustum walk for packets whose origins differ too (primary rays that start on their
  /// pixels): faster on every scene tried; occlusion keeps the per-lane walk for such
  /// packets, since shadow rays' origins spread over surfaces (perf/reports/traversal.md).
  static constexpr bool kSpreadFrustum = true;
  HitPacket<K>& hits;

  B bound(int o, B tmax) const { return upper_bound<typename Kernels::Isa>(B::load_aligned(hits.t + o), tmax); }

  /// PacketKernels::intersect, a sparse last block's padding untested (last_block_triangles).
  LanesStep leaf(PreparedPacket<K>& prep, const typename Kernels::Block* blocks, std::uint32_t count,
                 std::uint32_t lanes, B* tfar) {
    prep.rays.active = lanes;
    Packet::intersect(prep, blocks, count, hits, last_block_triangles<Kernels>(blocks, count));
    for (int c = 0; c < K / L; ++c) {
      const B ht = B::load_aligned(hits.t + c * L);
      tfar[c] = xsimd::select(ht < tfar[c], ht, tfar[c]);
    }
    return {0, true};
  }

  bool single(const typename Kernels::View& bvh, const PreparedPacket<K>& prep, const PacketSetup<K>& setup,
              std::uint32_t start, int i, float& far) {
    Hit h{hits.t[i], hits.u[i], hits.v[i], hits.prim[i]};
    ClosestHitRay<Kernels> q{h};
    if (Kernels::trace_lane(bvh, prep, setup, i, start, q)) {
      hits.t[i] = h.t, hits.u[i] = h.u, hits.v[i] = h.v, hits.prim[i] = h.prim;
      far = h.t;
    }
    return false;
  }
};

/// Every hit of a packet's lanes by the crossing test: sink(lane, prim, t, u, v) for each;
/// no lane finishes early and no bound falls.
template <class Kernels, class Sink>
struct AllHitsPacket {
  using B = typename Kernels::Float;
  using Packet = typename Kernels::LeafPacket;
  static constexpr int K = Kernels::K, L = Kernels::L;
  static constexpr bool kNearFirst = true;
  Sink& sink;

  B bound(int, B tmax) const { return tmax; }
  LanesStep leaf(PreparedPacket<K>& prep, const typename Kernels::Block* blocks, std::uint32_t count,
                 std::uint32_t lanes, B*) {
    Packet::all(prep, blocks, count, lanes, sink);
    return {0, false};
  }
  bool single(const typename Kernels::View& bvh, const PreparedPacket<K>& prep, const PacketSetup<K>& setup,
              std::uint32_t start, int i, float&) {
    auto one = [this, i](std::uint32_t prim, float t, float u, float v) { sink(i, prim, t, u, v); };
    AllHitsRay<Kernels, decltype(one)> q{one};
    Kernels::trace_lane(bvh, prep, setup, i, start, q);
    return false;
  }
};

/// Any hit of a packet's lanes: a lane is finished at its first hit.
template <class Kernels>
struct AnyHitPacket {
  using B = typename Kernels::Float;
  using Packet = typename Kernels::LeafPacket;
  static constexpr int K = Kernels::K, L = Kernels::L;
  static constexpr bool kNearFirst = false;
  static constexpr bool kDeferSingles = true;

  B bound(int, B tmax) const { return tmax; }

  /// PacketKernels::occluded, a sparse last block's padding untested (last_block_triangles).
  LanesStep leaf(PreparedPacket<K>& prep, const typename Kernels::Block* blocks, std::uint32_t count,
                 std::uint32_t lanes, B* tfar) {
    const std::uint32_t now =
        Packet::occluded(prep, blocks, count, lanes, last_block_triangles<Kernels>(blocks, count));
    if (now == 0) return {0, false};
    for (int c = 0; c < K / L; ++c)
      tfar[c] = xsimd::select(mask_from_bits<typename Kernels::Isa>((now >> (c * L)) & ((1u << L) - 1u)),
                              B(-std::numeric_limits<float>::infinity()), tfar[c]);
    return {now, true};
  }

  bool single(const typename Kernels::View& bvh, const PreparedPacket<K>& prep, const PacketSetup<K>& setup,
              std::uint32_t start, int i, float& far) {
    AnyHitRay<Kernels> q;
    if (!Kernels::trace_lane(bvh, prep, setup, i, start, q)) return false;
    far = -std::numeric_limits<float>::infinity();
    return true;
  }
};

}  // namespace detail

}  // namespace volley::simd
