// Path tracing for diffuse interreflection, next-event estimation to the point lights,
// one scattering event per vertex chosen by albedo.
#include <cmath>

#include "render/optics.h"
#include "render/sampling.h"
#include "render/shading_step.h"
#include "render/spawn.h"

namespace volley::render {

namespace {

struct Path {
  template <unsigned Stages>
  static glm::vec3 then(const Scene& scene, const PathState& path, const SurfacePoint& s, const glm::vec3& d,
                        int max_depth, std::vector<PathState>& next);
};

template <unsigned Stages>
glm::vec3 Path::then(const Scene& scene, const PathState& path, const SurfacePoint& s, const glm::vec3& d,
                     int max_depth, std::vector<PathState>& next) {
  const io::Material& m = scene.materials()[s.material];
  const glm::vec3 emitted = path.weight * m.emission;
  if (int(path.depth) >= max_depth) return emitted;

  PathState out{path.ray, path.weight, path.pixel, path.depth + 1, RayKind::diffuse, path.rng};
  Rng& rng = out.rng;
  // Pick one event with probability albedo_i / max(sum, 1): absorption takes the rest,
  // and the weight albedo_i / P(i) keeps the estimate unbiased.
  // Stages left out have zero albedo in every material of the scene.
  const float pd = luminance(m.diffuse);
  const float pm = (Stages & kMirrors) != 0 ? luminance(m.mirror) : 0.0f;
  const float pt = (Stages & kRefraction) != 0 ? luminance(m.transmittance) : 0.0f;
  const float scale = std::max(pd + pm + pt, 1.0f);
  if (path.depth >= 3) {  // Russian roulette on the path throughput
    const float q = std::min(0.95f, std::max(out.weight.r, std::max(out.weight.g, out.weight.b)));
    if (rng.uniform() >= q) return emitted;
    out.weight /= q;
  }
  const float x = rng.uniform() * scale;
  glm::vec3 w;
  if (x < pd) {
    w = cosine_direction(s.ns, rng);
    if (glm::dot(w, s.ng) <= 0.0f) return emitted;  // the shading normal sent it below the surface
    out.weight *= m.diffuse * (scale / pd);
  } else if (x < pd + pm) {
    w = reflect_above(d, s.ns, s.ng);
    out.weight *= m.mirror * (scale / pm);
    out.kind = RayKind::reflection;
  } else if (x < pd + pm + pt) {
    const Refraction r = refraction(d, s.ns, s.front, m.ior);
    if (rng.uniform() < r.reflectance) {  // always on total internal reflection
      w = reflect_above(d, s.ns, s.ng);
      out.kind = RayKind::reflection;
    } else {
      w = *r.dir;
      out.kind = RayKind::refraction;
    }
    out.weight *= m.transmittance * (scale / pt);
  } else {
    return emitted;  // absorbed
  }
  out.ray = spawn_ray(s.p, s.p_error, s.ng, w);
  next.push_back(out);
  return emitted;
}

}  // namespace

ShadeFn path_shader(unsigned stages) { return shader_for<Path>(stages); }
ContinueFn path_continuation(unsigned stages) { return continuation_for<Path>(stages); }

}  // namespace volley::render
