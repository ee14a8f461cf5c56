// Polygon validation (planarity by Newell's normal) and bounds.
#include "core/polygon.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

namespace volley::core {

namespace {

using Vec3d = Vec3<double>;

[[noreturn]] void reject(const std::string& why) {
  throw std::invalid_argument("make_polygon: " + why);
}

}  // namespace

Polygon make_polygon(std::vector<glm::vec3> verts) {
  const std::size_t count = verts.size();
  if (count < 3)
    reject("a polygon needs at least 3 vertices, got " + std::to_string(count));
  for (std::size_t i = 0; i < count; ++i) {
    const glm::vec3& p = verts[i];
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) {
      std::ostringstream msg;
      msg << "vertex " << i << " has a non-finite coordinate (" << p.x << ", " << p.y << ", "
          << p.z << ")";
      reject(msg.str());
    }
  }

  // Centroid (vertex average) and bounding box, in double.
  Vec3d centroid(0), lo(verts[0]), hi(verts[0]);
  for (const glm::vec3& p : verts) {
    centroid += Vec3d(p);
    lo = glm::min(lo, Vec3d(p));
    hi = glm::max(hi, Vec3d(p));
  }
  centroid /= double(count);
  const double diag = glm::length(hi - lo);

  // Newell's normal (Sutherland, Sproull & Schumacker 1974; Tampieri, Graphics Gems III):
  // twice the vector area, exact for planar outlines, a best fit for nearly planar ones.
  // Centroid-relative coordinates keep the products small.
  Vec3d newell(0);
  for (std::size_t i = 0, j = count - 1; i < count; j = i++) {
    const Vec3d a = Vec3d(verts[j]) - centroid;
    const Vec3d b = Vec3d(verts[i]) - centroid;
    newell += Vec3d((a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y));
  }
  const double area2 = glm::length(newell);
  if (!(area2 > 1e-12 * diag * diag)) {
    std::ostringstream msg;
    msg << "zero area: the vertices are coincident or collinear (|Newell normal| = " << area2
        << ", bounding-box diagonal " << diag << ")";
    reject(msg.str());
  }
  const Vec3d normal = newell / area2;

  // Planarity: distance of every vertex from the plane through the centroid.
  double deviation = 0;
  for (const glm::vec3& p : verts)
    deviation = std::max(deviation, std::abs(glm::dot(normal, Vec3d(p) - centroid)));
  const double tolerance = 1e-4 * diag;
  if (deviation > tolerance) {
    std::ostringstream msg;
    msg.precision(6);
    msg << "the vertices are not coplanar: a vertex lies " << deviation
        << " from the best-fit plane (Newell normal through the centroid), more than the "
           "tolerance "
        << tolerance << " (1e-4 x bounding-box diagonal " << diag << ")";
    reject(msg.str());
  }

  const Vec3d a = glm::abs(normal);
  const int drop = a.x >= a.y ? (a.x >= a.z ? 0 : 2) : (a.y >= a.z ? 1 : 2);
  Polygon poly;
  poly.vertices = std::move(verts);
  poly.normal = Vec3<float>(normal);
  poly.d = float(glm::dot(normal, centroid));
  poly.drop_axis = drop;
  poly.axis_u = (drop + 1) % 3;
  poly.axis_v = (drop + 2) % 3;
  poly.plane_deviation = float(deviation);
  return poly;
}

namespace {

// Padding of the bounds: hits lie on the best-fit plane, up to sqrt(3) x deviation off the
// vertices along the dropped axis, plus the float rounding of normal and d.
float bounds_pad(const Polygon& poly) {
  float extent = 0;
  for (const Vec3<float>& p : poly.vertices)
    extent = std::max({extent, std::abs(p.x), std::abs(p.y), std::abs(p.z)});
  return 2 * poly.plane_deviation + 8 * std::numeric_limits<float>::epsilon() * extent;
}

}  // namespace

Vec3<float> polygon_lo(const Polygon& poly) {
  Vec3<float> lo(std::numeric_limits<float>::infinity());
  for (const Vec3<float>& p : poly.vertices) lo = glm::min(lo, p);
  return lo - bounds_pad(poly);
}

Vec3<float> polygon_hi(const Polygon& poly) {
  Vec3<float> hi(-std::numeric_limits<float>::infinity());
  for (const Vec3<float>& p : poly.vertices) hi = glm::max(hi, p);
  return hi + bounds_pad(poly);
}

}  // namespace volley::core
