// The part of a triangle within a slab between two axis-aligned planes, as the
// spatial-split builder (bvh_spatial.cpp) cuts triangles: its conservative box, and the
// float estimate of where the edges cross one plane.
#pragma once
#include <algorithm>
#include <cstdint>
#include <cstring>

#include <glm/glm.hpp>

#include "core/bbox.h"

namespace volley::core {

/// The box both a and b contain (empty when they do not meet).
inline BBox box_intersection(const BBox& a, const BBox& b) {
  BBox r;
  for (int k = 0; k < 3; ++k) {
    r.lo[k] = std::max(a.lo[k], b.lo[k]);
    r.hi[k] = std::min(a.hi[k], b.hi[k]);
  }
  return r;
}

/// The float next to finite f towards -inf (+inf with up): its bits one step on.
inline float float_step(float f, bool up) {
  std::uint32_t bits;
  std::memcpy(&bits, &f, 4);
  if (f == 0.0f) bits = up ? 1u : 0x80000001u;  // the smallest subnormals
  else if ((f > 0.0f) == up) ++bits;
  else --bits;
  std::memcpy(&f, &bits, 4);
  return f;
}

/// Extends `box` by the double point p, one float step beyond its nearest float on each
/// side, on every axis but `axis`, where it is the plane `x` (a float, exactly). p is within
/// a few double ulps of the exact point, far less than the half float step that the
/// nearest float may lie on the wrong side: the bounds hold the exact point.
inline void extend_outwards(BBox& box, const double (&p)[3], int axis, float x) {
  for (int k = 0; k < 3; ++k) {
    if (k == axis) {
      box.lo[k] = std::min(box.lo[k], x);
      box.hi[k] = std::max(box.hi[k], x);
      continue;
    }
    const float f = static_cast<float>(p[k]);
    box.lo[k] = std::min(box.lo[k], float_step(f, false));
    box.hi[k] = std::max(box.hi[k], float_step(f, true));
  }
}

/// Bounds of the part of triangle v with lo <= x_axis <= hi, within `clip` (empty when the
/// part is): its vertices in the slab and the edges' crossings of the two planes, computed
/// in double and rounded outwards, so the boxes of a triangle's parts cover it.
inline BBox clipped_triangle_box(const glm::vec3* v, int axis, float lo, float hi, const BBox& clip) {
  BBox box;
  for (int e = 0; e < 3; ++e) {
    const glm::vec3& p = v[e];
    const glm::vec3& q = v[e == 2 ? 0 : e + 1];
    if (p[axis] >= lo && p[axis] <= hi) box.extend(p);
    for (const float x : {lo, hi}) {
      if (!((p[axis] < x && q[axis] > x) || (p[axis] > x && q[axis] < x))) continue;
      const double t = (double(x) - p[axis]) / (double(q[axis]) - p[axis]);
      const double point[3] = {p.x + t * (double(q.x) - p.x), p.y + t * (double(q.y) - p.y),
                               p.z + t * (double(q.z) - p.z)};
      extend_outwards(box, point, axis, x);
    }
  }
  return box_intersection(box, clip);
}

/// Bounds of the points where the edges of triangle v cross the plane x_axis = x, in float
/// (an estimate: the builder prices splits with it, it does not bound references).
inline BBox plane_crossings(const glm::vec3* v, int axis, float x) {
  BBox box;
  for (int e = 0; e < 3; ++e) {
    const glm::vec3& p = v[e];
    const glm::vec3& q = v[e == 2 ? 0 : e + 1];
    if (!((p[axis] < x && x < q[axis]) || (q[axis] < x && x < p[axis]))) continue;
    glm::vec3 c = p + ((x - p[axis]) / (q[axis] - p[axis])) * (q - p);
    c[axis] = x;
    box.extend(c);
  }
  return box;
}

}  // namespace volley::core
