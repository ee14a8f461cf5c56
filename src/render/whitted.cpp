// Whitted-style ray tracing with the notes' Phong model, one bounce at a time.
#include <array>
#include <cmath>
#include <utility>

#include "render/integrator.h"
#include "render/lighting.h"
#include "render/optics.h"
#include "render/spawn.h"

namespace volley::render {

template <unsigned Stages>
glm::vec3 continue_whitted(const Scene& scene, const PathState& path, const SurfacePoint& s, const glm::vec3& d,
                           int max_depth, std::vector<PathState>& next) {
  const io::Material& m = scene.materials()[s.material];
  if constexpr ((Stages & (kMirrors | kRefraction)) != 0) {
    if (int(path.depth) >= max_depth) return path.weight * (m.emission + m.ambient);
    auto spawn = [&](const glm::vec3& w, const glm::vec3& weight, RayKind kind) {
      next.push_back({spawn_ray(s.p, s.p_error, s.ng, w), path.weight * weight, path.pixel, path.depth + 1, kind, path.rng});
    };
    const glm::vec3 mirror = reflect_above(d, s.ns, s.ng);
    if constexpr ((Stages & kMirrors) != 0)
      if (m.mirror != glm::vec3(0.0f)) spawn(mirror, m.mirror, RayKind::reflection);
    if ((Stages & kRefraction) != 0 && m.transmittance != glm::vec3(0.0f)) {
      const Refraction r = refraction(d, s.ns, s.front, m.ior);
      if (r.dir) spawn(*r.dir, m.transmittance * (1.0f - r.reflectance), RayKind::refraction);
      spawn(mirror, m.transmittance * r.reflectance, RayKind::reflection);  // all of it on TIR
    }
  }
  return path.weight * (m.emission + m.ambient);
}

template <unsigned Stages>
glm::vec3 shade_whitted(const Scene& scene, const PathState& path, const Hit& hit, int max_depth,
                        std::vector<PathState>& next, std::vector<ShadowQuery>& shadows) {
  if (!hit.hit()) return path.weight * scene.background();
  const Ray& ray = path.ray;
  const glm::vec3 d = glm::normalize(glm::vec3(ray.dir[0], ray.dir[1], ray.dir[2]));
  const SurfacePoint s = scene.surface_as<(Stages & kSmoothNormals) != 0>(ray, hit);
  if constexpr ((Stages & kShadows) != 0) queue_direct_lighting(scene, s, d, path.weight, path.pixel, shadows);
  return continue_whitted<Stages>(scene, path, s, d, max_depth, next);
}

namespace {
template <std::size_t... S>
constexpr std::array<ShadeFn, sizeof...(S)> whitted_table(std::index_sequence<S...>) {
  return {&shade_whitted<unsigned(S)>...};
}
template <std::size_t... S>
constexpr std::array<ContinueFn, sizeof...(S)> continue_table(std::index_sequence<S...>) {
  return {&continue_whitted<unsigned(S)>...};
}
}  // namespace

ShadeFn whitted_shader(unsigned stages) {
  static constexpr auto table = whitted_table(std::make_index_sequence<kAllStages + 1>{});
  return table[stages & kAllStages];
}

ContinueFn whitted_continuation(unsigned stages) {
  static constexpr auto table = continue_table(std::make_index_sequence<kAllStages + 1>{});
  return table[stages & kAllStages];
}

}  // namespace volley::render
