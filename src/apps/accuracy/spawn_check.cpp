#include "accuracy/spawn_check.h"

#include <cmath>
#include <random>

#include <glm/glm.hpp>

#include "render/spawn.h"
#include "volley/accel.h"

namespace volley::accuracy {

SpawnRow spawn_check(float scale, std::size_t count, Isa isa, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> uni(0.0f, 1.0f);
  // A tilted triangle far from the origin at this scale.
  const glm::vec3 p0 = glm::vec3(0.3f, 0.1f, 0.7f) * scale, p1 = glm::vec3(1.2f, 0.4f, 0.9f) * scale,
                  p2 = glm::vec3(0.5f, 1.3f, 0.2f) * scale;
  Accel accel;
  const float xyz[] = {p0.x, p0.y, p0.z, p1.x, p1.y, p1.z, p2.x, p2.y, p2.z};
  const std::uint32_t idx[] = {0, 1, 2};
  accel.add_triangles(xyz, 3, idx, 1);
  Options options;
  options.isa = isa;
  accel.commit(options);
  const glm::vec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
  SpawnRow row{scale, isa, 0, 0};
  while (row.spawned < count) {
    // A ray from a random point above the triangle to a random point on it.
    float u = uni(rng), v = uni(rng);
    if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
    const glm::vec3 target = (1 - u - v) * p0 + u * p1 + v * p2;
    const glm::vec3 org =
        target + n * scale * (uni(rng) + 0.1f) + glm::vec3(uni(rng), uni(rng), uni(rng)) * scale * 0.2f;
    const Ray ray{{org.x, org.y, org.z}, 0.0f, {target.x - org.x, target.y - org.y, target.z - org.z}, INFINITY};
    const Hit hit = accel.intersect(ray);
    if (!hit.hit()) continue;
    // The hit point and its error bound as the renderer computes them (Scene::surface_as).
    glm::vec3 err;
    const glm::vec3 p = render::hit_point(p0, p1, p2, hit.u, hit.v, err);
    const glm::vec3 ng = glm::dot(n, glm::vec3(ray.dir[0], ray.dir[1], ray.dir[2])) < 0 ? n : -n;
    // A random direction on either side.
    const glm::vec3 w(uni(rng) - 0.5f, uni(rng) - 0.5f, uni(rng) - 0.5f);
    if (glm::length(w) < 1e-3f) continue;
    ++row.spawned;
    row.rehits += accel.occluded(render::spawn_ray(p, err, ng, glm::normalize(w))) ? 1 : 0;
  }
  return row;
}

}  // namespace volley::accuracy
