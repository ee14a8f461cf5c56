// The flat-box stress scene shared by the binary and the wide BVH tests: a floor of unit
// quads at z = 0 (boxes flat in z) and walls in the planes x = 4, 8, ... and y = 4, 8, ...;
// axis-aligned rays (the other components +0 or -0) from integer and half-integer
// coordinates run exactly in slab planes and through shared edges and vertices, where
// 0 * inf = NaN decides whether a node is culled.
#pragma once
#include <glm/vec3.hpp>
#include <vector>

namespace volley::test {

/// Adds the triangles of a g x g grid and its walls to `soup` (soup.add(a, b, c)) and
/// returns the rays aimed along an axis through them, each made by make_ray(origin, direction).
template <class Ray, class Soup, class MakeRay>
std::vector<Ray> slab_plane_grid(int g, Soup& soup, MakeRay&& make_ray) {
  auto quad = [&](glm::vec3 p, glm::vec3 e1, glm::vec3 e2) {
    soup.add(p, p + e1, p + e1 + e2);
    soup.add(p, p + e1 + e2, p + e2);
  };
  for (int i = 0; i < g; ++i)
    for (int j = 0; j < g; ++j) quad({float(i), float(j), 0}, {1, 0, 0}, {0, 1, 0});
  for (int w = 4; w < g; w += 4)
    for (int j = 0; j < g; ++j)
      for (int k = -2; k < 2; ++k) {
        quad({float(w), float(j), float(k)}, {0, 1, 0}, {0, 0, 1});
        quad({float(j), float(w), float(k)}, {1, 0, 0}, {0, 0, 1});
      }
  std::vector<Ray> rays;
  auto add_ray = [&](glm::vec3 o, glm::vec3 d) { rays.push_back(make_ray(o, d)); };
  for (float zero : {0.0f, -0.0f})
    for (int a = 0; a <= 2 * g; ++a)
      for (int b = -4; b <= 4; ++b) {
        const float x = 0.5f * a, h = 0.5f * b;
        add_ray(glm::vec3{x, 0.5f * float(a / 2 + b + 4), 5}, glm::vec3{zero, zero, -1});  // down
        add_ray(glm::vec3{x, x, 5}, glm::vec3{zero, zero, -2});                            // down, diagonal
        add_ray(glm::vec3{-1, x, h}, glm::vec3{1, zero, zero});                            // +x to the walls
        add_ray(glm::vec3{x, float(g) + 1.0f, h}, glm::vec3{zero, -1, zero});              // -y to the walls
        add_ray(glm::vec3{x, 0.5f * float(b + 4), 0}, glm::vec3{1, zero, zero});           // in the floor plane
      }
  return rays;
}

}  // namespace volley::test
