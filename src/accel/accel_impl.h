// Accel's private state and query paths. One BVH over triangles and one over polygons,
// each built only when the scene has that kind. Triangle data is kept in the layout of
// the chosen test only: with a SIMD ISA the wide BVH over triangle blocks (WideAccel);
// with Isa::scalar the oracle's binary BVH and plane precomputation for `plane`, raw
// vertices otherwise.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "accel/wide_accel.h"
#include "core/bvh.h"
#include "core/polygon.h"
#include "core/triangle.h"
#include "volley/accel.h"
#include "volley/packet.h"

namespace volley {

struct Accel::Impl {
  // Input, in prim-id order of each kind.
  std::vector<glm::vec3> triangles;  ///< 3 vertices per triangle
  std::vector<std::uint32_t> triangle_ids;
  std::vector<core::Polygon> polygons;
  std::vector<std::uint32_t> polygon_ids;
  std::uint32_t next_id = 0;

  // Committed state.
  bool committed = false;
  TriangleTest test = TriangleTest::watertight;
  Isa isa = Isa::scalar;
  bool robust = true;             ///< Options::robust: padded slab tests
  bool reference_double = false;  ///< Options::reference_double (isa == scalar only)
  double build_seconds = 0.0;
  std::size_t degenerate = 0;
  core::Bvh triangle_bvh;  ///< scalar path only (the SIMD path keeps the wide BVH)
  core::Bvh polygon_bvh;
  core::BvhBuildOptions build_options;          ///< of the triangle BVH
  core::BvhStats triangle_stats;                 ///< of the binary triangle BVH, as built
  std::vector<core::PlaneTriangle<float>> plane_triangles;  ///< scalar `plane` only
  /// `plane` with reference_double only: the planes of the widened vertices.
  std::vector<core::PlaneTriangle<double>> plane_triangles_double;
  /// SIMD path (isa != scalar): the wide BVH over triangle blocks.
  std::unique_ptr<accel::WideAccel> wide;
  /// `wide` when it holds the whole scene (no polygons), else null: Accel's single-ray
  /// queries call it directly (one call per ray less).
  const accel::WideAccel* wide_only = nullptr;

  void build();
  Hit intersect(const Ray& ray) const;
  bool occluded(const Ray& ray) const;
  template <int K>
  void intersect(const RayPacket<K>& rays, HitPacket<K>& hits) const;
  template <int K>
  std::uint32_t occluded(const RayPacket<K>& rays) const;
  void intersect(const Ray* rays, std::size_t count, Hit* hits) const;
  void occluded(const Ray* rays, std::size_t count, std::uint8_t* blocked) const;
  AccelInfo info() const;

 private:
  template <bool AnyHit, bool Robust>
  bool trace_triangles_scalar(const core::RayT<float>& ray, Hit& hit) const;
  /// The reference: the triangle test in double on the widened ray, t, u, v rounded to float.
  template <bool AnyHit>
  bool trace_triangles_double(const core::RayT<float>& ray, Hit& hit) const;
  /// Polygons nearer than `tmax`: updates `hit` (closest) or answers at the first one.
  template <bool AnyHit, bool Robust>
  bool trace_polygons_as(const core::RayT<float>& ray, Hit& hit) const;
  /// trace_polygons_as with the committed `robust`.
  template <bool AnyHit>
  bool trace_polygons(const core::RayT<float>& ray, Hit& hit) const;
  template <bool AnyHit>
  bool trace(const Ray& ray, Hit& hit) const;
};

}  // namespace volley
