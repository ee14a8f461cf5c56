// The per-lane packet walk: each node tested per lane, subtrees with few active lanes
// handed to the single-ray walk, leaves to the query (queries.h).
#pragma once
#include <bit>
#include <cstdint>
#include <limits>

#include "simd/wide/compress.h"
#include "simd/wide/node_lanes.h"
#include "simd/wide/packet_family.h"
#include "simd/wide/packet_lanes.h"
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
  using B = detail::FloatB<Arch>;
  using M = detail::MaskB<Arch>;
  static_assert(B::size == L, "kLanes<Arch> must be the float lane count");
  constexpr int C = K / L;  // chunks of L lanes
  const RayPacket<K>& rays = prep.rays;
  const std::uint32_t valid = setup.valid;
  const float kNaN = std::numeric_limits<float>::quiet_NaN();
  const B pad(Robust ? core::kSlabExitPad : 1.0f);

  // Any hit: a lane's upper end only falls when the lane finishes, so whether it is active
  // in a stacked subtree is decided at the push (its entry bits), not re-tested at the pop.
  constexpr bool kBits = !Query::kNearFirst;
  // Any hit with one lane per child (AVX2, kLaneByLane): each node is tested lane by lane
  // against all its children (PacketLanes::lanes_enter) instead of child by child for each
  // chunk of lanes, the lanes' far ends read from memory (they do not change until a lane
  // finishes, and a finished lane leaves `bits`).
  constexpr bool kLaneNodes = kBits && detail::kLaneByLane<Arch>;

  detail::PacketLanes<Arch, K> lanes(rays, setup, query);
  B* const tfar = lanes.tfar;
  static_assert(Uniform || !NoZero, "no zero direction component: one octant as well");
  constexpr bool Fused = NoZero && detail::kFusedLanes<Arch>;
  using FusedLanes = typename detail::PacketLanes<Arch, K>::Fused;
  [[maybe_unused]] const FusedLanes fused = lanes.template fuse_if<Fused>(Robust ? core::kSlabExitPad : 1.0f, Robust);
  // Uniform octant: the plane arrays of a valid lane's octant; otherwise each lane's octant.
  const int lane0 = std::countr_zero(valid);
  const int np[3] = {Uniform && setup.inv[0][lane0] < 0.0f ? 1 : 0, Uniform && setup.inv[1][lane0] < 0.0f ? 3 : 2,
                     Uniform && setup.inv[2][lane0] < 0.0f ? 5 : 4};
  M negx[C], negy[C], negz[C];
  for (int c = 0; c < C; ++c) {
    negx[c] = lanes.ix[c] < B(0.0f);
    negy[c] = lanes.iy[c] < B(0.0f);
    negz[c] = lanes.iz[c] < B(0.0f);
  }

  alignas(64) float lane_far[kLaneNodes ? K : 1];
  if constexpr (kLaneNodes)
    for (int c = 0; c < C; ++c) tfar[c].store_aligned(lane_far + c * L);
  // The family's shortcut (any hit, one octant and no zero component).
  constexpr bool kFamily = kBits && NoZero;
  [[maybe_unused]] detail::PacketFamily<Arch, K> family;
  [[maybe_unused]] typename detail::Lanes8<Arch>::V family_far;
  if constexpr (kFamily) {
    family = detail::PacketFamily<Arch, K>(lanes, valid, Robust ? core::kSlabExitPad : 1.0f);
    family_far = detail::Lanes8<Arch>::set1(lanes.far_max());
  }
  alignas(64) float stack_dist[kBits ? 1 : detail::kWideStack][K];
  // (kLaneNodes: room for a whole register's store past the last entry.)
  std::uint32_t stack_bits[kBits ? detail::kWideStack + N : 1];
  std::uint32_t stack_ref[detail::kWideStack + N];
  int size = 0;
  std::uint32_t finished = 0;

  // Deferred hand-offs: (subtree, lane), at most kDeferred (more are walked at once).
  constexpr int kDeferred = 32;
  std::uint32_t defer_ref[kDeferred];
  std::uint8_t defer_lane[kDeferred];
  int deferred = 0;
  const bool defer = Uniform && detail::defer_singles<Query>() && bvh.defer_handoffs;
  const auto walk_deferred = [&]() {
    if (deferred == 0) return finished;
    for (int k = 0; k < deferred; ++k) {
      const std::uint32_t ref = defer_ref[k];
      if (ref & wide_ref::kLeafBit) continue;
      const WideNode<N>& node = wide_ref::node_at(bvh.nodes, ref);
      for (int j = 0; j < N && node.child[j] != wide_ref::kEmptyRef; ++j) {
        if (node.child[j] & wide_ref::kLeafBit)
          wide_ref::request_leaf(bvh.blocks, node.child[j]);
        else
          wide_ref::request_node(bvh.nodes, node.child[j]);
      }
    }
    alignas(64) float far_lanes[K];
    for (int c = 0; c < C; ++c) tfar[c].store_aligned(far_lanes + c * L);
    for (int k = 0; k < deferred; ++k) {
      const int i = defer_lane[k];
      if (!(finished & (1u << i)) && query.single(bvh, prep, setup, defer_ref[k], i, far_lanes[i]))
        finished |= 1u << i;
    }
    return finished;
  };

  std::uint32_t cur = bvh.root;
  B cur_dist[C];
  std::uint32_t cur_bits = valid;
  if constexpr (!kBits)
    for (int c = 0; c < C; ++c)
      cur_dist[c] =
          xsimd::select(detail::mask_from_bits<Arch>((valid >> (c * L)) & kChunkBits), lanes.tmin[c], B(kNaN));

  for (;;) {
    // Lanes active in `cur`: entry within the current upper end (NaN: not entered), or the
    // entering lanes less the finished ones (kBits).
    M act[C];
    std::uint32_t bits = 0;
    if constexpr (kBits) {
      bits = cur_bits & ~finished;
      for (int c = 0; c < C; ++c) act[c] = detail::mask_from_bits<Arch>((bits >> (c * L)) & kChunkBits);
    } else {
      for (int c = 0; c < C; ++c) {
        act[c] = cur_dist[c] <= tfar[c] * pad;
        bits |= detail::bits_from_mask<Arch>(act[c]) << (c * L);
      }
      bits &= ~finished;
    }
    if (defer && bits != 0 && std::popcount(bits) <= kPacketSwitchLanes &&
        deferred + std::popcount(bits) <= kDeferred) {
      if (cur & wide_ref::kLeafBit)
        wide_ref::request_leaf(bvh.blocks, cur);
      else
        wide_ref::request_node(bvh.nodes, cur);
      for (std::uint32_t b = bits; b != 0; b &= b - 1) {
        defer_ref[deferred] = cur;
        defer_lane[deferred++] = static_cast<std::uint8_t>(std::countr_zero(b));
      }
      bits = 0;
    }
    if (bits != 0 && std::popcount(bits) <= kPacketSwitchLanes) {
      // Few lanes left: the rest of this subtree one ray at a time.
      alignas(64) float far_lanes[K];
      for (int c = 0; c < C; ++c) tfar[c].store_aligned(far_lanes + c * L);
      for (std::uint32_t b = bits; b != 0; b &= b - 1) {
        const int i = std::countr_zero(b);
        if (query.single(bvh, prep, setup, cur, i, far_lanes[i])) finished |= 1u << i;
      }
      for (int c = 0; c < C; ++c) tfar[c] = B::load_aligned(far_lanes + c * L);
      if (finished == valid) return finished;
      bits = 0;
    }
    if (bits != 0) {
      if (!(cur & wide_ref::kLeafBit)) {
        // Interior: each child against the active lanes.
        const WideNode<N>& node = wide_ref::node_at(bvh.nodes, cur);
        // The family first (any hit, no zero component), where every running lane entered
        // the node (below a node some lane missed, the family, which holds that lane, cannot
        // say that all its rays enter a child): true when every child is settled, `all` then
        // the children every ray of the family enters (the others none may enter), so the
        // lanes' own tests are not needed.
        const auto family_settles = [&](std::uint32_t& all) {
          if constexpr (kFamily) {
            if (bits != (valid & ~finished)) return false;
            typename detail::Lanes8<Arch>::V entry;
            const std::uint32_t maybe = family.maybe(node, family_far, entry);
            all = family.all(node) & maybe;
            return maybe == all;
          } else {
            return false;
          }
        };
        // Child j's entry distance per lane (NaN where a lane does not enter it); whether
        // some lane enters it.
        const auto enter = [&](int j, B* dist, std::uint32_t& entered) {
          bool any = false;
          entered = 0;
          for (int c = 0; c < C; ++c) {
            if (!xsimd::any(act[c])) {
              dist[c] = B(kNaN);
              continue;
            }
            B entry(0.0f), exit(0.0f);  // set below
            if constexpr (Fused) {
              lanes.fused_slabs(fused, node, j, np, c, tfar[c] * pad, entry, exit);
            } else if constexpr (Uniform) {
              lanes.slabs(node, j, np, c, pad, entry, exit);
            } else {
              const B ox = lanes.ox[c], oy = lanes.oy[c], oz = lanes.oz[c];
              const B ix = lanes.ix[c], iy = lanes.iy[c], iz = lanes.iz[c];
              const B lx = (B(node.bounds[0][j]) - ox) * ix, hx = (B(node.bounds[1][j]) - ox) * ix;
              const B ly = (B(node.bounds[2][j]) - oy) * iy, hy = (B(node.bounds[3][j]) - oy) * iy;
              const B lz = (B(node.bounds[4][j]) - oz) * iz, hz = (B(node.bounds[5][j]) - oz) * iz;
              const B tnx = xsimd::select(negx[c], hx, lx), tfx = xsimd::select(negx[c], lx, hx);
              const B tny = xsimd::select(negy[c], hy, ly), tfy = xsimd::select(negy[c], ly, hy);
              const B tnz = xsimd::select(negz[c], hz, lz), tfz = xsimd::select(negz[c], lz, hz);
              // NaN-safe order, as PacketLanes::slabs.
              entry = xsimd::max(tnz, xsimd::max(tny, xsimd::max(tnx, lanes.tmin[c])));
              exit = xsimd::min(tfz, xsimd::min(tfy, xsimd::min(tfx, tfar[c]))) * pad;
            }
            const M hit = act[c] & (entry <= exit);
            // (Computed under kBits too, though unread: without it GCC leaves the any-hit
            // push loop rolled, 13-16% slower; perf/reports/rays.md, "the bit stack".)
            dist[c] = xsimd::select(hit, entry, B(kNaN));
            if constexpr (kBits) entered |= detail::bits_from_mask<Arch>(hit) << (c * L);
            any |= xsimd::any(hit);
          }
          return any;
        };
        if constexpr (kBits) {
          // Any order: every entered child pushed in slot order with no branch on whether
          // it is entered (a coin toss to the predictor; perf/reports/rays.md, "the stream walk"), then the
          // first entered taken as next and the last moved into its place (other orders
          // measured: the same page).
          const int base = size;
          if constexpr (kLaneNodes) {
            // AVX2: the entered children (the used ones some lane enters) stored by one
            // compress each for references and lanes, no loop over the children.
            using I = detail::IntB<Arch>;
            I entered;
            if (std::uint32_t all; family_settles(all))
              entered = xsimd::select(xsimd::bool_cast(detail::mask_from_bits<Arch>(all)),
                                      I(static_cast<std::int32_t>(bits)), I(0));
            else
              entered = detail::PacketLanes<Arch, K>::template lanes_enter<Uniform>(node, np, bits, rays, setup,
                                                                                      lane_far, pad);
            const I refs = I::load_aligned(reinterpret_cast<const std::int32_t*>(node.child));
            const std::uint32_t taken = detail::bits_from_mask<Arch>(
                xsimd::bool_cast(entered != I(0)) &
                xsimd::bool_cast(refs != I(static_cast<std::int32_t>(wide_ref::kEmptyRef))));
            detail::compress_lanes<Arch>(stack_ref + base, refs, taken);
            size += detail::compress_lanes<Arch>(stack_bits + base, entered, taken);
          } else if (std::uint32_t all; family_settles(all)) {
            for (int j = 0; j < N; ++j) {
              const std::uint32_t child = node.child[j];
              if (child == wide_ref::kEmptyRef) break;  // used children come first
              stack_ref[size] = child;
              stack_bits[size] = bits;
              size += (all >> j) & 1u;
            }
          } else {
            for (int j = 0; j < N; ++j) {
              const std::uint32_t child = node.child[j];
              if (child == wide_ref::kEmptyRef) break;  // used children come first
              std::uint32_t entered;
              B dist[C];
              const bool any = enter(j, dist, entered);
              stack_ref[size] = child;
              stack_bits[size] = entered;
              size += any ? 1 : 0;
            }
          }
          if (size != base) {
            --size;
            cur = stack_ref[base];
            cur_bits = stack_bits[base];
            stack_ref[base] = stack_ref[size];
            stack_bits[base] = stack_bits[size];
            continue;
          }
        } else {
          // Nearest first: the first-entered child is the next `cur` unless a later one is
          // entered earlier by some lane; the others pushed.
          std::uint32_t next = wide_ref::kEmptyRef;
          B next_dist[C];
          for (int c = 0; c < C; ++c) next_dist[c] = B(kNaN);
          for (int j = 0; j < N; ++j) {
            const std::uint32_t child = node.child[j];
            if (child == wide_ref::kEmptyRef) break;  // used children come first
            B dist[C];
            std::uint32_t entered;
            if (!enter(j, dist, entered)) continue;
            if (child & wide_ref::kLeafBit) wide_ref::request_leaf(bvh.blocks, child);
            if (next == wide_ref::kEmptyRef) {
              next = child;
              for (int c = 0; c < C; ++c) next_dist[c] = dist[c];
              continue;
            }
            bool nearer = false;
            for (int c = 0; c < C; ++c) nearer = nearer || xsimd::any(dist[c] < next_dist[c]);
            float* slot = stack_dist[size];
            if (nearer) {
              stack_ref[size++] = next;
              for (int c = 0; c < C; ++c) {
                next_dist[c].store_aligned(slot + c * L);
                next_dist[c] = dist[c];
              }
              next = child;
            } else {
              stack_ref[size++] = child;
              for (int c = 0; c < C; ++c) dist[c].store_aligned(slot + c * L);
            }
          }
          if (next != wide_ref::kEmptyRef) {
            cur = next;
            for (int c = 0; c < C; ++c) cur_dist[c] = next_dist[c];
            continue;
          }
        }
      } else {
        // Leaf: its blocks to the query, for the active lanes.
        const std::uint32_t count = wide_ref::leaf_count(cur);
        if (count != 0) {
          const detail::LanesStep step = query.leaf(prep, bvh.blocks + wide_ref::leaf_first(cur), count, bits, tfar);
          finished |= step.finished;
          if (step.finished != 0 && finished == valid) return finished;
        }
      }
    }
    // Pop the next subtree.
    if (size == 0) return walk_deferred();
    --size;
    cur = stack_ref[size];
    if constexpr (kBits)
      cur_bits = stack_bits[size];
    else
      for (int c = 0; c < C; ++c) cur_dist[c] = B::load_aligned(stack_dist[size] + c * L);
  }
}

}  // namespace volley::simd
