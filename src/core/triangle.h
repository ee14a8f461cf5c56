// Scalar oracle: the three ray/triangle tests behind one switch (docs/kernels.md), and the degenerate-triangle predicate the builders share.
#pragma once
#include <cmath>

#include "core/geometry.h"
#include "core/triangle_moller.h"
#include "core/triangle_plane.h"
#include "core/triangle_watertight.h"
#include "volley/options.h"

namespace volley::core {

/// True when no ray/triangle test can be trusted on (p0, p1, p2): a non-finite coordinate,
/// or a cross product (p1-p0) x (p2-p0) that is exactly zero (zero area: repeated vertex,
/// collinear) or not finite (overflow). All three tests miss a zero-area or NaN triangle.
template <class T>
bool is_degenerate(const Vec3<T>& p0, const Vec3<T>& p1, const Vec3<T>& p2) {
  const auto finite = [](const Vec3<T>& p) {
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  };
  if (!finite(p0) || !finite(p1) || !finite(p2)) return true;
  const Vec3<T> n = glm::cross(p1 - p0, p2 - p0);
  return n == Vec3<T>(0) || !finite(n);
}

/// Runs the chosen test on one ray and one triangle, building its precomputed data
/// (PlaneTriangle, WoopRay) on the fly. Same contract as the individual tests: both
/// facings, tmin <= t < tmax, `hit` written only on a hit. `variant_of`: the ISA whose
/// kernels' answers to reproduce bit for bit (moller and watertight fuse on AVX2/AVX-512
/// only, moller_fused_for, watertight_fused_for; plane is the same everywhere); by default
/// the scalar oracle's. Pure function, thread safe.
template <class T>
bool intersect_triangle(volley::TriangleTest test, const RayT<T>& ray, const Vec3<T>& p0, const Vec3<T>& p1,
                        const Vec3<T>& p2, TriHit<T>& hit, volley::Isa variant_of = volley::Isa::scalar) {
  switch (test) {
    case volley::TriangleTest::plane:
      return intersect_plane(ray, PlaneTriangle<T>::from(p0, p1, p2), hit);
    case volley::TriangleTest::moller:
      return moller_fused_for(variant_of) ? intersect_moller<T, true>(ray, p0, p1, p2, hit)
                                          : intersect_moller<T, false>(ray, p0, p1, p2, hit);
    case volley::TriangleTest::watertight:
      return watertight_fused_for(variant_of) ? intersect_watertight<T, true>(ray, p0, p1, p2, hit)
                                              : intersect_watertight<T, false>(ray, p0, p1, p2, hit);
  }
  return false;
}

}  // namespace volley::core
