// Local Phong shading of the notes with hard shadows: for each point light,
// (kd max(0, n.l) + ks max(0, r.v)^alpha) I / r^2 when the light is visible. Visibility is
// decided later by tracing the shadow rays of a whole tile as one occlusion stream.
#pragma once
#include <vector>

#include <glm/glm.hpp>

#include "render/path_state.h"
#include "render/scene.h"

namespace volley::render {

/// Appends one shadow query per point light that can light s as seen along view_dir,
/// each carrying weight * (its Phong term). Intensities are in units where a unit-albedo
/// Lambertian surface facing a light of intensity I at distance r has radiance I / r^2.
void queue_direct_lighting(const Scene& scene, const SurfacePoint& s, const glm::vec3& view_dir,
                           const glm::vec3& weight, std::uint32_t pixel, std::vector<ShadowQuery>& out);

}  // namespace volley::render
