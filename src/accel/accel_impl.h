// Accel's private state: the geometry as added, and at commit one triangle engine (the
// wide SIMD BVH, the scalar oracle or the double reference: engine.h) and one polygon
// engine, each only when the scene has that kind, combined once: triangles, then polygons.
#pragma once
#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "accel/engine.h"
#include "accel/wide_accel.h"
#include "core/bvh.h"
#include "core/polygon.h"
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
  core::BvhStats triangle_stats;  ///< of the binary triangle BVH, as built (unit costs)
  std::unique_ptr<accel::TriangleEngine> triangle_engine;
  std::unique_ptr<accel::Engine> polygon_engine;
  /// The wide BVH when it holds the whole scene (no polygons), else null: Accel's single-ray
  /// queries and full packets call it directly (a layer of calls less).
  const accel::WideAccel* wide_only = nullptr;

  void build();
  Hit intersect(const Ray& ray) const;
  bool occluded(const Ray& ray) const;
  template <int K>
  void intersect(const RayPacket<K>& rays, HitPacket<K>& hits) const;
  template <int K>
  std::uint32_t occluded(const RayPacket<K>& rays) const;
  /// The stream policy (stream.cpp): runs of 16 rays as packets where that pays.
  void intersect(const Ray* rays, std::size_t count, Hit* hits) const;
  void occluded(const Ray* rays, std::size_t count, std::uint8_t* blocked) const;
  AccelInfo info() const;
};

}  // namespace volley
