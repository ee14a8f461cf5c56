// Whitted-style ray tracing with the notes' Phong model, one bounce at a time.
#include <cmath>

#include "render/optics.h"
#include "render/shading_step.h"
#include "render/spawn.h"

namespace volley::render {

namespace {

struct Whitted {
  template <unsigned Stages>
  static glm::vec3 then(const Scene& scene, const PathState& path, const SurfacePoint& s, const glm::vec3& d,
                        int max_depth, std::vector<PathState>& next);
};

template <unsigned Stages>
glm::vec3 Whitted::then(const Scene& scene, const PathState& path, const SurfacePoint& s, const glm::vec3& d,
                        int max_depth, std::vector<PathState>& next) {
  const io::Material& m = scene.materials()[s.material];
  if constexpr ((Stages & (kMirrors | kRefraction)) != 0) {
    if (int(path.depth) >= max_depth) return path.weight * (m.emission + m.ambient);
    auto spawn = [&](const glm::vec3& w, const glm::vec3& weight, RayKind kind) {
      next.push_back(
          {spawn_ray(s.p, s.p_error, s.ng, w), path.weight * weight, path.pixel, path.depth + 1, kind, path.rng});
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

}  // namespace

ShadeFn whitted_shader(unsigned stages) { return shader_for<Whitted>(stages); }
ContinueFn whitted_continuation(unsigned stages) { return continuation_for<Whitted>(stages); }

}  // namespace volley::render
