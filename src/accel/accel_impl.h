// Accel's private state and query paths. One BVH over triangles and one over polygons,
// each built only when the scene has that kind. Triangle data is kept in the layout of
// the chosen test only: plane precomputation for `plane`, raw vertices otherwise.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "core/bvh.h"
#include "core/polygon.h"
#include "core/triangle.h"
#include "simd/dispatch.h"
#include "simd/triangle_kernels.h"
#include "volley/accel.h"

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
  double build_seconds = 0.0;
  std::size_t degenerate = 0;
  core::Bvh triangle_bvh;
  core::Bvh polygon_bvh;
  core::BvhBuildOptions build_options;
  std::vector<core::PlaneTriangle<float>> plane_triangles;  ///< scalar `plane` only
  /// SIMD path (isa != scalar): triangle blocks per BVH leaf, indexed by node.
  std::unique_ptr<simd::TriangleKernels> kernels;
  std::vector<simd::BlockRange> node_blocks;

  void build();
  Hit intersect(const Ray& ray) const;
  bool occluded(const Ray& ray) const;
  AccelInfo info() const;

 private:
  void build_blocks();
  template <bool AnyHit>
  bool trace_triangles_scalar(const core::RayT<float>& ray, Hit& hit) const;
  template <bool AnyHit>
  bool trace_triangles_simd(const Ray& ray, Hit& hit) const;
  template <bool AnyHit>
  bool trace(const Ray& ray, Hit& hit) const;
};

}  // namespace volley
