// Whitted-style recursive ray tracing (Whitted 1980) with the notes' Phong model.
#include <cmath>

#include "render/integrator.h"
#include "render/lighting.h"
#include "render/optics.h"
#include "render/spawn.h"

namespace volley::render {
namespace {

glm::vec3 trace(const Scene& scene, const Ray& ray, int depth, int max_depth, RayStats& stats) {
  const Hit hit = scene.accel().intersect(ray);
  if (!hit.hit()) return scene.background();
  const glm::vec3 d = glm::normalize(glm::vec3(ray.dir[0], ray.dir[1], ray.dir[2]));
  const SurfacePoint s = scene.surface(ray, hit);
  const io::Material& m = scene.materials()[s.material];
  glm::vec3 c = m.emission + m.ambient + direct_lighting(scene, s, d, stats);
  if (depth >= max_depth) return c;

  auto reflected = [&]() {
    glm::vec3 r = reflect(d, s.ns);
    if (glm::dot(r, s.ng) <= 0.0f) r = reflect(d, s.ng);  // shading normal bent it below
    stats.add(RayKind::reflection);
    return trace(scene, spawn_ray(s.p, s.p_error, s.ng, r), depth + 1, max_depth, stats);
  };
  if (m.mirror != glm::vec3(0.0f)) c += m.mirror * reflected();
  if (m.transmittance != glm::vec3(0.0f)) {
    const float eta_i = s.front ? 1.0f : m.ior;
    const float eta_t = s.front ? m.ior : 1.0f;
    const auto t = refract(d, s.ns, eta_i, eta_t);
    if (!t) {
      c += m.transmittance * reflected();  // total internal reflection
    } else {
      const float f = schlick(-glm::dot(d, s.ns), -glm::dot(*t, s.ns), eta_i, eta_t);
      stats.add(RayKind::refraction);
      const glm::vec3 through =
          trace(scene, spawn_ray(s.p, s.p_error, s.ng, *t), depth + 1, max_depth, stats);
      c += m.transmittance * ((1.0f - f) * through + f * reflected());
    }
  }
  return c;
}

}  // namespace

glm::vec3 trace_whitted(const Scene& scene, const Ray& ray, int max_depth, RayStats& stats) {
  return trace(scene, ray, 0, max_depth, stats);
}

}  // namespace volley::render
