// volley public API: rays and hits in array-of-structures form (the API boundary).
// C++17-compatible; depends on the standard library only.
#pragma once
#include <cstdint>
#include <limits>

namespace volley {

/// Prim id reported for a miss.
inline constexpr std::uint32_t kInvalidPrim = 0xffffffffu;

/// One ray: r(t) = org + t * dir, searched over tmin <= t < tmax.
/// The direction need not be normalized; t is in units of |dir|.
/// Same field order as a `.vray` record (32 bytes).
struct Ray {
  float org[3];  ///< origin (12 bytes)
  float tmin;    ///< start of the search interval, inclusive (4 bytes)
  float dir[3];  ///< direction, not necessarily normalized (12 bytes)
  float tmax;    ///< end of the search interval, exclusive (4 bytes)
};
static_assert(sizeof(Ray) == 32, "Ray is a .vray record");

/// Closest-hit answer: t along the ray, barycentrics (u, v) of the hit relative to the
/// triangle's second and third vertex (p = (1-u-v) p0 + u p1 + v p2), and the prim id
/// the primitive was given when added. A miss has t = +inf and prim = kInvalidPrim.
/// Polygons report u = v = 0. Same layout as a `.vhit` record (16 bytes).
struct Hit {
  float t = std::numeric_limits<float>::infinity();  ///< distance in units of |dir| (4 bytes)
  float u = 0.0f;                                     ///< barycentric weight of the second vertex (4 bytes)
  float v = 0.0f;                                     ///< barycentric weight of the third vertex (4 bytes)
  std::uint32_t prim = kInvalidPrim;                  ///< prim id, kInvalidPrim for a miss (4 bytes)
  /// True for a hit, false for a miss.
  bool hit() const { return prim != kInvalidPrim; }
};
static_assert(sizeof(Hit) == 16, "Hit is a .vhit record");

}  // namespace volley
