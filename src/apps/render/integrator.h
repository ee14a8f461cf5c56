// The two integrators as shading steps of the wavefront renderer: each takes one traced
// ray and its hit, returns the light that reaches the pixel directly (already weighted),
// and queues shadow rays and the rays of the next bounce.
#pragma once
#include <vector>

#include <glm/glm.hpp>

#include "render/path_state.h"
#include "render/pipeline.h"
#include "render/scene.h"

namespace volley::render {

enum class IntegratorKind { whitted, path };

/// One shading step: the light `path` brings to its pixel directly (already weighted);
/// shadow queries and next-bounce rays are appended.
using ShadeFn = glm::vec3 (*)(const Scene& scene, const PathState& path, const Hit& hit, int max_depth,
                              std::vector<PathState>& next, std::vector<ShadowQuery>& shadows);

// The integrators (whitted.cpp, path.cpp), each a continuation after direct light:
// Whitted (1980), the notes' ray tracer: emission + ambient + Phong from each visible
// light, plus a mirror ray and Fresnel-weighted (Schlick) refraction and reflection rays,
// total internal reflection handled, up to max_depth bounces.
// Path tracing (Kajiya 1986): emission + Phong direct light from the point lights (next
// event estimation), then one scattering event chosen by albedo: cosine-weighted diffuse,
// mirror, or Fresnel-chosen reflection/refraction; Russian roulette after 3 bounces. No
// ambient term: indirect light replaces it.
// Both are compiled per stage set (bits of Stage), leaving out what a scene does not use.

/// What an integrator does at a shaded surface point after queuing its direct light: the
/// light the point adds to the pixel (emission, ambient) and the next bounce's rays.
/// `view_dir` is the unit direction of the incoming ray. A shading step is surface point,
/// direct light, then this (the batch shader of shade_batch.h does the first two in SIMD).
using ContinueFn = glm::vec3 (*)(const Scene& scene, const PathState& path, const SurfacePoint& s,
                                 const glm::vec3& view_dir, int max_depth, std::vector<PathState>& next);

/// Whether the continuation of `kind` for `stages` reads the surface point beyond its
/// material: Whitted without mirrors or glass only adds emission and ambient light.
constexpr bool continuation_reads_surface(IntegratorKind kind, unsigned stages) {
  return kind == IntegratorKind::path || (stages & (kMirrors | kRefraction)) != 0;
}

/// The shading function of `kind` compiled for `stages` (any subset of kAllStages).
ShadeFn whitted_shader(unsigned stages);
ShadeFn path_shader(unsigned stages);
/// Their continuations after direct light, for the same stages.
ContinueFn whitted_continuation(unsigned stages);
ContinueFn path_continuation(unsigned stages);

}  // namespace volley::render
