// The point query of core/'s binary BVH (the scalar oracle's closest point): children
// visited nearest box first, a subtree skipped once its box lies beyond the nearest
// primitive found; the same box distance and pruning rule as the wide walk
// (simd/wide/point_walk.h), so both visit every primitive that can win.
#pragma once
#include <cmath>
#include <cstdint>

#include "core/bvh.h"
#include "core/kernel_constants.h"
#include "core/point_triangle.h"
#include "core/polygon.h"

namespace volley::core {

/// Squared distance from p to the box (0 inside), in float.
inline float box_distance2(const BBox& b, const float* p) {
  float d2 = 0.0f;
  for (int a = 0; a < 3; ++a) {
    float d = b.lo[a] - p[a];
    const float e = p[a] - b.hi[a];
    d = d > e ? d : e;
    d = d > 0.0f ? d : 0.0f;
    d2 += d * d;
  }
  return d2;
}

/// The bound a box's squared distance must not exceed to be entered, given the nearest
/// squared distance so far: padded by 2^-10 relative (far above the rounding of the box and
/// triangle distances), and below +inf so an empty box (distance +inf) is never entered.
inline float nearest_bound(float d2) {
  const float b = d2 * (1.0f + 0x1p-10f);
  return b < 0x1.fffffep127f ? b : 0x1.fffffep127f;  // (not std::fmin: a libm call)
}

/// Calls leaf(prim) for the primitives of every leaf whose box lies within the bound of
/// query.d2 (which leaf lowers), nearest box first. A non-finite point visits nothing.
template <class Leaf>
void nearest_walk(const Bvh& bvh, PointQuery& query, Leaf&& leaf) {
  if (bvh.nodes.empty()) return;
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(query.p[a])) return;
  if (!(box_distance2(bvh.nodes[0].box, query.p) <= nearest_bound(query.d2))) return;
  std::uint32_t stack[kBvhMaxDepth];
  float stack_d2[kBvhMaxDepth];
  int size = 0;
  std::uint32_t index = 0;
  for (;;) {
    const BvhNode& node = bvh.nodes[index];
    if (!node.is_leaf()) {
      const std::uint32_t c0 = node.first_or_child;
      const float d0 = box_distance2(bvh.nodes[c0].box, query.p);
      const float d1 = box_distance2(bvh.nodes[c0 + 1].box, query.p);
      const float bound = nearest_bound(query.d2);
      const bool in0 = d0 <= bound, in1 = d1 <= bound;
      if (in0 && in1) {
        const bool swap = d1 < d0;
        stack[size] = swap ? c0 : c0 + 1;
        stack_d2[size++] = swap ? d0 : d1;
        index = swap ? c0 + 1 : c0;
        continue;
      }
      if (in0 || in1) {
        index = in0 ? c0 : c0 + 1;
        continue;
      }
    } else {
      for (std::uint32_t i = node.first_or_child; i < node.first_or_child + node.count; ++i) leaf(bvh.prim_index[i]);
    }
    for (;;) {
      if (size == 0) return;
      --size;
      if (stack_d2[size] <= nearest_bound(query.d2)) break;
    }
    index = stack[size];
  }
}

/// A planar polygon offered to `query` (kept when strictly nearer): the projection onto
/// its plane when the even-odd rule puts it inside, else the nearest point of its edges.
/// Barycentrics are not defined for polygons: u = v = 0.
inline bool offer_polygon(PointQuery& query, const Polygon& poly, std::uint32_t prim) {
  const Vec3<float> p(query.p[0], query.p[1], query.p[2]);
  const float h = glm::dot(poly.normal, p) - poly.d;
  const Vec3<float> proj = p - h * poly.normal;
  float best = INFINITY;
  Vec3<float> q(0.0f);
  if (polygon_inside_2d(poly, proj[poly.axis_u], proj[poly.axis_v])) {
    best = h * h, q = proj;
  } else {
    const std::size_t n = poly.vertices.size();
    for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
      const Vec3<float> a = poly.vertices[j], e = poly.vertices[i] - a, w = p - a;
      float t = glm::dot(w, e) / glm::dot(e, e);
      t = t > 0.0f ? t : 0.0f;
      t = t < 1.0f ? t : 1.0f;
      const Vec3<float> d = w - t * e;
      const float d2 = glm::dot(d, d);
      if (d2 < best) best = d2, q = a + t * e;
    }
  }
  if (!(best < query.d2)) return false;
  query.d2 = best;
  query.q[0] = q.x, query.q[1] = q.y, query.q[2] = q.z;
  query.u = query.v = 0.0f;
  query.prim = prim;
  return true;
}

}  // namespace volley::core
