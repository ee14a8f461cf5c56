// The single-ray queries (the protocol: query_protocol.h): closest hit, any hit, every hit,
// the instances of a top level, and any of them counted. The packet and stream queries
// (packet_queries.h, stream_queries.h) answer a lane or a ray of a stream with these.
#pragma once
#include <bit>
#include <cstdint>
#include <limits>

#include "simd/wide/kernels.h"
#include "simd/wide/query_protocol.h"

namespace volley::simd {

namespace detail {

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

/// Closest hit of one ray: every leaf lowers the bound to its nearest hit. Excludes: the
/// triangle whose id is `excluded` is not hit (the excluding query: a ray leaving a surface
/// skips the triangle it starts on).
template <class Kernels, bool Excludes = false>
struct ClosestHitRay {
  using Leaf = RayBlockKernels<typename Kernels::SingleArch, Kernels::kTest>;
  static constexpr bool kNearFirst = true;
  static constexpr bool kSureRange = false;
  Hit& hit;
  std::uint32_t excluded = kInvalidPrim;
  bool found = false;

  float bound(const Ray& ray) const { return hit.t < ray.tmax ? hit.t : ray.tmax; }
  void node() {}
  [[gnu::always_inline]] LeafStep leaf(const PreparedRay& pr, const typename Kernels::Block* blocks,
                                       std::uint32_t count, float& bound) {
    Leaf::template intersect_inline<false, Excludes>(pr, blocks, count, hit, excluded);
    if (!(hit.t < bound)) return LeafStep::go_on;
    bound = hit.t;
    found = true;
    return LeafStep::narrowed;
  }
  bool answer() const { return found; }
};

/// Any hit of one ray: the first leaf with a hit ends the walk (Excludes as ClosestHitRay's).
template <class Kernels, bool Excludes = false>
struct AnyHitRay {
  using Leaf = RayBlockKernels<typename Kernels::SingleArch, Kernels::kTest>;
  static constexpr bool kNearFirst = false;
  static constexpr bool kSureRange = true;
  std::uint32_t excluded = kInvalidPrim;
  bool occluded = false;

  float bound(const Ray& ray) const { return ray.tmax; }
  void node() {}
  [[gnu::always_inline]] LeafStep leaf(const PreparedRay& pr, const typename Kernels::Block* blocks,
                                       std::uint32_t count, float&) {
    if (!Leaf::template occluded_inline<Excludes>(pr, blocks, count, excluded)) return LeafStep::go_on;
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

}  // namespace detail

}  // namespace volley::simd
