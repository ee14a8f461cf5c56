// The single-ray entries of the wide-BVH kernels: each makes its query (queries.h) and
// hands it to the single-ray walk (single_walk.h). The erased ones take the view as a void
// pointer, so that accel::WideAccel calls them through a plain function pointer.
#pragma once
#include <vector>

#include "simd/hit_list.h"
#include "simd/wide/queries.h"
#include "simd/wide/single_walk.h"

namespace volley::simd {

template <class Arch, TriangleTest Test, bool Robust, int PK>
void WideKernels<Arch, Test, Robust, PK>::intersect_erased(const void* bvh, const Ray& ray, Hit& hit) {
  const View& view = *static_cast<const View*>(bvh);
  detail::ClosestHitRay<WideKernels> query{hit};
  trace_ray(view, ray, view.root, query);
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
bool WideKernels<Arch, Test, Robust, PK>::occluded_erased(const void* bvh, const Ray& ray) {
  const View& view = *static_cast<const View*>(bvh);
  detail::AnyHitRay<WideKernels> query;
  return trace_ray(view, ray, view.root, query);
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
void WideKernels<Arch, Test, Robust, PK>::intersect_excluding_erased(const void* bvh, const Ray& ray,
                                                                     std::uint32_t excluded, Hit& hit) {
  const View& view = *static_cast<const View*>(bvh);
  detail::ClosestHitRay<WideKernels, true> query{hit, excluded};
  trace_ray(view, ray, view.root, query);
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
bool WideKernels<Arch, Test, Robust, PK>::occluded_excluding_erased(const void* bvh, const Ray& ray,
                                                                    std::uint32_t excluded) {
  const View& view = *static_cast<const View*>(bvh);
  detail::AnyHitRay<WideKernels, true> query{excluded};
  return trace_ray(view, ray, view.root, query);
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
bool WideKernels<Arch, Test, Robust, PK>::walk_instances(const InstanceView& top, const Ray& ray, float bound,
                                                     InstanceVisit visit, InstanceWalk mode) {
  switch (mode) {
    case InstanceWalk::closest: {
      detail::InstancesRay<true, false> query{visit, bound};
      return trace_ray(top, ray, top.root, query);
    }
    case InstanceWalk::any: {
      detail::InstancesRay<false, true> query{visit, bound};
      return trace_ray(top, ray, top.root, query);
    }
    case InstanceWalk::every: {
      detail::InstancesRay<false, false> query{visit, bound};
      return trace_ray(top, ray, top.root, query);
    }
  }
  return false;
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
WalkCounts WideKernels<Arch, Test, Robust, PK>::walk_counts(const View& view, const Ray& ray, bool any_hit) {
  WalkCounts counts;
  if (any_hit) {
    detail::AnyHitRay<WideKernels> query;
    detail::CountingRay<WideKernels, decltype(query)> counted{query, counts};
    trace_ray(view, ray, view.root, counted);
  } else {
    Hit hit;
    detail::ClosestHitRay<WideKernels> query{hit};
    detail::CountingRay<WideKernels, decltype(query)> counted{query, counts};
    trace_ray(view, ray, view.root, counted);
  }
  return counts;
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
void WideKernels<Arch, Test, Robust, PK>::all_hits(const View& view, const Ray& ray, std::vector<Hit>& out) {
  auto sink = [&out](std::uint32_t prim, float t, float u, float v) { append_hit(out, Hit{t, u, v, prim}); };
  detail::AllHitsRay<WideKernels, decltype(sink)> query{sink};
  trace_ray(view, ray, view.root, query);
}

}  // namespace volley::simd
