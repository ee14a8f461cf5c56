// Path tracing for diffuse interreflection (Kajiya 1986), next-event estimation to the
// point lights, one scattering event per vertex chosen by albedo.
#include <cmath>

#include "render/integrator.h"
#include "render/lighting.h"
#include "render/optics.h"
#include "render/spawn.h"

namespace volley::render {
namespace {

float luminance(const glm::vec3& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

// Cosine-weighted direction about unit n (Malley's method).
glm::vec3 cosine_direction(const glm::vec3& n, Rng& rng) {
  const float r = std::sqrt(rng.uniform());
  const float phi = 6.28318530718f * rng.uniform();
  // Orthonormal basis (Duff et al. 2017).
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float b = n.x * n.y * a;
  const glm::vec3 t(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
  const glm::vec3 bt(b, sign + n.y * n.y * a, -n.y);
  const float z = std::sqrt(std::max(0.0f, 1.0f - r * r));
  return glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * bt + z * n);
}

}  // namespace

glm::vec3 trace_path(const Scene& scene, const Ray& camera_ray, int max_depth, Rng& rng, RayStats& stats) {
  glm::vec3 radiance(0.0f);
  glm::vec3 throughput(1.0f);
  Ray ray = camera_ray;
  for (int depth = 0;; ++depth) {
    const Hit hit = scene.accel().intersect(ray);
    if (!hit.hit()) {
      radiance += throughput * scene.background();
      break;
    }
    const glm::vec3 d = glm::normalize(glm::vec3(ray.dir[0], ray.dir[1], ray.dir[2]));
    const SurfacePoint s = scene.surface(ray, hit);
    const io::Material& m = scene.materials()[s.material];
    radiance += throughput * (m.emission + direct_lighting(scene, s, d, stats));
    if (depth >= max_depth) break;

    // Pick one event with probability albedo_i / max(sum, 1): absorption takes the rest,
    // and the weight albedo_i / P(i) keeps the estimate unbiased.
    const float pd = luminance(m.diffuse), pm = luminance(m.mirror), pt = luminance(m.transmittance);
    float scale = std::max(pd + pm + pt, 1.0f);
    if (depth >= 3) {  // Russian roulette on the path throughput
      const float q = std::min(0.95f, std::max(throughput.r, std::max(throughput.g, throughput.b)));
      if (rng.uniform() >= q) break;
      throughput /= q;
    }
    const float x = rng.uniform() * scale;
    glm::vec3 w;
    if (x < pd) {
      w = cosine_direction(s.ns, rng);
      if (glm::dot(w, s.ng) <= 0.0f) break;  // shading normal sent it below the surface
      throughput *= m.diffuse * (scale / pd);
      stats.add(RayKind::diffuse);
    } else if (x < pd + pm) {
      w = reflect(d, s.ns);
      if (glm::dot(w, s.ng) <= 0.0f) w = reflect(d, s.ng);
      throughput *= m.mirror * (scale / pm);
      stats.add(RayKind::reflection);
    } else if (x < pd + pm + pt) {
      const float eta_i = s.front ? 1.0f : m.ior;
      const float eta_t = s.front ? m.ior : 1.0f;
      const auto t = refract(d, s.ns, eta_i, eta_t);
      const float f = t ? schlick(-glm::dot(d, s.ns), -glm::dot(*t, s.ns), eta_i, eta_t) : 1.0f;
      if (rng.uniform() < f) {
        w = reflect(d, s.ns);
        if (glm::dot(w, s.ng) <= 0.0f) w = reflect(d, s.ng);
        stats.add(RayKind::reflection);
      } else {
        w = *t;
        stats.add(RayKind::refraction);
      }
      throughput *= m.transmittance * (scale / pt);
    } else {
      break;  // absorbed
    }
    ray = spawn_ray(s.p, s.p_error, s.ng, w);
  }
  return radiance;
}

}  // namespace volley::render
