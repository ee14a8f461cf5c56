// The queries the walks answer. A query is a leaf action and a termination rule; the walks
// (single_walk.h, frustum_walk.h, packet_walk.h) know nothing else of what is asked, so a
// new query is a new struct here and an entry that hands it to a walk (docs/adding-a-query.md).
//
// A single-ray query Q (the walk in single_walk.h):
//   Q::kNearFirst   true: children are visited nearest entry first, and a stacked subtree
//                   whose entry lies beyond the current bound is dropped (closest hit);
//                   false: any order, no distances, nothing dropped (any hit).
//   Q::kSureRange   the prepared ray carries the sure quotient range of the watertight
//                   any-hit decision (PreparedRay::sure).
//   q.bound(ray)    the upper end of the search on entry.
//   q.node()        called at every interior node the walk tests (CountingRay counts them).
//   q.leaf(pr, blocks, count, bound)
//                   the leaf's triangles (a top level's: its instance ids):
//                   LeafStep::narrowed after lowering `bound`, LeafStep::done to end the
//                   walk, LeafStep::go_on otherwise.
//   q.answer()      what the walk returns.
// A packet query P (the walks in frustum_walk.h and packet_walk.h), per lane:
//   P::kNearFirst   true: the per-lane walk puts next the child some lane enters first;
//                   false: it keeps the node's slot order (any hit, as single rays).
//   p.bound(o, tmax)                 the upper ends of lanes o .. o + L - 1 on entry.
//   p.leaf(prep, blocks, count, lanes, tfar)
//                   the leaf's triangles for `lanes`; lowers their tfar, and returns the
//                   lanes that are finished (their tfar set to -inf) and whether any tfar fell.
//   p.single(bvh, prep, setup, start, lane, far)
//                   the subtree `start` for one lane of the prepared packet by the single
//                   walk (few lanes left; Kernels::trace_lane); updates the lane's upper end
//                   `far`, true when the lane is finished.
//   P::kDeferSingles (optional, false if absent) the per-lane walk may run those single
//                   walks after its own (where the view defers hand-offs): the answer does
//                   not depend on when a lane's subtrees are searched (any hit).
#pragma once
#include <bit>
#include <cstdint>
#include <limits>

#include "simd/wide/kernels.h"

namespace volley::simd {

namespace detail {

/// Whether packets of one octant whose origins differ take the frustum walk under `Query`
/// (PacketWalk::spread_frustum): only where the query says so (kSpreadFrustum).
template <class Query>
constexpr bool spread_frustum() {
  if constexpr (requires { Query::kSpreadFrustum; })
    return Query::kSpreadFrustum;
  else
    return false;
}

/// Whether the per-lane walk may defer the query's hand-offs to single rays (kDeferSingles).
template <class Query>
constexpr bool defer_singles() {
  if constexpr (requires { Query::kDeferSingles; })
    return Query::kDeferSingles;
  else
    return false;
}

/// Whether the frustum walk tests the lanes again at each subtree it pops (skipping it or
/// handing it to single rays when few lanes enter): unless the query says otherwise
/// (kLanesOnPop = false).
template <class Query>
constexpr bool lanes_on_pop() {
  if constexpr (requires { Query::kLanesOnPop; })
    return Query::kLanesOnPop;
  else
    return true;
}

/// Whether the stream walk may test a long leaf list L rays at a time in lanes
/// (q.leaf_lanes, ClosestHitStream's), instead of ray by ray by the single query's leaf.
template <class Query>
constexpr bool leaf_lanes() {
  if constexpr (requires { Query::kLeafLanes; })
    return Query::kLeafLanes;
  else
    return false;
}

/// What a single-ray query's leaf action tells the walk.
enum class LeafStep {
  go_on,     ///< nothing changed
  narrowed,  ///< the bound fell: the walk refreshes its copy for the node tests
  done,      ///< the answer is known: the walk ends
};

/// What a packet query's leaf action tells the walk.
struct LanesStep {
  std::uint32_t finished;  ///< lanes whose answer is known (their tfar is now -inf)
  bool narrowed;           ///< some lane's tfar fell
};

/// Triangles used in a block: the lanes before its padding (prim = kInvalidPrim).
template <class Arch, class Block>
int used_lanes(const Block& block) {
  using I = IntB<Arch>;
  const I ids = I::load_aligned(reinterpret_cast<const std::int32_t*>(block.prim));
  const auto used = xsimd::bool_cast(ids != I(static_cast<std::int32_t>(kInvalidPrim)));
  return std::popcount(bits_from_mask<Arch>(used));
}

/// How many of a leaf's last block's triangles the packet leaves test: the used ones when
/// the block is at most half full, else all W. A padding lane costs a full test in the
/// packet form, so a sparse block stops at its last triangle (the block kernels' `last`).
template <class Kernels>
int last_block_triangles(const typename Kernels::Block* blocks, std::uint32_t count) {
  const int used = used_lanes<typename Kernels::SingleArch>(blocks[count - 1]);
  return used > Kernels::W / 2 ? Kernels::W : used;
}

/// Closest hit of one ray: every leaf lowers the bound to its nearest hit.
template <class Kernels>
struct ClosestHitRay {
  using Leaf = RayBlockKernels<typename Kernels::SingleArch, Kernels::kTest>;
  static constexpr bool kNearFirst = true;
  static constexpr bool kSureRange = false;
  Hit& hit;
  bool found = false;

  float bound(const Ray& ray) const { return hit.t < ray.tmax ? hit.t : ray.tmax; }
  void node() {}
  [[gnu::always_inline]] LeafStep leaf(const PreparedRay& pr, const typename Kernels::Block* blocks,
                                       std::uint32_t count, float& bound) {
    Leaf::template intersect_inline<false>(pr, blocks, count, hit);
    if (!(hit.t < bound)) return LeafStep::go_on;
    bound = hit.t;
    found = true;
    return LeafStep::narrowed;
  }
  bool answer() const { return found; }
};

/// Any hit of one ray: the first leaf with a hit ends the walk.
template <class Kernels>
struct AnyHitRay {
  using Leaf = RayBlockKernels<typename Kernels::SingleArch, Kernels::kTest>;
  static constexpr bool kNearFirst = false;
  static constexpr bool kSureRange = true;
  bool occluded = false;

  float bound(const Ray& ray) const { return ray.tmax; }
  void node() {}
  [[gnu::always_inline]] LeafStep leaf(const PreparedRay& pr, const typename Kernels::Block* blocks,
                                       std::uint32_t count, float&) {
    if (!Leaf::occluded_inline(pr, blocks, count)) return LeafStep::go_on;
    occluded = true;
    return LeafStep::done;
  }
  bool answer() const { return occluded; }
};

/// Every hit of one ray by the crossing test (all hits, counts): each leaf's hits go to
/// `sink`, nothing is pruned and the walk never ends early.
template <class Kernels, class Sink>
struct AllHitsRay {
  using Leaf = RayBlockKernels<typename Kernels::SingleArch, Kernels::kTest>;
  static constexpr bool kNearFirst = false;
  static constexpr bool kSureRange = false;
  Sink& sink;

  float bound(const Ray& ray) const { return ray.tmax; }
  void node() {}
  [[gnu::always_inline]] LeafStep leaf(const PreparedRay& pr, const typename Kernels::Block* blocks,
                                       std::uint32_t count, float&) {
    Leaf::all_inline(pr, blocks, count, sink);
    return LeafStep::go_on;
  }
  bool answer() const { return false; }
};

/// The instances a ray's walk of a top level reaches (WideKernels::walk_instances): each
/// leaf's instance ids to the visitor. NearFirst: closest hit (a visit's hit lowers the
/// bound); EndAtHit: any hit (the first hit ends the walk); neither: every instance.
template <bool NearFirst, bool EndAtHit>
struct InstancesRay {
  static constexpr bool kNearFirst = NearFirst;
  static constexpr bool kSureRange = false;
  InstanceVisit visit;
  /// The upper end of the search besides ray.tmax (given apart: a ray copied and given a
  /// new tmax just before the walk would stall the walk's 16-byte loads of it, as a store
  /// of 4 bytes cannot be forwarded to them).
  float limit;
  bool found = false;

  // (Not templated on the ISA: inlined, so that no per-ISA object defines them.)
  [[gnu::always_inline]] float bound(const Ray& ray) const { return limit < ray.tmax ? limit : ray.tmax; }
  [[gnu::always_inline]] void node() {}
  [[gnu::always_inline]] LeafStep leaf(const PreparedRay&, const std::uint32_t* instances, std::uint32_t count,
                                       float& bound) {
    LeafStep step = LeafStep::go_on;
    for (std::uint32_t k = 0; k < count; ++k) {
      if (!visit.visit(visit.context, instances[k], bound)) continue;
      found = true;
      if constexpr (EndAtHit) return LeafStep::done;
      step = LeafStep::narrowed;
    }
    return step;
  }
  [[gnu::always_inline]] bool answer() const { return found; }
};

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
  /// and diffuse rays unchanged (perf/instances.md). The lanes are not tested again at each
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

/// A single-ray query counted: the walk's interior nodes, leaves and their triangles go
/// to `counts`, the answers are `inner`'s.
template <class Kernels, class Query>
struct CountingRay {
  static constexpr bool kNearFirst = Query::kNearFirst;
  static constexpr bool kSureRange = Query::kSureRange;
  Query& inner;
  WalkCounts& counts;

  float bound(const Ray& ray) const { return inner.bound(ray); }
  void node() { ++counts.nodes; }
  LeafStep leaf(const PreparedRay& pr, const typename Kernels::Block* blocks, std::uint32_t count, float& bound) {
    ++counts.leaves;
    for (std::uint32_t b = 0; b < count; ++b)
      counts.triangles += static_cast<std::uint64_t>(used_lanes<typename Kernels::SingleArch>(blocks[b]));
    return inner.leaf(pr, blocks, count, bound);
  }
  bool answer() const { return inner.answer(); }
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
  /// packets, since shadow rays' origins spread over surfaces (perf/traversal.md).
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

/// Any hit of each ray of a stream (stream_walk.h): blocked[i] = 1 at ray i's first hit,
/// its upper end then -inf (finished). A stream query names the single-ray query that
/// answers one ray (`Single`, at leaves and in subtrees left to the single walk), makes one
/// for ray i, and takes its answer back (`done`), lowering the ray's upper end `far`.
template <class Kernels>
struct AnyHitStream {
  using Single = AnyHitRay<Kernels>;
  static constexpr bool kNearFirst = false;
  std::uint8_t* blocked;

  float bound(std::size_t, const Ray& ray) const { return ray.tmax; }
  Single single(std::uint32_t) const { return Single{}; }
  void done(std::uint32_t i, const Single& q, float& far) {
    if (!q.answer()) return;
    blocked[i] = 1;
    far = -std::numeric_limits<float>::infinity();
  }
};

/// Closest hit of each ray of a stream (stream_walk.h): hits[i] as ClosestHitRay's (its t
/// on entry bounds the search), the ray's upper end lowered to it.
template <class Kernels>
struct ClosestHitStream {
  using Single = ClosestHitRay<Kernels>;
  using B = typename Kernels::Float;
  static constexpr bool kNearFirst = true;
  static constexpr bool kLeafLanes = true;
  Hit* hits;

  float bound(std::size_t i, const Ray& ray) const { return hits[i].t < ray.tmax ? hits[i].t : ray.tmax; }
  Single single(std::uint32_t i) const { return Single{hits[i]}; }
  void done(std::uint32_t i, const Single& q, float& far) {
    if (q.answer()) far = hits[i].t;
  }
  /// A leaf for the rays ids[0 .. L) in lanes `r` at once, the triangles broadcast (the
  /// stream walk's long leaf lists; the closest-hit packet kernel's loop): lanes searching
  /// [tmin, upper), the last block's first `last` triangles only. Each hit lane's ray gets
  /// its nearest hit, and its upper end `far(i)` falls to it.
  template <class T, class Far>
  [[gnu::always_inline]] void leaf_lanes(const typename T::Rays& r, B upper, const std::uint32_t* ids,
                                         const typename Kernels::Block* blocks, std::uint32_t count, int last,
                                         Far&& far) {
    NearestLanes<typename Kernels::Isa, T> near(upper, B(0.0f), B(0.0f), B(0.0f));
    near.blocks(r, blocks, count, last);
    std::uint32_t bits = bits_from_mask<typename Kernels::Isa>(near.any);
    if (bits == 0) return;
    near.finish();
    alignas(64) float t[Kernels::L], u[Kernels::L], v[Kernels::L];
    alignas(64) std::uint32_t prim[Kernels::L];
    near.upper.store_aligned(t), near.u.store_aligned(u), near.v.store_aligned(v);
    near.prim.store_aligned(reinterpret_cast<float*>(prim));
    for (; bits != 0; bits &= bits - 1) {
      const int l = std::countr_zero(bits);
      Hit& hit = hits[ids[l]];
      hit.t = t[l], hit.u = u[l], hit.v = v[l], hit.prim = prim[l];
      far(ids[l]) = t[l];
    }
  }
};

}  // namespace detail

}  // namespace volley::simd
