// The per-lane packet walk's state and steps (WideKernels::LaneWalk): the node test of each
// child for the active lanes, the child order (nearest first, or the entered children in
// slot order for any hit), the hand-offs to the single-ray walk, deferred or at once.
// trace_packet (packet_walk.h) is the loop over them.
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

// The per-lane walk's state (the packet's lanes, the planes of its octant, the family, the
// deferred hand-offs) and its steps, each forced inline into trace_packet, which keeps the
// loop's state (the current subtree, the stacks, the finished lanes) in its own locals.
template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query, bool Uniform, bool NoZero, class Leaves>
struct WideKernels<Arch, Test, Robust, PK>::LaneWalk {
  using B = detail::FloatB<Arch>;
  using M = detail::MaskB<Arch>;
  static_assert(B::size == L, "kLanes<Arch> must be the float lane count");
  static_assert(Uniform || !NoZero, "no zero direction component: one octant as well");
  static constexpr int C = K / L;  // chunks of L lanes
  // Any hit: a lane's upper end only falls when the lane finishes, so whether it is active
  // in a stacked subtree is decided at the push (its entry bits), not re-tested at the pop.
  static constexpr bool kBits = !Query::kNearFirst;
  // Any hit with one lane per child (AVX2, kLaneByLane): each node is tested lane by lane
  // against all its children (PacketLanes::lanes_enter) instead of child by child for each
  // chunk of lanes, the lanes' far ends read from memory (they do not change until a lane
  // finishes, and a finished lane leaves `bits`).
  static constexpr bool kLaneNodes = kBits && detail::kLaneByLane<Arch>;
  static constexpr bool kFused = NoZero && detail::kFusedLanes<Arch>;
  // The family's shortcut (any hit, one octant and no zero component).
  static constexpr bool kFamily = kBits && NoZero;
  // Deferred hand-offs: (subtree, lane), at most kDeferred (more are walked at once).
  static constexpr int kDeferred = 32;
  static constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

  const WideView<Leaves>& bvh;
  PreparedPacket<K>& prep;
  const detail::PacketSetup<K>& setup;
  Query& query;
  const RayPacket<K>& rays;
  std::uint32_t valid;
  B pad;
  // The lanes apart from the walk's own state: the query's leaves and hand-offs take their
  // far ends by pointer, and an object whose part escapes is kept in memory whole.
  detail::PacketLanes<Arch, K>& lanes;
  typename detail::PacketLanes<Arch, K>::Fused fused;
  // Uniform octant: the plane arrays of a valid lane's octant; otherwise each lane's octant.
  // (np and lane_far, which the lanes' tests take by pointer, are the walk's locals too.)
  int (&np)[3];
  M negx[C], negy[C], negz[C];
  float (&lane_far)[kLaneNodes ? K : 1];
  detail::PacketFamily<Arch, K> family;
  typename detail::Lanes8<Arch>::V family_far;
  std::uint32_t defer_ref[kDeferred];
  std::uint8_t defer_lane[kDeferred];
  int deferred = 0;
  bool defer;

  [[gnu::always_inline]] LaneWalk(const WideView<Leaves>& view, PreparedPacket<K>& prepared,
                                  const detail::PacketSetup<K>& packet_setup, Query& q,
                                  detail::PacketLanes<Arch, K>& packet_lanes, int (&planes)[3],
                                  float (&far_lanes)[kLaneNodes ? K : 1])
      : bvh(view),
        prep(prepared),
        setup(packet_setup),
        query(q),
        rays(prepared.rays),
        valid(packet_setup.valid),
        pad(Robust ? core::kSlabExitPad : 1.0f),
        lanes(packet_lanes),
        fused(lanes.template fuse_if<kFused>(Robust ? core::kSlabExitPad : 1.0f, Robust)),
        np(planes),
        lane_far(far_lanes),
        defer(Uniform && detail::defer_singles<Query>() && view.defer_handoffs) {
    const int lane0 = std::countr_zero(valid);
    np[0] = Uniform && setup.inv[0][lane0] < 0.0f ? 1 : 0;
    np[1] = Uniform && setup.inv[1][lane0] < 0.0f ? 3 : 2;
    np[2] = Uniform && setup.inv[2][lane0] < 0.0f ? 5 : 4;
    for (int c = 0; c < C; ++c) {
      negx[c] = lanes.ix[c] < B(0.0f);
      negy[c] = lanes.iy[c] < B(0.0f);
      negz[c] = lanes.iz[c] < B(0.0f);
    }
    if constexpr (kLaneNodes)
      for (int c = 0; c < C; ++c) lanes.tfar[c].store_aligned(lane_far + c * L);
    if constexpr (kFamily) {
      family = detail::PacketFamily<Arch, K>(lanes, valid, Robust ? core::kSlabExitPad : 1.0f);
      family_far = detail::Lanes8<Arch>::set1(lanes.far_max());
    }
  }

  /// The root's entry distances: the valid lanes' tmin, NaN elsewhere (not kBits).
  [[gnu::always_inline]] void root_entry(B (&dist)[C]) const {
    for (int c = 0; c < C; ++c)
      dist[c] = xsimd::select(detail::mask_from_bits<Arch>((valid >> (c * L)) & kChunkBits), lanes.tmin[c], B(kNaN));
  }

  /// Lanes active in a subtree: entry within the current upper end (NaN: not entered), or
  /// the entering lanes less the finished ones (kBits); as masks in `act`, returned as bits.
  [[gnu::always_inline]] std::uint32_t active(const B (&dist)[C], std::uint32_t entering, std::uint32_t finished,
                                              M (&act)[C]) const {
    std::uint32_t bits = 0;
    if constexpr (kBits) {
      bits = entering & ~finished;
      for (int c = 0; c < C; ++c) act[c] = detail::mask_from_bits<Arch>((bits >> (c * L)) & kChunkBits);
    } else {
      for (int c = 0; c < C; ++c) {
        act[c] = dist[c] <= lanes.tfar[c] * pad;
        bits |= detail::bits_from_mask<Arch>(act[c]) << (c * L);
      }
      bits &= ~finished;
    }
    return bits;
  }

  /// Few lanes in a subtree and room to list them: the subtree requested and its lanes
  /// listed for walk_deferred; returns the lanes left to the packet (none when listed).
  [[gnu::always_inline]] std::uint32_t defer_few(std::uint32_t ref, std::uint32_t bits) {
    if (!defer || bits == 0 || std::popcount(bits) > kPacketSwitchLanes || deferred + std::popcount(bits) > kDeferred)
      return bits;
    if (ref & wide_ref::kLeafBit)
      wide_ref::request_leaf(bvh.blocks, ref);
    else
      wide_ref::request_node(bvh.nodes, ref);
    for (std::uint32_t b = bits; b != 0; b &= b - 1) {
      defer_ref[deferred] = ref;
      defer_lane[deferred++] = static_cast<std::uint8_t>(std::countr_zero(b));
    }
    return 0;
  }

  /// Few lanes left: the rest of subtree `ref` one ray at a time, each finished lane added
  /// to `finished`.
  [[gnu::always_inline]] void hand_off(std::uint32_t ref, std::uint32_t bits, std::uint32_t& finished) {
    alignas(64) float far_lanes[K];
    for (int c = 0; c < C; ++c) lanes.tfar[c].store_aligned(far_lanes + c * L);
    for (std::uint32_t b = bits; b != 0; b &= b - 1) {
      const int i = std::countr_zero(b);
      if (query.single(bvh, prep, setup, ref, i, far_lanes[i])) finished |= 1u << i;
    }
    for (int c = 0; c < C; ++c) lanes.tfar[c] = B::load_aligned(far_lanes + c * L);
  }

  /// The listed hand-offs, after the packet's own walk: every interior start's children
  /// requested first, then each lane not yet finished walked; returns the finished lanes.
  [[gnu::always_inline]] std::uint32_t walk_deferred(std::uint32_t finished) {
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
    for (int c = 0; c < C; ++c) lanes.tfar[c].store_aligned(far_lanes + c * L);
    for (int k = 0; k < deferred; ++k) {
      const int i = defer_lane[k];
      if (!(finished & (1u << i)) && query.single(bvh, prep, setup, defer_ref[k], i, far_lanes[i])) finished |= 1u << i;
    }
    return finished;
  }

  /// The family first (any hit, no zero component), where every running lane entered the
  /// node (below a node some lane missed, the family, which holds that lane, cannot say
  /// that all its rays enter a child): true when every child is settled, `all` then the
  /// children every ray of the family enters (the others none may enter), so the lanes'
  /// own tests are not needed.
  [[gnu::always_inline]] bool family_settles(const WideNode<N>& node, std::uint32_t bits, std::uint32_t finished,
                                             std::uint32_t& all) {
    if constexpr (kFamily) {
      if (bits != (valid & ~finished)) return false;
      typename detail::Lanes8<Arch>::V entry;
      const std::uint32_t maybe = family.maybe(node, family_far, entry);
      all = family.all(node) & maybe;
      return maybe == all;
    } else {
      return false;
    }
  }

  /// Child j's entry distance per lane of `act` (NaN where a lane does not enter it), the
  /// entering lanes as bits (kBits); whether some lane enters it.
  [[gnu::always_inline]] bool enter(const WideNode<N>& node, int j, const M (&act)[C], B (&dist)[C],
                                    std::uint32_t& entered) const {
    bool any = false;
    entered = 0;
    for (int c = 0; c < C; ++c) {
      if (!xsimd::any(act[c])) {
        dist[c] = B(kNaN);
        continue;
      }
      B entry(0.0f), exit(0.0f);  // set below
      if constexpr (kFused) {
        lanes.fused_slabs(fused, node, j, np, c, lanes.tfar[c] * pad, entry, exit);
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
        exit = xsimd::min(tfz, xsimd::min(tfy, xsimd::min(tfx, lanes.tfar[c]))) * pad;
      }
      const M hit = act[c] & (entry <= exit);
      // (Computed under kBits too, though unread: without it GCC leaves the any-hit
      // push loop rolled, 13-16% slower; perf/reports/rays.md, "the bit stack".)
      dist[c] = xsimd::select(hit, entry, B(kNaN));
      if constexpr (kBits) entered |= detail::bits_from_mask<Arch>(hit) << (c * L);
      any |= xsimd::any(hit);
    }
    return any;
  }

  /// Any order (kBits): every entered child pushed in slot order with no branch on whether
  /// it is entered (a coin toss to the predictor; perf/reports/rays.md, "the stream walk"),
  /// each with its entering lanes.
  [[gnu::always_inline]] void push_entered(const WideNode<N>& node, std::uint32_t bits, std::uint32_t finished,
                                           const M (&act)[C], std::uint32_t* stack_ref, std::uint32_t* stack_bits,
                                           int& size) {
    if constexpr (kLaneNodes) {
      // AVX2: the entered children (the used ones some lane enters) stored by one
      // compress each for references and lanes, no loop over the children.
      using I = detail::IntB<Arch>;
      I entered;
      if (std::uint32_t all; family_settles(node, bits, finished, all))
        entered = xsimd::select(xsimd::bool_cast(detail::mask_from_bits<Arch>(all)), I(static_cast<std::int32_t>(bits)),
                                I(0));
      else
        entered =
            detail::PacketLanes<Arch, K>::template lanes_enter<Uniform>(node, np, bits, rays, setup, lane_far, pad);
      const I refs = I::load_aligned(reinterpret_cast<const std::int32_t*>(node.child));
      const std::uint32_t taken =
          detail::bits_from_mask<Arch>(xsimd::bool_cast(entered != I(0)) &
                                       xsimd::bool_cast(refs != I(static_cast<std::int32_t>(wide_ref::kEmptyRef))));
      detail::compress_lanes<Arch>(stack_ref + size, refs, taken);
      size += detail::compress_lanes<Arch>(stack_bits + size, entered, taken);
    } else if (std::uint32_t all; family_settles(node, bits, finished, all)) {
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
        const bool any = enter(node, j, act, dist, entered);
        stack_ref[size] = child;
        stack_bits[size] = entered;
        size += any ? 1 : 0;
      }
    }
  }

  /// Nearest first (not kBits): the first-entered child is `next` unless a later one is
  /// entered earlier by some lane; the others pushed with their distances. Returns whether
  /// some child was entered (`next` and `next_dist` then set).
  [[gnu::always_inline]] bool nearest_first(const WideNode<N>& node, const M (&act)[C], std::uint32_t* stack_ref,
                                            float (*stack_dist)[K], int& size, std::uint32_t& next, B (&next_dist)[C]) {
    next = wide_ref::kEmptyRef;
    for (int c = 0; c < C; ++c) next_dist[c] = B(kNaN);
    for (int j = 0; j < N; ++j) {
      const std::uint32_t child = node.child[j];
      if (child == wide_ref::kEmptyRef) break;  // used children come first
      B dist[C];
      std::uint32_t entered;
      if (!enter(node, j, act, dist, entered)) continue;
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
    return next != wide_ref::kEmptyRef;
  }
};

}  // namespace volley::simd
