// The per-lane packet walk: each node tested per lane, subtrees with few active lanes
// handed to the single-ray walk, leaves to the query (queries.h).
#pragma once
#include <bit>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "simd/wide/compress.h"
#include "simd/wide/deferred_handoffs.h"
#include "simd/wide/node_lanes.h"
#include "simd/wide/packet_family.h"
#include "simd/wide/packet_lanes.h"
#include "simd/wide/queries.h"
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
// Hand-offs to single rays are deferred (deferred_handoffs.h) for a view that defers them,
// a query that allows it and one octant; packets of mixed octants (bounce and ambient-
// occlusion rays, most of which are blocked) walk them at once: deferred, a lane that a
// hand-off would have finished stays in the packet's walk, which costs more than the
// misses (perf/rays.md, "deferred hand-offs on trees past the caches").
// Uniform: every valid lane has the same octant, so the near and far planes are picked once
// for the packet instead of per lane. NoZero: no lane has a zero direction component
// either: on AVX-512 each slab distance is one fused operation (PacketLanes::fused_slabs);
// an any-hit walk asks the packet's interval family first at each node that all its
// running lanes entered, and where the family settles every child (each entered by all the
// packet's rays or by none) the lanes' own tests are skipped (PacketFamily).
/// The per-lane walk of one packet, in its named steps: set-up (the constructor), the lanes
/// active in the current subtree, hand-offs of few lanes to the single-ray walk (now, or
/// deferred), the node test of a child, the child order (any order, or nearest first), the
/// leaf, the pop, each inlined into run().
template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query, bool Uniform, bool NoZero, class Leaves>
class WideKernels<Arch, Test, Robust, PK>::PacketWalker {
  using B = detail::FloatB<Arch>;
  using M = detail::MaskB<Arch>;
  using Lanes = detail::PacketLanes<Arch, K>;
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
  // Deferred hand-offs (at most DeferredHandoffs::kMax; more are walked at once): only for
  // one octant and a query that allows them.
  static constexpr bool kMayDefer = Uniform && detail::defer_singles<Query>();
  // The fused lanes, the family and its far end where the walk uses them, else nothing
  // (an unused member would still be set up: the walker is too large to live in registers).
  struct Unused {};
  struct FamilyFarEnd {
    typename detail::Lanes8<Arch>::V v;
  };
  using Fused = std::conditional_t<kFused, typename Lanes::Fused, Unused>;
  using Family = std::conditional_t<kFamily, detail::PacketFamily<Arch, K>, Unused>;
  using FamilyFar = std::conditional_t<kFamily, FamilyFarEnd, Unused>;

  /// What the walk changes as it goes, kept apart from the walker so that it stays in
  /// registers (the walker, with its stacks, is too large to): the current subtree and its
  /// lanes' entry distances or bits, the stack's size, the finished lanes, the deferred count.
  struct Position {
    std::uint32_t cur;
    std::uint32_t cur_bits;
    int size;
    std::uint32_t finished;
    int deferred;
    B cur_dist[C];
  };

 public:
  /// `lanes`: the packet's lanes (PacketLanes of prep.rays), apart from the walker since
  /// the leaves are handed their far ends by address.
  [[gnu::always_inline]] PacketWalker(const WideView<Leaves>& bvh, PreparedPacket<K>& prep,
                                      const detail::PacketSetup<K>& setup, Query& query, Lanes& lanes)
      : bvh_(bvh), prep_(prep), setup_(setup), query_(query), valid_(setup.valid),
        pad_(Robust ? core::kSlabExitPad : 1.0f), lanes_(lanes), fused_(fused_of(lanes)),
        defer_(kMayDefer && bvh.defer_handoffs), family_(family_of(lanes, setup.valid)), family_far_(far_of(lanes)) {
    // Uniform octant: the plane arrays of a valid lane's octant; otherwise each lane's octant.
    const int lane0 = std::countr_zero(valid_);
    np_[0] = Uniform && setup.inv[0][lane0] < 0.0f ? 1 : 0;
    np_[1] = Uniform && setup.inv[1][lane0] < 0.0f ? 3 : 2;
    np_[2] = Uniform && setup.inv[2][lane0] < 0.0f ? 5 : 4;
    for (int c = 0; c < C; ++c) {
      neg_[c][0] = lanes_.ix[c] < B(0.0f);
      neg_[c][1] = lanes_.iy[c] < B(0.0f);
      neg_[c][2] = lanes_.iz[c] < B(0.0f);
    }
    if constexpr (kLaneNodes)
      for (int c = 0; c < C; ++c) lanes_.tfar[c].store_aligned(lane_far_ + c * L);
  }

  /// The walk: returns the lanes the query finished.
  [[gnu::always_inline]] std::uint32_t run() {
    Position at;
    at.cur = bvh_.root;
    at.cur_bits = valid_;
    at.size = 0;
    at.finished = 0;
    at.deferred = 0;
    if constexpr (!kBits)
      for (int c = 0; c < C; ++c)
        at.cur_dist[c] = xsimd::select(detail::mask_from_bits<Arch>((valid_ >> (c * L)) & kChunkBits), lanes_.tmin[c],
                                       B(kNaN));
    for (;;) {
      M act[C];
      std::uint32_t bits = active_lanes(at, act);
      if (kMayDefer && defer_ && bits != 0 && std::popcount(bits) <= kPacketSwitchLanes &&
          at.deferred + std::popcount(bits) <= detail::DeferredHandoffs::kMax) {
        deferred_.add(bvh_, at.cur, bits, at.deferred);
        bits = 0;
      }
      if (bits != 0 && std::popcount(bits) <= kPacketSwitchLanes) {
        if (walk_singles(at, bits)) return at.finished;
        bits = 0;
      }
      if (bits != 0) {
        if (!(at.cur & wide_ref::kLeafBit)) {
          const WideNode<N>& node = wide_ref::node_at(bvh_.nodes, at.cur);
          if constexpr (kBits) {
            if (push_entered(at, node, act, bits)) continue;
          } else if (take_nearest(at, node, act)) {
            continue;
          }
        } else if (leaf(at, bits)) {
          return at.finished;
        }
      }
      if (!pop(at)) return walk_deferred(at);
    }
  }

 private:
  static constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

  [[gnu::always_inline]] static Fused fused_of(const Lanes& lanes) {
    if constexpr (kFused)
      return lanes.fuse(Robust ? core::kSlabExitPad : 1.0f, Robust);
    else
      return Fused{};
  }
  [[gnu::always_inline]] static Family family_of(const Lanes& lanes, std::uint32_t valid) {
    if constexpr (kFamily)
      return Family(lanes, valid, Robust ? core::kSlabExitPad : 1.0f);
    else
      return Family{};
  }
  [[gnu::always_inline]] static FamilyFar far_of(const Lanes& lanes) {
    if constexpr (kFamily)
      return FamilyFar{detail::Lanes8<Arch>::set1(lanes.far_max())};
    else
      return FamilyFar{};
  }

  /// Lanes active in the current subtree: entry within the current upper end (NaN: not
  /// entered), or the entering lanes less the finished ones (kBits); as masks in `act`.
  [[gnu::always_inline]] std::uint32_t active_lanes(const Position& at, M act[C]) const {
    std::uint32_t bits = 0;
    if constexpr (kBits) {
      bits = at.cur_bits & ~at.finished;
      for (int c = 0; c < C; ++c) act[c] = detail::mask_from_bits<Arch>((bits >> (c * L)) & kChunkBits);
    } else {
      for (int c = 0; c < C; ++c) {
        act[c] = at.cur_dist[c] <= lanes_.tfar[c] * pad_;
        bits |= detail::bits_from_mask<Arch>(act[c]) << (c * L);
      }
      bits &= ~at.finished;
    }
    return bits;
  }

  /// Few lanes left: the rest of the current subtree one ray at a time. Returns whether
  /// every valid lane has finished.
  [[gnu::always_inline]] bool walk_singles(Position& at, std::uint32_t bits) {
    alignas(64) float far_lanes[K];
    for (int c = 0; c < C; ++c) lanes_.tfar[c].store_aligned(far_lanes + c * L);
    for (std::uint32_t b = bits; b != 0; b &= b - 1) {
      const int i = std::countr_zero(b);
      if (query_.single(bvh_, prep_, setup_, at.cur, i, far_lanes[i])) at.finished |= 1u << i;
    }
    for (int c = 0; c < C; ++c) lanes_.tfar[c] = B::load_aligned(far_lanes + c * L);
    return at.finished == valid_;
  }

  /// The deferred hand-offs, each interior start's children requested first; returns the
  /// lanes finished.
  [[gnu::always_inline]] std::uint32_t walk_deferred(Position& at) {
    if (!kMayDefer || at.deferred == 0) return at.finished;
    deferred_.request_children(bvh_, at.deferred);
    alignas(64) float far_lanes[K];
    for (int c = 0; c < C; ++c) lanes_.tfar[c].store_aligned(far_lanes + c * L);
    for (int k = 0; k < at.deferred; ++k) {
      const int i = deferred_.lane[k];
      if (!(at.finished & (1u << i)) && query_.single(bvh_, prep_, setup_, deferred_.ref[k], i, far_lanes[i]))
        at.finished |= 1u << i;
    }
    return at.finished;
  }

  /// The node test of child j: its entry distance per lane in `dist` (NaN where a lane
  /// does not enter it), the entering lanes in `entered` (kBits); whether some lane enters.
  [[gnu::always_inline]] bool enter(const WideNode<N>& node, int j, const M act[C], B* dist,
                                    std::uint32_t& entered) const {
    bool any = false;
    entered = 0;
    for (int c = 0; c < C; ++c) {
      if (!xsimd::any(act[c])) {
        dist[c] = B(kNaN);
        continue;
      }
      B entry(0.0f), exit(0.0f);  // set below
      if constexpr (kFused)
        lanes_.fused_slabs(fused_, node, j, np_, c, lanes_.tfar[c] * pad_, entry, exit);
      else if constexpr (Uniform)
        lanes_.slabs(node, j, np_, c, pad_, entry, exit);
      else
        lanes_.slabs_any_octant(node, j, neg_[c], c, pad_, entry, exit);
      const M hit = act[c] & (entry <= exit);
      // (Computed under kBits too, though unread: without it GCC leaves the any-hit
      // push loop rolled, 13-16% slower; perf/rays.md, "the bit stack".)
      dist[c] = xsimd::select(hit, entry, B(kNaN));
      if constexpr (kBits) entered |= detail::bits_from_mask<Arch>(hit) << (c * L);
      any |= xsimd::any(hit);
    }
    return any;
  }

  /// The family first (any hit, no zero component), where every running lane entered the
  /// node (below a node some lane missed, the family, which holds that lane, cannot say
  /// that all its rays enter a child): true when every child is settled, `all` then the
  /// children every ray of the family enters (the others none may enter), so the lanes'
  /// own tests are not needed.
  [[gnu::always_inline]] bool family_settles(const Position& at, const WideNode<N>& node, std::uint32_t bits,
                                             std::uint32_t& all) const {
    if constexpr (kFamily)
      return bits == (valid_ & ~at.finished) && family_.settles(node, family_far_.v, all);
    else
      return false;
  }

  /// Child order for any hit: every entered child pushed in slot order with no branch on
  /// whether it is entered (a coin toss to the predictor; perf/rays.md, "the stream walk"),
  /// then the first entered taken as the current subtree and the last moved into its place
  /// (other orders measured: the same page). Returns whether some child was entered.
  [[gnu::always_inline]] bool push_entered(Position& at, const WideNode<N>& node, const M act[C], std::uint32_t bits) {
    const int base = at.size;
    if constexpr (kLaneNodes) {
      // AVX2: the entered children (the used ones some lane enters) stored by one
      // compress each for references and lanes, no loop over the children.
      using I = detail::IntB<Arch>;
      I entered;
      if (std::uint32_t all; family_settles(at, node, bits, all))
        entered = xsimd::select(xsimd::bool_cast(detail::mask_from_bits<Arch>(all)), I(static_cast<std::int32_t>(bits)),
                                I(0));
      else
        entered = Lanes::template lanes_enter<Uniform>(node, np_, bits, prep_.rays, setup_, lane_far_, pad_);
      const I refs = I::load_aligned(reinterpret_cast<const std::int32_t*>(node.child));
      const std::uint32_t taken =
          detail::bits_from_mask<Arch>(xsimd::bool_cast(entered != I(0)) &
                                       xsimd::bool_cast(refs != I(static_cast<std::int32_t>(wide_ref::kEmptyRef))));
      detail::compress_lanes<Arch>(stack_ref_ + base, refs, taken);
      at.size += detail::compress_lanes<Arch>(stack_bits_ + base, entered, taken);
    } else if (std::uint32_t all; family_settles(at, node, bits, all)) {
      for (int j = 0; j < N; ++j) {
        const std::uint32_t child = node.child[j];
        if (child == wide_ref::kEmptyRef) break;  // used children come first
        stack_ref_[at.size] = child;
        stack_bits_[at.size] = bits;
        at.size += (all >> j) & 1u;
      }
    } else {
      for (int j = 0; j < N; ++j) {
        const std::uint32_t child = node.child[j];
        if (child == wide_ref::kEmptyRef) break;  // used children come first
        std::uint32_t entered;
        B dist[C];
        const bool any = enter(node, j, act, dist, entered);
        stack_ref_[at.size] = child;
        stack_bits_[at.size] = entered;
        at.size += any ? 1 : 0;
      }
    }
    if (at.size == base) return false;
    --at.size;
    at.cur = stack_ref_[base];
    at.cur_bits = stack_bits_[base];
    stack_ref_[base] = stack_ref_[at.size];
    stack_bits_[base] = stack_bits_[at.size];
    return true;
  }

  /// Child order nearest first: the first-entered child is the next current subtree unless
  /// a later one is entered earlier by some lane; the others pushed. Returns whether some
  /// child was entered.
  [[gnu::always_inline]] bool take_nearest(Position& at, const WideNode<N>& node, const M act[C]) {
    std::uint32_t next = wide_ref::kEmptyRef;
    B next_dist[C];
    for (int c = 0; c < C; ++c) next_dist[c] = B(kNaN);
    for (int j = 0; j < N; ++j) {
      const std::uint32_t child = node.child[j];
      if (child == wide_ref::kEmptyRef) break;  // used children come first
      B dist[C];
      std::uint32_t entered;
      if (!enter(node, j, act, dist, entered)) continue;
      if (child & wide_ref::kLeafBit) wide_ref::request_leaf(bvh_.blocks, child);
      if (next == wide_ref::kEmptyRef) {
        next = child;
        for (int c = 0; c < C; ++c) next_dist[c] = dist[c];
        continue;
      }
      bool nearer = false;
      for (int c = 0; c < C; ++c) nearer = nearer || xsimd::any(dist[c] < next_dist[c]);
      float* slot = stack_dist_[at.size];
      if (nearer) {
        stack_ref_[at.size++] = next;
        for (int c = 0; c < C; ++c) {
          next_dist[c].store_aligned(slot + c * L);
          next_dist[c] = dist[c];
        }
        next = child;
      } else {
        stack_ref_[at.size++] = child;
        for (int c = 0; c < C; ++c) dist[c].store_aligned(slot + c * L);
      }
    }
    if (next == wide_ref::kEmptyRef) return false;
    at.cur = next;
    for (int c = 0; c < C; ++c) at.cur_dist[c] = next_dist[c];
    return true;
  }

  /// The leaf: its blocks to the query for the active lanes. Returns whether every valid
  /// lane has finished.
  [[gnu::always_inline]] bool leaf(Position& at, std::uint32_t bits) {
    const std::uint32_t count = wide_ref::leaf_count(at.cur);
    if (count == 0) return false;
    const detail::LanesStep step = query_.leaf(prep_, bvh_.blocks + wide_ref::leaf_first(at.cur), count, bits, lanes_.tfar);
    at.finished |= step.finished;
    return step.finished != 0 && at.finished == valid_;
  }

  /// The next subtree from the stack; false when it is empty.
  [[gnu::always_inline]] bool pop(Position& at) {
    if (at.size == 0) return false;
    --at.size;
    at.cur = stack_ref_[at.size];
    if constexpr (kBits)
      at.cur_bits = stack_bits_[at.size];
    else
      for (int c = 0; c < C; ++c) at.cur_dist[c] = B::load_aligned(stack_dist_[at.size] + c * L);
    return true;
  }

  const WideView<Leaves>& bvh_;
  PreparedPacket<K>& prep_;
  const detail::PacketSetup<K>& setup_;
  Query& query_;
  const std::uint32_t valid_;
  const B pad_;
  Lanes& lanes_;
  [[maybe_unused]] const Fused fused_;
  const bool defer_;
  [[maybe_unused]] const Family family_;
  [[maybe_unused]] const FamilyFar family_far_;
  int np_[3];
  M neg_[C][3];  // each chunk's signs of ix, iy, iz
  alignas(64) float lane_far_[kLaneNodes ? K : 1];
  alignas(64) float stack_dist_[kBits ? 1 : detail::kWideStack][K];
  // (kLaneNodes: room for a whole register's store past the last entry.)
  std::uint32_t stack_bits_[kBits ? detail::kWideStack + N : 1];
  std::uint32_t stack_ref_[detail::kWideStack + N];
  detail::DeferredHandoffs deferred_;
};

template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query, bool Uniform, bool NoZero, class Leaves>
std::uint32_t WideKernels<Arch, Test, Robust, PK>::trace_packet(const WideView<Leaves>& bvh, PreparedPacket<K>& prep,
                                                            const detail::PacketSetup<K>& setup, Query& query) {
  detail::PacketLanes<Arch, K> lanes(prep.rays, setup, query);
  PacketWalker<Query, Uniform, NoZero, Leaves> walker(bvh, prep, setup, query, lanes);
  return walker.run();
}

}  // namespace volley::simd
