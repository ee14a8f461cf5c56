// The query protocol: what a query gives the walks (single_walk.h, frustum_walk.h,
// packet_walk.h, stream_walk.h), declared as concepts that each walk checks at compile time.
// A query is a termination rule, a leaf action and an answer; the walks know nothing else
// of what is asked and name no query, so a new query is a new type (queries.h,
// packet_queries.h, stream_queries.h) and an entry that hands it to a walk
// (docs/adding-a-query.md).
//
// A single-ray query Q (RayQuery; the walk in single_walk.h):
//   Q::kNearFirst   true: children are visited nearest entry first, and a stacked subtree
//                   whose entry lies beyond the current bound is dropped (closest hit);
//                   false: any order, no distances, nothing dropped (any hit).
//   Q::kSureRange   the prepared ray carries the sure quotient range of the watertight
//                   any-hit decision (PreparedRay::sure).
//   q.bound(ray)    the upper end of the search on entry.
//   q.node()        called at every interior node the walk tests (CountingRay counts them).
//   q.leaf(pr, leaf, count, bound)
//                   the leaf's items (triangle blocks; a top level's: its instance ids):
//                   LeafStep::narrowed after lowering `bound`, LeafStep::done to end the
//                   walk, LeafStep::go_on otherwise.
//   q.answer()      what the walk returns.
// A packet query P (PacketQuery; the walks in frustum_walk.h and packet_walk.h), per lane:
//   P::kNearFirst   true: the per-lane walk puts next the child some lane enters first;
//                   false: it keeps the node's slot order (any hit, as single rays).
//   p.bound(o, tmax)                 the upper ends of lanes o .. o + L - 1 on entry.
//   p.leaf(prep, leaf, count, lanes, tfar)
//                   the leaf's items for `lanes`; lowers their tfar, and returns the
//                   lanes that are finished (their tfar set to -inf) and whether any tfar fell.
//   p.single(bvh, prep, setup, start, lane, far)
//                   the subtree `start` for one lane of the prepared packet by the single
//                   walk (few lanes left; Kernels::trace_lane); updates the lane's upper end
//                   `far`, true when the lane is finished.
//   Optional constants, each read through the function of its name below:
//   P::kSpreadFrustum, P::kDeferSingles, P::kLanesOnPop.
// A stream query S (StreamQuery; the walk in stream_walk.h) answers each ray of a batch by
// a single-ray query:
//   S::Single       that query (a RayQuery over triangle blocks).
//   S::kNearFirst   as a single-ray query's, for the stream's node order.
//   s.bound(i, ray) ray i's upper end on entry.
//   s.single(i)     the single-ray query of ray i (run at leaves and in subtrees left to
//                   the single walk).
//   s.done(i, q, far) takes ray i's query back, lowering its upper end `far`.
//   Optional: S::kLeafLanes with s.leaf_lanes(...) (a long leaf list L rays at a time).
#pragma once
#include <concepts>
#include <cstddef>
#include <cstdint>

#include "simd/rays/prepared_packet.h"
#include "simd/rays/prepared_ray.h"
#include "simd/wide/wide_bvh.h"
#include "volley/ray.h"

namespace volley::simd {

namespace detail {

template <int K>
struct PacketSetup;

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

/// A single-ray query over leaves of `Leaf` items.
template <class Q, class Leaf>
concept RayQuery = requires(Q& q, const Q& cq, const Ray& ray, const PreparedRay& pr, const Leaf* leaf,
                            std::uint32_t count, float& bound) {
  { Q::kNearFirst } -> std::convertible_to<bool>;
  { Q::kSureRange } -> std::convertible_to<bool>;
  { cq.bound(ray) } -> std::same_as<float>;
  q.node();
  { q.leaf(pr, leaf, count, bound) } -> std::same_as<LeafStep>;
  { cq.answer() } -> std::same_as<bool>;
};

/// A packet query of the walks of `Kernels` (WideKernels) over leaves of `Leaf` items.
template <class P, class Kernels, class Leaf>
concept PacketQuery = requires(P& p, const P& cp, int offset, typename Kernels::Float tmax,
                               typename Kernels::Float* tfar, PreparedPacket<Kernels::K>& prep,
                               const PreparedPacket<Kernels::K>& cprep, const PacketSetup<Kernels::K>& setup,
                               const WideView<Leaf>& bvh, const Leaf* leaf, std::uint32_t count, std::uint32_t lanes,
                               int lane, float& far) {
  { P::kNearFirst } -> std::convertible_to<bool>;
  { cp.bound(offset, tmax) } -> std::same_as<typename Kernels::Float>;
  { p.leaf(prep, leaf, count, lanes, tfar) } -> std::same_as<LanesStep>;
  { p.single(bvh, cprep, setup, count, lane, far) } -> std::same_as<bool>;
};

/// A stream query of the walk of `Kernels` (over its triangle blocks).
template <class S, class Kernels>
concept StreamQuery = RayQuery<typename S::Single, typename Kernels::Block> &&
                      requires(S& s, const S& cs, std::size_t i, std::uint32_t id, const Ray& ray,
                               const typename S::Single& q, float& far) {
                        { S::kNearFirst } -> std::convertible_to<bool>;
                        { cs.bound(i, ray) } -> std::same_as<float>;
                        { cs.single(id) } -> std::same_as<typename S::Single>;
                        s.done(id, q, far);
                      };

/// Whether packets of one octant whose origins differ take the frustum walk under `Query`
/// (PacketWalk::spread_frustum): only where the query says so (kSpreadFrustum).
template <class Query>
constexpr bool spread_frustum() {
  if constexpr (requires { Query::kSpreadFrustum; })
    return Query::kSpreadFrustum;
  else
    return false;
}

/// Whether the per-lane walk may defer the query's hand-offs to single rays (kDeferSingles):
/// the answer does not depend on when a lane's subtrees are searched (any hit).
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

}  // namespace detail

}  // namespace volley::simd
