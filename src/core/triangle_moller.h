// Scalar oracle: ray/triangle by the notes' algorithm 2, the 3x3 barycentric system
// solved by Cramer's rule (Moller & Trumbore 1997, "Fast, minimum storage ray/triangle
// intersection", JGT 2(1)).
#pragma once
#include <cmath>
#include <limits>

#include "core/geometry.h"

namespace volley::core {

/// Intersects `ray` with the triangle (p0, p1, p2), both facings (no culling).
///
/// Solves  [-(p1-p0)  -(p2-p0)  dir] [u v t]^T = p0 - org  by Cramer's rule and reports a
/// hit iff det != 0 (finite), u >= 0, v >= 0, u + v <= 1 and tmin <= t < tmax.
/// On a hit writes `hit` = {t, u, v} (hit point = (1-u-v) p0 + u p1 + v p2) and returns true;
/// on a miss returns false and leaves `hit` untouched.
///
/// The determinants are the triple products of Moller-Trumbore, factored as in Embree's
/// Moller intersector so the normal n = (p1-p0) x (p2-p0) is computed once: a triangle with
/// n == 0 exactly (is_degenerate) gets det == 0 and never hits. The quotients are true
/// divisions (no reciprocal): this is the accuracy reference for the SIMD twins.
/// NaN or Inf anywhere in the input makes a comparison below fail: no hit, never NaN out.
/// Pure function, thread safe.
template <class T>
bool intersect_moller(const RayT<T>& ray, const Vec3<T>& p0, const Vec3<T>& p1, const Vec3<T>& p2,
                      TriHit<T>& hit) {
  const Vec3<T> e1 = p1 - p0;
  const Vec3<T> e2 = p2 - p0;
  const Vec3<T> n = glm::cross(e1, e2);
  const Vec3<T> c = p0 - ray.org;  // right-hand side of the system

  // det[-e1 -e2 d] = d . (e1 x e2). Written so NaN fails: parallel ray, degenerate
  // triangle (n == 0), overflow (Inf) and NaN input all leave here.
  const T det = glm::dot(ray.dir, n);
  if (!(std::abs(det) > 0 && std::abs(det) <= std::numeric_limits<T>::max())) return false;

  // Cramer: replace one column by c. With r = d x c:
  //   det[c -e2 d] = -e2 . r,   det[-e1 c d] = e1 . r,   det[-e1 -e2 c] = c . n.
  const Vec3<T> r = glm::cross(ray.dir, c);
  const T u = -glm::dot(e2, r) / det;
  const T v = glm::dot(e1, r) / det;
  // Half-plane tests; each comparison is false for NaN.
  if (!(u >= 0 && v >= 0 && u + v <= 1)) return false;

  const T t = glm::dot(c, n) / det;
  // Half-open range tmin <= t < tmax; false for NaN.
  if (!(ray.tmin <= t && t < ray.tmax)) return false;

  hit = {t, u, v};
  return true;
}

}  // namespace volley::core
