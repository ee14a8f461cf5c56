// Whitted-style ray tracing with the notes' Phong model, one bounce at a time.
#include <cmath>

#include "render/integrator.h"
#include "render/lighting.h"
#include "render/optics.h"
#include "render/spawn.h"

namespace volley::render {

glm::vec3 shade_whitted(const Scene& scene, const PathState& path, const Hit& hit, int max_depth,
                        std::vector<PathState>& next, std::vector<ShadowQuery>& shadows) {
  if (!hit.hit()) return path.weight * scene.background();
  const Ray& ray = path.ray;
  const glm::vec3 d = glm::normalize(glm::vec3(ray.dir[0], ray.dir[1], ray.dir[2]));
  const SurfacePoint s = scene.surface(ray, hit);
  const io::Material& m = scene.materials()[s.material];
  queue_direct_lighting(scene, s, d, path.weight, path.pixel, shadows);
  if (int(path.depth) < max_depth) {
    auto spawn = [&](const glm::vec3& w, const glm::vec3& weight, RayKind kind) {
      next.push_back({spawn_ray(s.p, s.p_error, s.ng, w), path.weight * weight, path.pixel, path.depth + 1, kind, path.rng});
    };
    auto mirror_direction = [&]() {
      const glm::vec3 r = reflect(d, s.ns);
      return glm::dot(r, s.ng) > 0.0f ? r : reflect(d, s.ng);  // shading normal bent it below
    };
    if (m.mirror != glm::vec3(0.0f)) spawn(mirror_direction(), m.mirror, RayKind::reflection);
    if (m.transmittance != glm::vec3(0.0f)) {
      const float eta_i = s.front ? 1.0f : m.ior;
      const float eta_t = s.front ? m.ior : 1.0f;
      if (const auto t = refract(d, s.ns, eta_i, eta_t)) {
        const float f = schlick(-glm::dot(d, s.ns), -glm::dot(*t, s.ns), eta_i, eta_t);
        spawn(*t, m.transmittance * (1.0f - f), RayKind::refraction);
        spawn(mirror_direction(), m.transmittance * f, RayKind::reflection);
      } else {
        spawn(mirror_direction(), m.transmittance, RayKind::reflection);  // total internal reflection
      }
    }
  }
  return path.weight * (m.emission + m.ambient);
}

}  // namespace volley::render
