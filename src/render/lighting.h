// Local Phong shading of the notes with hard shadows: for each point light,
// (kd max(0, n.l) + ks max(0, r.v)^alpha) I / r^2 when the light is visible.
#pragma once
#include <glm/glm.hpp>

#include "render/scene.h"
#include "render/stats.h"

namespace volley::render {

/// Light arriving from all point lights at s and reflected toward -view_dir, shadows
/// tested with occlusion rays. Intensities are in units where a unit-albedo Lambertian
/// surface facing a light of intensity I at distance r has radiance I / r^2.
glm::vec3 direct_lighting(const Scene& scene, const SurfacePoint& s, const glm::vec3& view_dir,
                          RayStats& stats);

}  // namespace volley::render
