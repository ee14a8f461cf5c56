// The stream queries (the protocol: query_protocol.h): any hit and closest hit of each ray
// of a stream, each ray answered by a single-ray query (queries.h).
#pragma once
#include <bit>
#include <cstdint>
#include <limits>

#include "simd/wide/kernels.h"
#include "simd/wide/queries.h"

namespace volley::simd {

namespace detail {

/// Any hit of each ray of a stream (stream_walk.h): blocked[i] = 1 at ray i's first hit,
/// its upper end then -inf (finished). A stream query names the single-ray query that
/// answers one ray (`Single`, at leaves and in subtrees left to the single walk), makes one
/// for ray i, and takes its answer back (`done`), lowering the ray's upper end `far`.
/// Excludes: ray i passes over the triangle of id excluded[i] (the excluding query).
template <class Kernels, bool Excludes = false>
struct AnyHitStream {
  using Single = AnyHitRay<Kernels, Excludes>;
  static constexpr bool kNearFirst = false;
  std::uint8_t* blocked;
  const std::uint32_t* excluded = nullptr;

  float bound(std::size_t, const Ray& ray) const { return ray.tmax; }
  Single single(std::uint32_t i) const {
    if constexpr (Excludes)
      return Single{excluded[i]};
    else
      return Single{};
  }
  void done(std::uint32_t i, const Single& q, float& far) {
    if (!q.answer()) return;
    blocked[i] = 1;
    far = -std::numeric_limits<float>::infinity();
  }
};

/// Closest hit of each ray of a stream (stream_walk.h): hits[i] as ClosestHitRay's (its t
/// on entry bounds the search), the ray's upper end lowered to it. Excludes as
/// AnyHitStream's; its leaves then go ray by ray (the lanes' leaf test excludes nothing).
template <class Kernels, bool Excludes = false>
struct ClosestHitStream {
  using Single = ClosestHitRay<Kernels, Excludes>;
  using B = typename Kernels::Float;
  static constexpr bool kNearFirst = true;
  static constexpr bool kLeafLanes = !Excludes;
  Hit* hits;
  const std::uint32_t* excluded = nullptr;

  float bound(std::size_t i, const Ray& ray) const { return hits[i].t < ray.tmax ? hits[i].t : ray.tmax; }
  Single single(std::uint32_t i) const {
    if constexpr (Excludes)
      return Single{hits[i], excluded[i]};
    else
      return Single{hits[i]};
  }
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
