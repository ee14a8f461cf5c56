// volley public API: the answer of a point query (Accel::closest_point).
#pragma once
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "volley/ray.h"

namespace volley {

/// The direction of Accel::contains' ray (nearly unit length; no axis or diagonal, so that on
/// the axis-aligned meshes common in practice it rarely meets an edge exactly, which the
/// crossing rule would decide anyway).
inline constexpr float kContainsDirection[3] = {0.43678f, 0.59234f, 0.67707f};

/// The nearest point of the scene's surface to a query point (as Open3D's
/// RaycastingScene.compute_closest_points). 32 bytes.
struct ClosestPoint {
  float point[3] = {0.0f, 0.0f, 0.0f};                       ///< the nearest surface point (12 bytes)
  float distance = std::numeric_limits<float>::infinity();  ///< to it; +inf when nothing lies within the search radius
  float u = 0.0f;                                           ///< barycentric weight of the triangle's second vertex (0 for a polygon)
  float v = 0.0f;                                           ///< of its third vertex (0 for a polygon)
  std::uint32_t prim = kInvalidPrim;                        ///< primitive within its geometry; kInvalidPrim: none found
  std::uint32_t geom = kInvalidId;                          ///< geometry id; kInvalidId: none found
  /// True when a surface point was found.
  bool found() const { return prim != kInvalidPrim; }
};
static_assert(sizeof(ClosestPoint) == 32, "ClosestPoint: 32 bytes");

/// Every hit of a batch of rays (Accel::intersect_all over an array): ray i's hits are
/// hits[offsets[i] .. offsets[i + 1]), nearest first (as Open3D's list_intersections).
struct HitLists {
  std::vector<std::size_t> offsets;  ///< rays + 1 entries
  std::vector<Hit> hits;
};

}  // namespace volley
