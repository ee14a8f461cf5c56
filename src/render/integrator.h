// The two integrators: Whitted (the notes' recursive ray tracer) and a path tracer for
// diffuse interreflection. Both take a camera ray and return linear RGB radiance.
#pragma once
#include <glm/glm.hpp>

#include "render/rng.h"
#include "render/scene.h"
#include "render/stats.h"

namespace volley::render {

enum class IntegratorKind { whitted, path };

/// Whitted: emission + ambient + Phong from each visible light, plus mirror reflection
/// and Fresnel-weighted refraction (total internal reflection handled) recursively up to
/// max_depth bounces.
glm::vec3 trace_whitted(const Scene& scene, const Ray& ray, int max_depth, RayStats& stats);

/// Path tracing: at each vertex emission + Phong direct light from the point lights (next
/// event estimation), then one scattering event chosen by albedo: cosine-weighted diffuse,
/// mirror, or Fresnel-chosen reflection/refraction; Russian roulette after 3 bounces.
/// No ambient term: indirect light replaces it.
glm::vec3 trace_path(const Scene& scene, const Ray& ray, int max_depth, Rng& rng, RayStats& stats);

}  // namespace volley::render
