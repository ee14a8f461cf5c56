// The frustum walk of a coherent packet (one octant; one origin, or origins that differ
// where the query asks, PacketWalk::spread_frustum): one interval slab test
// per node for the whole packet, the oracle's per-lane test at leaves, whose triangles go
// to the query (queries.h).
#pragma once
#include <bit>
#include <cstdint>

#include "simd/wide/node_lanes.h"
#include "simd/wide/packet_family.h"
#include "simd/wide/packet_lanes.h"
#include "simd/wide/query_protocol.h"
#include "simd/wide/stack.h"

namespace volley::simd {

// Frustum traversal of a coherent packet (the interval form of Reshetov et al., "Multi-level
// ray tracing algorithm", SIGGRAPH 2005; Embree's coherent mode): the slab distances of all
// lanes are bounded by interval arithmetic on [min, max] of origins and reciprocal
// directions, so one 8-wide test per node answers "may any lane hit this child?".
//
// The family's test (PacketFamily::maybe, packet_family.h, where it is argued) passes a
// child whenever some lane's own padded test would. Leaves are tested per lane (the
// oracle's test exactly, against each lane's own tfar) to pick the lanes handed to the
// block kernels, and every subtree popped is tested per lane again, against tfar as the hits since its push
// have left it: a subtree no lane enters is skipped, one that few lanes enter
// (kPacketSwitchLanes or fewer) goes to the single-ray walk lane by lane, as in the per-lane
// walk. Without that second test the frustum opened twice the leaves on the kitchen's
// primary rays (perf/reports/traversal.md).
template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query, class Leaves>
std::uint32_t WideKernels<Arch, Test, Robust, PK>::trace_frustum(const WideView<Leaves>& bvh, PreparedPacket<K>& prep,
                                                             const detail::PacketSetup<K>& setup, Query& query) {
  using V8 = detail::Lanes8<Arch>;
  using Item = detail::FrustumItem<Arch>;
  const std::uint32_t valid = setup.valid;
  const float pad1 = Robust ? core::kSlabExitPad : 1.0f;

  // Per-lane rays (for the leaf box tests) and the packet's intervals. No lane has a zero
  // direction component here, so the lanes' tests take the fused form (kFusedLanes).
  detail::PacketLanes<Arch, K> lanes(prep.rays, setup, query);
  constexpr bool kFused = detail::kFusedLanes<Arch>;
  using FusedLanes = typename detail::PacketLanes<Arch, K>::Fused;
  [[maybe_unused]] const FusedLanes fused = lanes.template fuse_if<kFused>(pad1, Robust);
  const detail::PacketFamily<Arch, K> family(lanes, valid, pad1);
  float far_hi = lanes.far_max();
  // The lanes whose own test enters child j of `node` (leaves, popped subtrees).
  const auto lanes_entering = [&](const WideNode<N>& node, std::uint32_t j) {
    return lanes.template lanes_entering<kFused>(fused, node, static_cast<int>(j), family.np, detail::FloatB<Arch>(pad1));
  };

  Item stack[detail::kWideStack];
  int size = 0;
  std::uint32_t finished = 0;
  Item cur{bvh.root, 0.0f, valid, wide_ref::kEmptyRef, 0};
  for (;;) {
    // The lanes that enter `cur` now (each against its own tfar, which hits since the push
    // may have lowered): none, skip it; few, the single-ray walk takes them from here.
    std::uint32_t live = cur.lanes & ~finished;
    if (detail::lanes_on_pop<Query>() && live != 0 && cur.parent != wide_ref::kEmptyRef)
      live &= lanes_entering(wide_ref::node_at(bvh.nodes, cur.parent), cur.slot);
    if (live == 0) {
      // Skipped: no lane reaches it any more.
    } else if (detail::lanes_on_pop<Query>() && std::popcount(live) <= kPacketSwitchLanes) {
      finished |= lanes.hand_off(live, [&](int i, float& far) { return query.single(bvh, prep, setup, cur.ref, i, far); });
      if (finished == valid) return finished;
      far_hi = lanes.far_max();
    } else if (!(cur.ref & wide_ref::kLeafBit)) {
      // Interior: the interval slab test of all eight children; the entered ones pushed far to
      // near (the top is next), a leaf only for the lanes whose own test enters its box.
      const WideNode<N>& node = wide_ref::node_at(bvh.nodes, cur.ref);
      typename V8::V entry;
      std::uint32_t bits = family.maybe(node, V8::set1(far_hi), entry);
      alignas(32) float dist[8];
      if (bits != 0) V8::store(dist, entry);
      for (const int base = size; bits != 0; bits &= bits - 1) {
        const std::uint32_t j = static_cast<std::uint32_t>(std::countr_zero(bits));
        const std::uint32_t child = node.child[j];
        std::uint32_t child_lanes = valid & ~finished;
        if (child & wide_ref::kLeafBit) {
          child_lanes &= lanes_entering(node, j);
          if (child_lanes == 0) continue;
          wide_ref::request_leaf(bvh.blocks, child);
        } else {
          wide_ref::request_node(bvh.nodes, child);
        }
        detail::insert_far_to_near(stack, size, base, Item{child, dist[j], child_lanes, cur.ref, j});
      }
    } else if (const std::uint32_t count = wide_ref::leaf_count(cur.ref); count != 0) {
      // Leaf: its blocks to the query, for the lanes that enter its box.
      const detail::LanesStep step = query.leaf(prep, bvh.blocks + wide_ref::leaf_first(cur.ref), count, live, lanes.tfar);
      finished |= step.finished;
      if (step.finished != 0 && finished == valid) return finished;
      if (step.narrowed) far_hi = lanes.far_max();
    }
    // The next subtree some lane may still reach before its tfar.
    if (!detail::pop_within<true>(stack, size, far_hi * pad1, cur)) return finished;
  }
}

}  // namespace volley::simd
