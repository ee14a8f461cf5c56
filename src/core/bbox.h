// Scalar oracle: axis-aligned bounding boxes (BVH nodes, primitive bounds).
#pragma once
#include <limits>

#include <glm/glm.hpp>

namespace volley::core {

/// Axis-aligned box [lo, hi] (closed), in float. The default box is empty, with
/// lo = +inf and hi = -inf, so extending it by anything yields that thing's bounds.
/// A box is empty when lo > hi on some axis, or when a bound is NaN.
/// Plain value type; no invariants beyond that; not synchronized.
struct BBox {
  glm::vec3 lo{std::numeric_limits<float>::infinity()};   // 12 bytes
  glm::vec3 hi{-std::numeric_limits<float>::infinity()};  // 12 bytes

  /// Grows the box to contain p. A NaN coordinate of p is ignored on its axis (the
  /// comparison is false and the bound is kept), so a primitive with a NaN vertex gets
  /// the bounds of its other vertices, and one made only of NaN vertices stays empty.
  void extend(const glm::vec3& p) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = p[a] < lo[a] ? p[a] : lo[a];
      hi[a] = p[a] > hi[a] ? p[a] : hi[a];
    }
  }

  /// Grows the box to contain b (no change for an empty b with ±inf bounds; NaN
  /// bounds of b are ignored as in extend(point)).
  void extend(const BBox& b) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = b.lo[a] < lo[a] ? b.lo[a] : lo[a];
      hi[a] = b.hi[a] > hi[a] ? b.hi[a] : hi[a];
    }
  }

  /// True when the box contains no point: lo > hi on some axis or a NaN bound
  /// (written as !(lo <= hi) so that NaN counts as empty).
  bool empty() const {
    return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z);
  }

  /// Centre, computed as lo/2 + hi/2 (finite for every finite box, no overflow near
  /// FLT_MAX). Meaningless for an empty box.
  glm::vec3 center() const { return 0.5f * lo + 0.5f * hi; }

  /// hi - lo. Meaningless for an empty box.
  glm::vec3 diagonal() const { return hi - lo; }

  /// Half the surface area (xy + yz + zx extents), the SAH measure; 0 for an empty box,
  /// and 0 for a box flat in two axes (a segment or a point).
  float half_area() const {
    if (empty()) return 0.0f;
    const glm::vec3 d = diagonal();
    return d.x * d.y + d.y * d.z + d.z * d.x;
  }

  /// Axis (0, 1, 2) of the largest extent; ties go to the lower axis.
  int largest_axis() const {
    const glm::vec3 d = diagonal();
    int axis = d.y > d.x ? 1 : 0;
    return d.z > d[axis] ? 2 : axis;
  }

  /// True when p lies in the closed box (false for a NaN coordinate).
  bool contains(const glm::vec3& p) const {
    return lo.x <= p.x && p.x <= hi.x && lo.y <= p.y && p.y <= hi.y && lo.z <= p.z &&
           p.z <= hi.z;
  }

  /// True when b lies in this closed box; an empty b is contained in every box.
  bool contains(const BBox& b) const {
    if (b.empty()) return true;
    return lo.x <= b.lo.x && lo.y <= b.lo.y && lo.z <= b.lo.z && b.hi.x <= hi.x &&
           b.hi.y <= hi.y && b.hi.z <= hi.z;
  }
};
static_assert(sizeof(BBox) == 24, "BBox is two packed vec3 (24 bytes)");

/// Bounds of a triangle (NaN coordinates ignored as in BBox::extend).
inline BBox triangle_bbox(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2) {
  BBox b;
  b.extend(p0);
  b.extend(p1);
  b.extend(p2);
  return b;
}

}  // namespace volley::core
