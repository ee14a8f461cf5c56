// Shading of a whole stream of hits, several at a time in SIMD lanes, for the pipeline a
// scene gets when it has no mirrors, no refraction and no per-corner normals: then the
// surface point and Phong direct light of every hit are the same straight-line code (no
// per-material branches into reflection or refraction rays, no normal interpolation), so
// the hits can share vector registers. The general pipeline must branch per hit and
// shades one at a time (integrator.h).
#pragma once
#include <cstddef>
#include <glm/glm.hpp>
#include <vector>

#include "render/integrator.h"

namespace volley::render {

/// Shades hits[0, n) of paths[0, n) as the one-at-a-time shader `one` of the same stages
/// would, hit by hit, bit for bit: surface point and direct light by the same float
/// operations in the same order (the build does not contract them), then `then` (the
/// integrator's continuation for these stages) per hit. So the images are identical to the
/// general pipeline's. Adds each path's light to sum[path.pixel] and appends shadow queries
/// and next-bounce rays in the one-at-a-time loop's order. Misses and polygon hits go to `one`.
/// Precondition: batch_shadable(stages).
void shade_batch(const Scene& scene, unsigned stages, ShadeFn one, ContinueFn then, const PathState* paths,
                 const Hit* hits, std::size_t n, int max_depth, std::vector<PathState>& next,
                 std::vector<ShadowQuery>& shadows, glm::vec3* sum);

}  // namespace volley::render
