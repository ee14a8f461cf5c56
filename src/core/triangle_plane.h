// Scalar oracle: ray/triangle by the notes' algorithm 1, ray/plane then half-plane tests,
// with the plane and the two edge planes precomputed (the layout of Havel & Herout 2010,
// "Yet faster ray-triangle intersection (using SSE4)", IEEE TVCG 16(3)), taken relative to
// the triangle's first vertex so that they stay accurate far from the origin.
#pragma once
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/geometry.h"

namespace volley::core {

/// A triangle stored as its reference vertex p0, its plane and two scaled edge planes, all
/// through p0. For a point q in the triangle's plane, u = n1.(q - p0) and v = n2.(q - p0)
/// are its barycentrics (q = (1-u-v) p0 + u p1 + v p2), so the half-plane tests need no
/// further scaling. The planes' offsets relative to p0 are zero and are not stored: keeping
/// absolute offsets (n.p0 etc.) would make t and u, v differences of numbers ~|p0| |n|,
/// which cancel catastrophically far from the origin (issue 5). 48 bytes for float, 96 for
/// double (the same as the absolute layout: p0 replaces the three offsets).
template <class T>
struct PlaneTriangle {
  Vec3<T> p0;  ///< reference vertex; 12 bytes (float)
  Vec3<T> n;   ///< plane normal (p1-p0) x (p2-p0), not normalized: n.(x - p0) = 0 in the plane; 12 bytes
  Vec3<T> n1;  ///< (e2 x n) / |n|^2 with e2 = p2-p0: gradient of u; 12 bytes
  Vec3<T> n2;  ///< (n x e1) / |n|^2 with e1 = p1-p0: gradient of v; 12 bytes

  /// Precomputes the planes of (p0, p1, p2). A degenerate triangle (zero area, non-finite
  /// vertex, or planes that overflow T) gets p0 = n = n1 = n2 = 0: the ray/plane
  /// denominator n.dir is 0 (or NaN), so it never hits and never yields NaN.
  static PlaneTriangle from(const Vec3<T>& p0, const Vec3<T>& p1, const Vec3<T>& p2);
};
static_assert(sizeof(PlaneTriangle<float>) == 48);
static_assert(sizeof(PlaneTriangle<double>) == 96);

template <class T>
PlaneTriangle<T> PlaneTriangle<T>::from(const Vec3<T>& p0, const Vec3<T>& p1, const Vec3<T>& p2) {
  constexpr T kMax = std::numeric_limits<T>::max();
  const PlaneTriangle never{Vec3<T>(0), Vec3<T>(0), Vec3<T>(0), Vec3<T>(0)};
  const Vec3<T> e1 = p1 - p0;
  const Vec3<T> e2 = p2 - p0;
  const Vec3<T> n = glm::cross(e1, e2);
  // Divide by the largest component before squaring: |n|^2 itself underflows in float for
  // edges below ~1e-10 and overflows above ~4e9. NaN fails the test.
  const T m = std::max({std::abs(n.x), std::abs(n.y), std::abs(n.z)});
  if (!(m > 0 && m <= kMax)) return never;
  const Vec3<T> ns = n / m;
  const T k = m * glm::dot(ns, ns);  // = |n|^2 / m
  // q - p0 = u e1 + v e2  =>  (q-p0) x e2 = u n  and  e1 x (q-p0) = v n; dot with n / |n|^2.
  const PlaneTriangle out{p0, n, glm::cross(e2, ns) / k, glm::cross(ns, e1) / k};
  for (T x : {out.p0.x, out.p0.y, out.p0.z, out.n1.x, out.n1.y, out.n1.z, out.n2.x, out.n2.y, out.n2.z})
    if (!(std::abs(x) <= kMax)) return never;
  return out;
}

/// Intersects `ray` with a precomputed triangle, both facings (no culling).
///
/// The notes' t = ((p0 - org).n) / (dir.n), with the difference a = p0 - org taken first
/// (between nearby numbers when the ray starts near the triangle, however far both are from
/// the origin); the hit point relative to p0 is q = t dir - a; hit iff n.dir != 0 (finite),
/// tmin <= t < tmax, u = n1.q >= 0, v = n2.q >= 0, u + v <= 1. On a hit writes `hit` =
/// {t, u, v} and returns true; on a miss returns false and leaves `hit` untouched. NaN or
/// Inf input fails a comparison: no hit, never NaN out. Pure function, thread safe.
template <class T>
bool intersect_plane(const RayT<T>& ray, const PlaneTriangle<T>& tri, TriHit<T>& hit) {
  // Ray parallel to the plane, degenerate triangle (n = 0), Inf or NaN: no hit.
  const T den = glm::dot(tri.n, ray.dir);
  if (!(std::abs(den) > 0 && std::abs(den) <= std::numeric_limits<T>::max())) return false;

  // Ray/plane distance; the half-open range test is false for NaN.
  const Vec3<T> a = tri.p0 - ray.org;
  const T t = glm::dot(tri.n, a) / den;
  if (!(ray.tmin <= t && t < ray.tmax)) return false;

  // Half-plane tests on the hit point's barycentrics; false for NaN.
  const Vec3<T> q = t * ray.dir - a;  // org + t dir - p0
  const T u = glm::dot(tri.n1, q);
  const T v = glm::dot(tri.n2, q);
  if (!(u >= 0 && v >= 0 && u + v <= 1)) return false;

  hit = {t, u, v};
  return true;
}

}  // namespace volley::core
