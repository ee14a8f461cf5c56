// Double-precision ray/triangle reference of the accuracy report and the stress suite.
#pragma once
#include <algorithm>
#include <array>

#include "volley/ray.h"

namespace volley::accuracy {

/// Moller-Trumbore in double, t unclamped: the ray parameter t and the barycentrics of the
/// intersection of the ray's line with the triangle's plane. `ok` is false when the ray is
/// parallel to the plane (det == 0).
struct RefHit {
  bool ok = false;
  double t = 0, u = 0, v = 0;
  /// Smallest barycentric (negative outside the triangle).
  double margin() const { return std::min(std::min(u, v), 1.0 - u - v); }
  bool inside(double min_margin = 0.0) const { return ok && margin() >= min_margin; }
};

/// The reference for ray `r` (float inputs widened exactly) and the triangle p0 p1 p2.
RefHit reference(const Ray& r, const std::array<double, 3>& p0, const std::array<double, 3>& p1,
                 const std::array<double, 3>& p2);

}  // namespace volley::accuracy
