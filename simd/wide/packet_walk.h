// The per-lane packet walk: each node tested per lane, subtrees with few active lanes
// handed to the single-ray walk, leaves to the query (queries.h).
#pragma once
#include <bit>
#include <cstdint>
#include <limits>

#include "simd/wide/lane_walk.h"
#include "simd/wide/query_protocol.h"
#include "simd/wide/stack.h"

namespace volley::simd {

// Packet traversal after Embree's BVHNIntersectorKHybrid: a stack of (subtree, entry
// distance per lane), NaN for lanes that did not hit the subtree's box; a lane is active in
// a subtree while its entry distance is within its current tmax (padded). Children are
// visited nearest first by the heuristic "any lane enters it before the current best",
// or, for a query with kNearFirst = false (any hit), in slot order as single rays; such a
// query's stack holds each subtree's entering lanes as bits instead of distances; where a
// register holds one lane per child (AVX2), such a query tests each node lane by lane
// against all its children (PacketLanes::lanes_enter) instead of child by child.
// Deferred hand-offs (a view that defers them, a query that allows it, one octant): a
// subtree left to single rays is requested and listed, and the listed walks run after the
// packet's own, each interior start's children requested first, so that the misses of a
// tree larger than the caches overlap the packet's walk and one another instead of
// following one another. Packets of mixed octants (bounce and ambient-occlusion rays, most
// of which are blocked) walk them at once: deferred, a lane that a hand-off would have
// finished stays in the packet's walk, which costs more than the misses (perf/reports/rays.md,
// "deferred hand-offs on trees past the caches").
// Uniform: every valid lane has the same octant, so the near and far planes are picked once
// for the packet instead of per lane. NoZero: no lane has a zero direction component
// either: on AVX-512 each slab distance is one fused operation (PacketLanes::fused_slabs);
// an any-hit walk asks the packet's interval family first at each node that all its
// running lanes entered, and where the family settles every child (each entered by all the
// packet's rays or by none) the lanes' own tests are skipped (PacketFamily).
template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query, bool Uniform, bool NoZero, class Leaves>
std::uint32_t WideKernels<Arch, Test, Robust, PK>::trace_packet(const WideView<Leaves>& bvh, PreparedPacket<K>& prep,
                                                            const detail::PacketSetup<K>& setup, Query& query) {
  using Walk = LaneWalk<Query, Uniform, NoZero, Leaves>;
  using B = typename Walk::B;
  using M = typename Walk::M;
  constexpr int C = Walk::C;
  constexpr bool kBits = Walk::kBits;
  detail::PacketLanes<Arch, K> lanes(prep.rays, setup, query);
  int np[3];
  alignas(64) float lane_far[Walk::kLaneNodes ? K : 1];
  Walk w(bvh, prep, setup, query, lanes, np, lane_far);
  alignas(64) float stack_dist[kBits ? 1 : detail::kWideStack][K];
  // (kLaneNodes: room for a whole register's store past the last entry.)
  std::uint32_t stack_bits[kBits ? detail::kWideStack + N : 1];
  std::uint32_t stack_ref[detail::kWideStack + N];
  int size = 0;
  std::uint32_t finished = 0;

  std::uint32_t cur = bvh.root;
  B cur_dist[C];
  std::uint32_t cur_bits = w.valid;
  if constexpr (!kBits) w.root_entry(cur_dist);

  for (;;) {
    M act[C];
    std::uint32_t bits = w.defer_few(cur, w.active(cur_dist, cur_bits, finished, act));
    if (bits != 0 && std::popcount(bits) <= kPacketSwitchLanes) {
      w.hand_off(cur, bits, finished);
      if (finished == w.valid) return finished;
      bits = 0;
    }
    if (bits != 0) {
      if (!(cur & wide_ref::kLeafBit)) {
        // Interior: each child against the active lanes; the first entered child next.
        const WideNode<N>& node = wide_ref::node_at(bvh.nodes, cur);
        if constexpr (kBits) {
          // The first entered taken as next and the last moved into its place (other
          // orders measured: perf/reports/rays.md, "the stream walk").
          const int base = size;
          w.push_entered(node, bits, finished, act, stack_ref, stack_bits, size);
          if (size != base) {
            --size;
            cur = stack_ref[base];
            cur_bits = stack_bits[base];
            stack_ref[base] = stack_ref[size];
            stack_bits[base] = stack_bits[size];
            continue;
          }
        } else {
          std::uint32_t next;
          B next_dist[C];
          if (w.nearest_first(node, act, stack_ref, stack_dist, size, next, next_dist)) {
            cur = next;
            for (int c = 0; c < C; ++c) cur_dist[c] = next_dist[c];
            continue;
          }
        }
      } else if (const std::uint32_t count = wide_ref::leaf_count(cur); count != 0) {
        // Leaf: its blocks to the query, for the active lanes.
        const detail::LanesStep step =
            query.leaf(prep, bvh.blocks + wide_ref::leaf_first(cur), count, bits, lanes.tfar);
        finished |= step.finished;
        if (step.finished != 0 && finished == w.valid) return finished;
      }
    }
    // Pop the next subtree.
    if (size == 0) return w.walk_deferred(finished);
    --size;
    cur = stack_ref[size];
    if constexpr (kBits)
      cur_bits = stack_bits[size];
    else
      for (int c = 0; c < C; ++c) cur_dist[c] = B::load_aligned(stack_dist[size] + c * L);
  }
}

}  // namespace volley::simd
