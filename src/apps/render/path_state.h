// The rays in flight of the wavefront renderer: every bounce traces all live rays of a
// tile as one stream, shades the hits, and collects the next bounce's rays (dead ones
// dropped) and the shadow rays, which are traced as one occlusion stream.
#pragma once
#include <cstdint>

#include <glm/glm.hpp>

#include "render/rng.h"
#include "render/stats.h"
#include "volley/ray.h"

namespace volley::render {

/// One ray in flight and what its radiance is worth to its pixel. 80 bytes.
struct PathState {
  Ray ray;                     // 32 bytes
  glm::vec3 weight{1.0f};      // 12 bytes: throughput from this ray to the pixel
  std::uint32_t pixel = 0;     //  4 bytes: index in the tile's accumulation buffer
  std::uint32_t depth = 0;     //  4 bytes: bounces so far (0 = camera ray)
  RayKind kind = RayKind::primary;  // 4 bytes
  Rng rng{0, 0};               // 16 bytes: the path's own random stream (path integrator)
};

/// A shadow ray and the light it brings to a pixel when nothing blocks it.
struct ShadowQuery {
  Ray ray;                     // 32 bytes
  glm::vec3 contribution;      // 12 bytes
  std::uint32_t pixel;         //  4 bytes
};

}  // namespace volley::render
