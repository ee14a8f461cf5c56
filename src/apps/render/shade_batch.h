// Shading of a whole stream of hits in SIMD lanes, for the pipeline a scene gets when it
// has no mirrors, no refraction and no per-corner normals: then the surface point and Phong
// direct light of every hit are the same straight-line code (no per-material branches into
// reflection or refraction rays, no normal interpolation), so the hits can share vector
// registers, as wide as the CPU allows (shade_lanes.h). The general pipeline must branch
// per hit and shades one at a time (integrator.h).
#pragma once
#include <cstddef>
#include <glm/glm.hpp>
#include <vector>

#include "render/integrator.h"
#include "volley/options.h"

namespace volley::render {

/// How a specialised pipeline shades in lanes.
struct BatchShading {
  unsigned stages = 0;        ///< bits of Stage; precondition: batch_shadable(stages)
  ShadeFn one = nullptr;      ///< the one-at-a-time shader of the same stages (misses, polygon hits)
  ContinueFn then = nullptr;  ///< the integrator's continuation after direct light
  /// Whether `then` reads the surface point beyond its material: the path integrator does
  /// (it spawns the next bounce there); Whitted without mirrors or glass does not, so the
  /// point, normal and view direction are not copied out of the lanes for it.
  bool then_reads_surface = true;
  Isa isa = Isa::sse42;  ///< lane width: sse42 (4), avx2 (8) or avx512 (16); anything else runs as sse42
};

/// Shades hits[0, n) of paths[0, n) as the one-at-a-time shader would, hit by hit, bit for
/// bit: surface point and direct light by the same float operations in the same order,
/// then the continuation per hit. So the images are identical to the general pipeline's.
/// Adds each path's light to sum[path.pixel] and appends shadow queries and next-bounce
/// rays in the one-at-a-time loop's order. Misses and polygon hits go to `one`.
void shade_batch(const Scene& scene, const BatchShading& how, const PathState* paths, const Hit* hits, std::size_t n,
                 int max_depth, std::vector<PathState>& next, std::vector<ShadowQuery>& shadows, glm::vec3* sum);

}  // namespace volley::render
