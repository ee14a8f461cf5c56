// volley public API: rays and hits in array-of-structures form (the API boundary).
// C++17-compatible; depends on the standard library only.
#pragma once
#include <cstdint>
#include <limits>

namespace volley {

/// Prim id reported for a miss.
inline constexpr std::uint32_t kInvalidPrim = 0xffffffffu;
/// Geometry id of a miss, and instance id of a miss or of a hit not made through an
/// instance.
inline constexpr std::uint32_t kInvalidId = 0xffffffffu;

/// The default geometry mask, and the ray mask of the queries that take none: every bit.
/// A ray sees a geometry when their masks share a bit (Accel::set_geometry_mask).
inline constexpr std::uint32_t kMaskAll = 0xffffffffu;

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
/// triangle's second and third vertex (p = (1-u-v) p0 + u p1 + v p2), the geometry hit
/// (the id its add_triangles / add_polygon call returned) and the primitive's index within
/// it (triangle i of that call; 0 for a polygon), as Embree's geomID and primID. A miss has
/// t = +inf, prim = kInvalidPrim and geom = kInvalidId. Polygons report u = v = 0. Same
/// layout as a `.vhit` record (24 bytes).
struct Hit {
  float t = std::numeric_limits<float>::infinity();  ///< distance in units of |dir| (4 bytes)
  float u = 0.0f;                                     ///< barycentric weight of the second vertex (4 bytes)
  float v = 0.0f;                                     ///< barycentric weight of the third vertex (4 bytes)
  std::uint32_t prim = kInvalidPrim;                  ///< primitive within its geometry; kInvalidPrim: a miss (4 bytes)
  std::uint32_t geom = kInvalidId;                    ///< geometry id; kInvalidId for a miss (4 bytes)
  std::uint32_t inst = kInvalidId;                    ///< instance id; kInvalidId when not through an instance (4 bytes)
  /// True for a hit, false for a miss.
  bool hit() const { return prim != kInvalidPrim; }
};
static_assert(sizeof(Hit) == 24, "Hit is a .vhit record");

/// What varies between the calls of a batch query (as Embree 4's RTCIntersectArguments):
/// Accel::intersect(rays, count, hits, args) and occluded(rays, count, blocked, args).
struct QueryArguments {
  /// One ray mask per ray (Accel::set_geometry_mask), or null: every geometry whose mask is not 0.
  const std::uint32_t* masks = nullptr;
  /// One hit per ray whose primitive that ray passes over (Accel::intersect_excluding), or
  /// null: nothing left out.
  const Hit* excluded = nullptr;
  /// 0: the caller's oneTBB arena (all cores by default), 1: the calling thread, n > 1:
  /// exactly n threads. Negative: Error.
  int threads = 0;
};

/// What the single-ray walk of the wide BVH visits for one ray (Accel::walk_counts): the
/// interior nodes whose children it tests, the leaves it opens and the triangles of their
/// blocks (padding lanes left out).
struct WalkCounts {
  std::uint64_t nodes = 0;
  std::uint64_t leaves = 0;
  std::uint64_t triangles = 0;
};

}  // namespace volley
