// The closed-and-opaque analysis (render/closed_surface.h, SceneFeatures::cull_admissible):
// closed meshes of the accuracy suite, an open quad, a flipped face, vertices split at a
// seam, a polygon cube, and glass (closed but not opaque).
#include <doctest/doctest.h>

#include <string>

#include "accuracy/closed_meshes.h"
#include "render/closed_surface.h"
#include "render/pipeline.h"
#include "render/scene.h"

using namespace volley;

namespace {

io::SceneDesc scene_of(const accuracy::Mesh& mesh) {
  io::SceneDesc desc;
  desc.materials.push_back(io::Material{"grey"});
  for (std::size_t v = 0; v < mesh.vertices(); ++v)
    desc.mesh.positions.push_back({mesh.xyz[3 * v], mesh.xyz[3 * v + 1], mesh.xyz[3 * v + 2]});
  desc.mesh.indices = mesh.idx;
  desc.mesh.material.assign(mesh.triangles(), 0);
  return desc;
}

render::SceneFeatures features_of(const io::SceneDesc& desc) {
  return render::with_closure(render::Scene(desc, 16, 16, Options{}), desc);
}

// accuracy::grid_cube winds the faces at both levels of an axis alike (the leak tests need
// no orientation), so three faces are wound against the other three: flip those.
accuracy::Mesh oriented_cube(int n) {
  accuracy::Mesh cube = accuracy::grid_cube(n).mesh;
  const std::size_t per_face = 2 * std::size_t(n) * std::size_t(n);  // faces in order: axis, then level 0, n
  for (std::size_t t = 0; t < cube.triangles(); ++t)
    if ((t / per_face) % 2 == 0) std::swap(cube.idx[3 * t + 1], cube.idx[3 * t + 2]);
  return cube;
}

// The six faces of the unit cube as polygons, counter-clockwise seen from outside.
std::vector<io::PolygonDesc> polygon_cube() {
  const glm::vec3 c[8] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  const int faces[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 4, 7, 3}, {1, 2, 6, 5}};
  std::vector<io::PolygonDesc> out;
  for (const auto& f : faces) out.push_back({"face", {c[f[0]], c[f[1]], c[f[2]], c[f[3]]}, 0});
  return out;
}

}  // namespace

TEST_CASE("scene analysis: closed meshes of the accuracy suite, consistently oriented, are closed and opaque") {
  for (const accuracy::Mesh& closed : {oriented_cube(3), accuracy::icosphere(2, 64.0).mesh}) {
    CAPTURE(closed.triangles());
    const render::SceneFeatures f = features_of(scene_of(closed));
    CHECK(f.closed);
    CHECK(f.open_edges == 0);
    CHECK(f.cull_admissible());
    CHECK(render::describe_culling(f).find("admissible (all geometry closed, all materials opaque), not used: ") !=
          std::string::npos);
  }
}

TEST_CASE("scene analysis: a single quad is open") {
  accuracy::Mesh quad;
  const auto a = quad.vertex(0, 0, 0), b = quad.vertex(1, 0, 0), c = quad.vertex(1, 1, 0), d = quad.vertex(0, 1, 0);
  quad.triangle(a, b, c);
  quad.triangle(a, c, d);
  const render::SceneFeatures f = features_of(scene_of(quad));
  CHECK_FALSE(f.closed);
  CHECK(f.open_edges == 4);  // the diagonal is matched, the four sides are not
  CHECK_FALSE(f.cull_admissible());
  CHECK(render::describe_culling(f) ==
        "back-face culling not admissible: open geometry (4 edges without one opposite partner)");
}

TEST_CASE("scene analysis: inward faces, a flipped face, a missing face and a doubled surface make a mesh not closed") {
  const accuracy::Mesh cube = oriented_cube(2);
  REQUIRE(features_of(scene_of(cube)).closed);
  // grid_cube itself: closed, but three faces wound inward.
  const render::SceneFeatures inward = features_of(scene_of(accuracy::grid_cube(2).mesh));
  CHECK_FALSE(inward.closed);
  CHECK(inward.open_edges == 24);  // the 12 cube edges, 2 segments each, both directions
  accuracy::Mesh flipped = cube;
  std::swap(flipped.idx[0], flipped.idx[1]);
  CHECK_FALSE(features_of(scene_of(flipped)).closed);
  accuracy::Mesh missing = cube;
  missing.idx.resize(missing.idx.size() - 3);
  CHECK_FALSE(features_of(scene_of(missing)).closed);
  accuracy::Mesh doubled = cube;  // a second copy of the whole surface: every edge four times
  doubled.idx.insert(doubled.idx.end(), cube.idx.begin(), cube.idx.end());
  CHECK_FALSE(features_of(scene_of(doubled)).closed);
}

TEST_CASE("scene analysis: vertices split at a seam (same position, new index) still close the mesh") {
  accuracy::Mesh split = oriented_cube(2);
  for (std::size_t t = 0; t < split.triangles(); t += 2) {  // every other triangle gets its own corners
    for (int k = 0; k < 3; ++k) {
      const auto p = split.position(split.idx[3 * t + k]);
      split.idx[3 * t + k] = split.vertex(p[0], p[1], p[2]);
    }
  }
  CHECK(features_of(scene_of(split)).closed);
}

TEST_CASE("scene analysis: polygons count like triangles, and may close a solid together") {
  io::SceneDesc desc;
  desc.materials.push_back(io::Material{"grey"});
  desc.polygons = polygon_cube();
  CHECK(features_of(desc).closed);
  desc.polygons.pop_back();
  const render::SceneFeatures open = features_of(desc);
  CHECK_FALSE(open.closed);
  CHECK(open.open_edges == 4);
}

TEST_CASE("scene analysis: a closed glass sphere is closed but not opaque: no culling") {
  io::SceneDesc desc = scene_of(accuracy::icosphere(1, 32.0).mesh);
  desc.materials[0].transmittance = glm::vec3(0.9f);
  desc.materials[0].ior = 1.5f;
  const render::SceneFeatures f = features_of(desc);
  CHECK(f.closed);
  CHECK(f.refraction);
  CHECK_FALSE(f.cull_admissible());
  CHECK(render::describe_culling(f) == "back-face culling not admissible: transmissive materials");
}

TEST_CASE("scene analysis: a closure check without faces is not closed") {
  core::ClosureCheck empty;
  CHECK_FALSE(empty.finish().closed());
}
