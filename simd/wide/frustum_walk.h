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
// primary rays (perf/traversal.md).
template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query, class Leaves>
std::uint32_t WideKernels<Arch, Test, Robust, PK>::trace_frustum(const WideView<Leaves>& bvh, PreparedPacket<K>& prep,
                                                             const detail::PacketSetup<K>& setup, Query& query) {
  using V8 = detail::Lanes8<Arch>;
  using B = detail::FloatB<Arch>;
  constexpr int C = K / L;
  const RayPacket<K>& rays = prep.rays;
  const std::uint32_t valid = setup.valid;
  const float pad1 = Robust ? core::kSlabExitPad : 1.0f;

  // Per-lane rays (for the leaf box tests) and the packet's intervals. No lane has a zero
  // direction component here, so the lanes' tests take the fused form (kFusedLanes).
  detail::PacketLanes<Arch, K> lanes(rays, setup, query);
  constexpr bool kFused = detail::kFusedLanes<Arch>;
  using FusedLanes = typename detail::PacketLanes<Arch, K>::Fused;
  [[maybe_unused]] const FusedLanes fused = lanes.template fuse_if<kFused>(pad1, Robust);
  const detail::PacketFamily<Arch, K> family(lanes, valid, pad1);
  const int* const np = family.np;
  float far_hi = lanes.far_max();
  const B padb(pad1);
  // A lane's own test of child j of `node` (leaves, popped subtrees).
  const auto lane_slabs = [&](const WideNode<N>& node, int j, int c, B& e, B& x) {
    if constexpr (kFused)
      lanes.fused_slabs(fused, node, j, np, c, lanes.tfar[c] * padb, e, x);
    else
      lanes.slabs(node, j, np, c, padb, e, x);
  };

  detail::FrustumItem<Arch> stack[detail::kWideStack];
  int size = 0;
  std::uint32_t finished = 0;
  std::uint32_t cur = bvh.root;
  std::uint32_t cur_lanes = valid;
  std::uint32_t cur_parent = wide_ref::kEmptyRef, cur_slot = 0;
  for (;;) {
    // The lanes that enter `cur` now (each against its own tfar, which hits since the push
    // may have lowered): none, skip it; few, the single-ray walk takes them from here.
    std::uint32_t live = cur_lanes & ~finished;
    if (detail::lanes_on_pop<Query>() && live != 0 && cur_parent != wide_ref::kEmptyRef) {
      const WideNode<N>& parent = wide_ref::node_at(bvh.nodes, cur_parent);
      std::uint32_t now = 0;
      for (int c = 0; c < C; ++c) {
        B e, x;
        lane_slabs(parent, static_cast<int>(cur_slot), c, e, x);
        now |= detail::bits_from_mask<Arch>(e <= x) << (c * L);
      }
      live &= now;
    }
    if (live == 0) {
      // Skipped: no lane reaches it any more.
    } else if (detail::lanes_on_pop<Query>() && std::popcount(live) <= kPacketSwitchLanes) {
      alignas(64) float far_lanes[K];
      for (int c = 0; c < C; ++c) lanes.tfar[c].store_aligned(far_lanes + c * L);
      for (std::uint32_t b = live; b != 0; b &= b - 1) {
        const int i = std::countr_zero(b);
        if (query.single(bvh, prep, setup, cur, i, far_lanes[i])) finished |= 1u << i;
      }
      for (int c = 0; c < C; ++c) lanes.tfar[c] = B::load_aligned(far_lanes + c * L);
      if (finished == valid) return finished;
      far_hi = lanes.far_max();
    } else if (!(cur & wide_ref::kLeafBit)) {
      // Interior: the interval slab test of all eight children.
      const WideNode<N>& node = wide_ref::node_at(bvh.nodes, cur);
      typename V8::V entry;
      std::uint32_t bits = family.maybe(node, V8::set1(far_hi), entry);
      if (bits != 0) {
        alignas(32) float dist[8];
        V8::store(dist, entry);
        // Push the hit children far to near (insertion by entry bound); the top is next.
        const int base = size;
        for (; bits != 0; bits &= bits - 1) {
          const int j = std::countr_zero(bits);
          const std::uint32_t child = node.child[j];
          std::uint32_t child_lanes = valid & ~finished;
          if (child & wide_ref::kLeafBit) {
            // A leaf: the oracle's box test per lane, against each lane's own tfar.
            child_lanes = 0;
            for (int c = 0; c < C; ++c) {
              B e, x;
              lane_slabs(node, j, c, e, x);
              child_lanes |= detail::bits_from_mask<Arch>(e <= x) << (c * L);
            }
            child_lanes &= valid & ~finished;
            if (child_lanes == 0) continue;
            wide_ref::request_leaf(bvh.blocks, child);
          } else {
            wide_ref::request_node(bvh.nodes, child);
          }
          int k = size++;
          for (; k > base && stack[k - 1].entry < dist[j]; --k) stack[k] = stack[k - 1];
          stack[k] = {child, dist[j], child_lanes, cur, static_cast<std::uint32_t>(j)};
        }
      }
    } else {
      // Leaf: its blocks to the query, for the lanes that enter its box.
      const std::uint32_t count = wide_ref::leaf_count(cur);
      if (count != 0) {
        const detail::LanesStep step = query.leaf(prep, bvh.blocks + wide_ref::leaf_first(cur), count, live, lanes.tfar);
        finished |= step.finished;
        if (step.finished != 0 && finished == valid) return finished;
        if (step.narrowed) far_hi = lanes.far_max();
      }
    }
    // Pop the next subtree some lane may still reach before its tfar.
    for (;;) {
      if (size == 0) return finished;
      --size;
      if (stack[size].entry <= far_hi * pad1) break;
    }
    cur = stack[size].ref;
    cur_lanes = stack[size].lanes;
    cur_parent = stack[size].parent;
    cur_slot = stack[size].slot;
  }
}

}  // namespace volley::simd
