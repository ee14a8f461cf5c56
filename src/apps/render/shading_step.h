// One shading step of either integrator, compiled per stage set: the surface point, its
// direct light (shadow queries), then the integrator's own continuation. An integrator
// is a type with `template <unsigned Stages> static glm::vec3 then(...)` (a ContinueFn);
// shader_for / continuation_for give the function for a stage set chosen at run time.
#pragma once
#include <array>
#include <glm/glm.hpp>
#include <utility>

#include "render/integrator.h"
#include "render/lighting.h"

namespace volley::render {

template <class Integrator, unsigned Stages>
glm::vec3 shading_step(const Scene& scene, const PathState& path, const Hit& hit, int max_depth,
                       std::vector<PathState>& next, std::vector<ShadowQuery>& shadows) {
  if (!hit.hit()) return path.weight * scene.background();
  const Ray& ray = path.ray;
  const glm::vec3 d = glm::normalize(glm::vec3(ray.dir[0], ray.dir[1], ray.dir[2]));
  const SurfacePoint s = scene.surface_as<(Stages & kSmoothNormals) != 0>(ray, hit);
  if constexpr ((Stages & kShadows) != 0) queue_direct_lighting(scene, s, d, path.weight, path.pixel, shadows);
  return Integrator::template then<Stages>(scene, path, s, d, max_depth, next);
}

namespace detail {
template <class Integrator, std::size_t... S>
constexpr std::array<ShadeFn, sizeof...(S)> shade_table(std::index_sequence<S...>) {
  return {&shading_step<Integrator, unsigned(S)>...};
}
template <class Integrator, std::size_t... S>
constexpr std::array<ContinueFn, sizeof...(S)> continue_table(std::index_sequence<S...>) {
  return {&Integrator::template then<unsigned(S)>...};
}
}  // namespace detail

template <class Integrator>
ShadeFn shader_for(unsigned stages) {
  static constexpr auto table = detail::shade_table<Integrator>(std::make_index_sequence<kAllStages + 1>{});
  return table[stages & kAllStages];
}

template <class Integrator>
ContinueFn continuation_for(unsigned stages) {
  static constexpr auto table = detail::continue_table<Integrator>(std::make_index_sequence<kAllStages + 1>{});
  return table[stages & kAllStages];
}

}  // namespace volley::render
