// Scalar oracle: planar polygons (convex or concave, any vertex count >= 3), hit by the
// notes' method: ray/plane, then the even-odd crossing test in a 2D projection
// (Haines 1994, "Point in Polygon Strategies", Graphics Gems IV; Franklin's PNPOLY).
#pragma once
#include <cmath>
#include <cstddef>
#include <limits>
#include <vector>

#include "core/geometry.h"

namespace volley::core {

/// A planar polygon ready for intersection; build it with make_polygon. Edges join
/// consecutive vertices and the last to the first; self-intersecting outlines are allowed
/// (even-odd rule) but must have nonzero signed area.
struct Polygon {
  std::vector<Vec3<float>> vertices;  ///< outline in the given order
  Vec3<float> normal;                 ///< unit Newell normal; right-hand rule on the order
  float d;                            ///< plane: dot(normal, x) = d (best fit, through the centroid)
  int drop_axis;                      ///< axis where |normal| is largest, dropped for the 2D test
  int axis_u;                         ///< 2D u coordinate = x[axis_u] = x[(drop_axis + 1) % 3]
  int axis_v;                         ///< 2D v coordinate = x[axis_v] = x[(drop_axis + 2) % 3]
  float plane_deviation;              ///< largest vertex distance from the plane (world units)
};

/// Validates `verts` and builds a Polygon. Throws std::invalid_argument, with a message
/// saying which rule failed, when: fewer than 3 vertices; a non-finite coordinate; zero
/// area (|Newell normal| <= 1e-12 x squared bounding-box diagonal: coincident or collinear
/// vertices); or non-planar: a vertex farther than 1e-4 x the bounding-box diagonal from the
/// best-fit plane (Newell's normal through the centroid); the message states the measured
/// distance and the tolerance. Computed in double.
Polygon make_polygon(std::vector<glm::vec3> verts);

/// Lower corner of a box holding every point intersect_polygon can accept: the vertices'
/// bounds padded by twice the plane deviation plus a few float ulps (for the BVH).
Vec3<float> polygon_lo(const Polygon& poly);
/// Upper corner, as polygon_lo.
Vec3<float> polygon_hi(const Polygon& poly);

/// The even-odd test of intersect_polygon on a point (qu, qv) of the polygon's 2D projection
/// (axes axis_u, axis_v), with its half-open boundary rule.
template <class T>
bool polygon_inside_2d(const Polygon& poly, T qu, T qv) {
  // Even-odd: count the edges crossed by the 2D ray from q toward +u.
  bool inside = false;
  const std::size_t count = poly.vertices.size();
  for (std::size_t i = 0, j = count - 1; i < count; j = i++) {
    const T ui = T(poly.vertices[i][poly.axis_u]) - qu;
    const T vi = T(poly.vertices[i][poly.axis_v]) - qv;
    const T uj = T(poly.vertices[j][poly.axis_u]) - qu;
    const T vj = T(poly.vertices[j][poly.axis_v]) - qv;
    // Half-open in v: a vertex with v == 0 counts as below the 2D ray, so a 2D ray through
    // a vertex crosses its two edges once in total (or twice / never at a local extreme).
    // Horizontal edges never count. NaN compares false: no crossing.
    if ((vi > 0) != (vj > 0)) {
      // Crossing abscissa u* = (ui vj - vi uj) / (vj - vi); count it iff u* > 0 strictly,
      // tested by signs so no division rounds the decision.
      const T num = ui * vj - vi * uj;
      if (vj > vi ? num > 0 : num < 0) inside = !inside;
    }
  }
  return inside;
}

/// Intersects `ray` with `poly`, both facings. Hit iff normal.dir != 0 (finite),
/// t = (d - normal.org) / (normal.dir) satisfies tmin <= t < tmax, and the hit point q lies
/// inside by the even-odd rule in the plane spanned by axes (axis_u, axis_v). On a hit writes
/// t and returns true; on a miss returns false and leaves t untouched. NaN or Inf input fails
/// a comparison: no hit.
///
/// Boundary rule (half-open, like a rasterizer's fill rule): a point on an edge or a vertex
/// is inside iff the point moved by (+e, +e^2) in (u, v), for an infinitesimal e, is inside.
/// So polygons tiling a plane region (same projection axes) claim each shared edge point
/// and shared vertex exactly once, when the 2D arithmetic below is exact (e.g. small dyadic
/// coordinates); otherwise rounding decides within an ulp of the boundary.
/// Pure function, thread safe.
template <class T>
bool intersect_polygon(const RayT<T>& ray, const Polygon& poly, T& t) {
  // Ray/plane, as the plane triangle test; false for parallel rays, Inf and NaN.
  const Vec3<T> n(poly.normal);
  const T den = glm::dot(n, ray.dir);
  if (!(std::abs(den) > 0 && std::abs(den) <= std::numeric_limits<T>::max())) return false;
  const T t_plane = (T(poly.d) - glm::dot(n, ray.org)) / den;
  if (!(ray.tmin <= t_plane && t_plane < ray.tmax)) return false;

  // Project the hit point by dropping the normal's dominant axis.
  const Vec3<T> q = ray.org + t_plane * ray.dir;
  const T qu = q[poly.axis_u];
  const T qv = q[poly.axis_v];

  const bool inside = polygon_inside_2d(poly, qu, qv);
  if (!inside) return false;
  t = t_plane;
  return true;
}

}  // namespace volley::core
