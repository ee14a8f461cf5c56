#include "render/lighting.h"

#include <cmath>

#include "render/optics.h"
#include "render/spawn.h"

namespace volley::render {

void queue_direct_lighting(const Scene& scene, const SurfacePoint& s, const glm::vec3& view_dir,
                           const glm::vec3& weight, std::uint32_t pixel, std::vector<ShadowQuery>& out) {
  const io::Material& m = scene.materials()[s.material];
  const bool specular = m.specular != glm::vec3(0.0f);
  if (m.diffuse == glm::vec3(0.0f) && !specular) return;  // nothing to light
  for (const io::PointLight& light : scene.lights()) {
    const glm::vec3 to_light = light.position - s.p;
    const float dist2 = glm::dot(to_light, to_light);
    const glm::vec3 l = to_light / std::sqrt(dist2);
    // Lights behind the surface (as seen by the geometric normal) cannot reach it.
    if (glm::dot(l, s.ng) <= 0.0f) continue;
    const float n_dot_l = glm::dot(s.ns, l);
    if (n_dot_l <= 0.0f) continue;
    glm::vec3 c = m.diffuse * n_dot_l;
    if (specular) {
      const float r_dot_v = glm::dot(reflect(-l, s.ns), -view_dir);
      if (r_dot_v > 0.0f) c += m.specular * std::pow(r_dot_v, m.shininess);
    }
    out.push_back({spawn_shadow_ray(s.p, s.p_error, s.ng, light.position), weight * c * light.intensity / dist2, pixel});
  }
}

}  // namespace volley::render
