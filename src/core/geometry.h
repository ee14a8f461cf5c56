// Scalar oracle: the basic types every core routine shares, in float or double.
#pragma once
#include <glm/glm.hpp>

namespace volley::core {

/// 3-vector of T (float for the fast path, double for references).
template <class T>
using Vec3 = glm::vec<3, T, glm::defaultp>;

/// A ray r(t) = org + t dir, searched over tmin <= t < tmax (half-open: a hit exactly
/// at tmax is not taken, so a shadow ray with tmax = 1 toward a light never hits it).
template <class T>
struct RayT {
  Vec3<T> org;
  T tmin;
  Vec3<T> dir;
  T tmax;
};

/// Result of a ray/primitive test: distance t and barycentrics (u, v) such that the
/// hit point is (1-u-v) p0 + u p1 + v p2.
template <class T>
struct TriHit {
  T t;
  T u;
  T v;
};

/// Converts between precisions (float rays to double references and back).
template <class To, class From>
RayT<To> ray_cast(const RayT<From>& r) {
  return {Vec3<To>(r.org), To(r.tmin), Vec3<To>(r.dir), To(r.tmax)};
}

}  // namespace volley::core
