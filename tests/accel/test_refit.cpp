// Refit (Accel::update_vertices, Options::refit): a committed BVH follows moved vertices
// with the answers of a fresh build, at every ISA and test, in every query form; it
// rebuilds instead when the topology, the options or a triangle's degeneracy changed, or
// when the SAH cost grew past kRefitRebuildGrowth.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "accel_test_util.h"
#include "simd/isa/dispatch.h"
#include "volley/accel.h"

using volley::Accel;
using volley::Hit;
using volley::Isa;
using volley::Ray;
using volley::TriangleTest;
using accel_test::agree;
using accel_test::check_forms;
using accel_test::report;

namespace {

/// A height field of n x n quads over [-1, 1]^2 at z = 0: vertices and indices.
struct Grid {
  int n;
  std::vector<float> xyz;
  std::vector<std::uint32_t> indices;
  explicit Grid(int cells) : n(cells) {
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) xyz.insert(xyz.end(), {-1.0f + 2.0f * i / n, -1.0f + 2.0f * j / n, 0.0f});
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const auto a = static_cast<std::uint32_t>(j * (n + 1) + i), b = a + 1, c = a + static_cast<std::uint32_t>(n + 1),
                   d = c + 1;
        indices.insert(indices.end(), {a, b, d, a, d, c});
      }
  }
  std::size_t vertices() const { return xyz.size() / 3; }
  std::size_t triangles() const { return indices.size() / 3; }
  /// The vertices under a smooth wave of amplitude `amp` (a smooth deformation).
  std::vector<float> waved(float amp) const {
    std::vector<float> out = xyz;
    for (std::size_t v = 0; v < vertices(); ++v)
      out[3 * v + 2] = amp * std::sin(3.0f * out[3 * v]) * std::cos(2.0f * out[3 * v + 1]);
    return out;
  }
};

std::vector<Ray> rays_down(int count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.1f, 1.1f), tilt(-0.3f, 0.3f);
  std::vector<Ray> rays;
  for (int i = 0; i < count; ++i) rays.push_back(Ray{{u(rng), u(rng), 2.0f}, 0.0f, {tilt(rng), tilt(rng), -1.0f}, INFINITY});
  return rays;
}

}  // namespace

TEST_CASE("refit: moved vertices give the answers of a fresh build, every ISA, test and query form") {
  // A wave of amplitude 0.3 deformed to one of 0.4 (a flat start would not do: its boxes
  // have no height, and any wave multiplies their area past kRefitRebuildGrowth).
  const Grid grid(24);
  const std::vector<float> start = grid.waved(0.3f), moved = grid.waved(0.4f);
  const std::vector<Ray> rays = rays_down(700, 3);
  accel_test::for_each_isa_and_test([&](Isa isa, TriangleTest test) {
    Accel accel;
    const std::uint32_t g = accel.add_triangles(start.data(), grid.vertices(), grid.indices.data(), grid.triangles());
    accel.commit({test, isa});
    CHECK(!accel.info().refitted);
    accel.update_vertices(g, moved.data(), grid.vertices());
    CHECK_THROWS_WITH_AS(accel.intersect(rays[0]), doctest::Contains("commit"), volley::Error);
    accel.commit({test, isa});
    CHECK(accel.info().refitted);
    CHECK(accel.info().sah_growth > 0.9);
    Accel fresh;
    fresh.add_triangles(moved.data(), grid.vertices(), grid.indices.data(), grid.triangles());
    fresh.commit({test, isa});
    std::vector<Hit> want(rays.size());
    std::size_t hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) hits += (want[i] = fresh.intersect(rays[i])).hit();
    CHECK(hits > rays.size() / 2);
    report(check_forms(accel, rays, want, 5), "refitted against a fresh build");
    // Back to the start: refitted again, to the SAH cost of the build.
    accel.update_vertices(g, start.data(), grid.vertices());
    accel.commit({test, isa});
    CHECK(accel.info().refitted);
    CHECK(accel.info().sah_growth == doctest::Approx(1.0));
  });
}

TEST_CASE("refit: a refit to the same vertices changes no answer, bit for bit") {
  const Grid grid(16);
  const std::vector<Ray> rays = rays_down(300, 9);
  for (Isa isa : {Isa::scalar, Isa::avx2, Isa::avx512}) {
    if (!volley::simd::cpu_has(isa)) continue;
    CAPTURE(std::string(volley::to_string(isa)));
    Accel accel;
    accel.add_triangles(grid.xyz.data(), grid.vertices(), grid.indices.data(), grid.triangles());
    accel.commit({TriangleTest::watertight, isa});
    std::vector<Hit> before(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) before[i] = accel.intersect(rays[i]);
    const auto info_before = accel.info();
    accel.update_vertices(0, grid.xyz.data(), grid.vertices());
    accel.commit({TriangleTest::watertight, isa});
    CHECK(accel.info().refitted);
    CHECK(accel.info().sah_cost == info_before.sah_cost);
    int differ = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const Hit h = accel.intersect(rays[i]);
      differ += std::memcmp(&h, &before[i], sizeof h) != 0;
    }
    CHECK(differ == 0);
  }
}

TEST_CASE("refit: commit builds instead when the topology, the options, a degeneracy or the SAH cost says so") {
  const Grid grid(12);
  const Isa isa = volley::simd::cpu_has(Isa::avx2) ? Isa::avx2 : Isa::scalar;
  const std::vector<float> moved = grid.waved(0.2f);
  {
    Accel accel;  // Options::refit = false
    accel.add_triangles(grid.xyz.data(), grid.vertices(), grid.indices.data(), grid.triangles());
    accel.commit({TriangleTest::watertight, isa});
    accel.update_vertices(0, moved.data(), grid.vertices());
    volley::Options no_refit{TriangleTest::watertight, isa};
    no_refit.refit = false;
    accel.commit(no_refit);
    CHECK(!accel.info().refitted);
  }
  {
    Accel accel;  // another test: a build
    accel.add_triangles(grid.xyz.data(), grid.vertices(), grid.indices.data(), grid.triangles());
    accel.commit({TriangleTest::watertight, isa});
    accel.update_vertices(0, moved.data(), grid.vertices());
    accel.commit({TriangleTest::moller, isa});
    CHECK(!accel.info().refitted);
  }
  {
    Accel accel;  // a geometry added: a build
    accel.add_triangles(grid.xyz.data(), grid.vertices(), grid.indices.data(), grid.triangles());
    accel.commit({TriangleTest::watertight, isa});
    accel.update_vertices(0, moved.data(), grid.vertices());
    accel.add_triangles(grid.xyz.data(), grid.vertices(), grid.indices.data(), 1);
    accel.commit({TriangleTest::watertight, isa});
    CHECK(!accel.info().refitted);
  }
  {
    // Triangles collapsed to zero area at the first build are left out of it; when a move
    // gives them area, commit builds (with them), and from then on refits whatever turns
    // degenerate or back: a degenerate triangle in the tree is never hit.
    std::vector<float> collapsed = grid.xyz;
    const std::uint32_t a = grid.indices[0], b = grid.indices[1];
    for (int k = 0; k < 3; ++k) collapsed[3 * b + k] = collapsed[3 * a + k];
    Accel accel;
    accel.add_triangles(collapsed.data(), grid.vertices(), grid.indices.data(), grid.triangles());
    accel.commit({TriangleTest::watertight, isa});
    CHECK(accel.info().degenerate >= 1);
    accel.update_vertices(0, grid.xyz.data(), grid.vertices());
    accel.commit({TriangleTest::watertight, isa});
    CHECK(!accel.info().refitted);
    CHECK(accel.info().degenerate == 0);
    accel.update_vertices(0, collapsed.data(), grid.vertices());
    accel.commit({TriangleTest::watertight, isa});
    CHECK(accel.info().refitted);
    accel.update_vertices(0, grid.xyz.data(), grid.vertices());
    accel.commit({TriangleTest::watertight, isa});
    CHECK(accel.info().refitted);
    // Triangle 0 has its area back and is hit where a fresh build hits it.
    const glm::vec3 p0(grid.xyz[3 * a], grid.xyz[3 * a + 1], 0.0f), p1(grid.xyz[3 * b], grid.xyz[3 * b + 1], 0.0f),
        p2(grid.xyz[3 * grid.indices[2]], grid.xyz[3 * grid.indices[2] + 1], 0.0f);
    const glm::vec3 c = (p0 + p1 + p2) / 3.0f;
    const Hit h = accel.intersect(Ray{{c.x, c.y, 1.0f}, 0.0f, {0, 0, -1}, INFINITY});
    CHECK(h.geom == 0);
    CHECK(h.prim == 0);
  }
  {
    Accel accel;  // vertices scattered: the refitted boxes overlap, SAH past the limit, a build
    accel.add_triangles(grid.xyz.data(), grid.vertices(), grid.indices.data(), grid.triangles());
    accel.commit({TriangleTest::watertight, isa});
    std::vector<float> scattered = grid.xyz;
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (float& c : scattered) c = u(rng);
    accel.update_vertices(0, scattered.data(), grid.vertices());
    accel.commit({TriangleTest::watertight, isa});
    CHECK(!accel.info().refitted);
    CHECK(accel.info().sah_growth == 1.0);
    const std::vector<Ray> rays = rays_down(200, 4);
    Accel fresh;
    fresh.add_triangles(scattered.data(), grid.vertices(), grid.indices.data(), grid.triangles());
    fresh.commit({TriangleTest::watertight, isa});
    int differ = 0;
    for (const Ray& r : rays) differ += !agree(accel.intersect(r), fresh.intersect(r));
    CHECK(differ == 0);
  }
}

TEST_CASE("refit: update_vertices rejects what it cannot take and then changes nothing") {
  const Grid grid(4);
  Accel accel;
  accel.add_triangles(grid.xyz.data(), grid.vertices(), grid.indices.data(), grid.triangles());
  const float square[] = {-2, -2, 4, 2, -2, 4, 2, 2, 4, -2, 2, 4};
  accel.add_polygon(square, 4);
  accel.commit();
  CHECK_THROWS_WITH_AS(accel.update_vertices(1, square, 4), doctest::Contains("polygon"), volley::Error);
  CHECK_THROWS_WITH_AS(accel.update_vertices(0, grid.xyz.data(), grid.vertices() - 1),
                       doctest::Contains("was added with 25 vertices, got 24"), volley::Error);
  CHECK_THROWS_WITH_AS(accel.update_vertices(2, grid.xyz.data(), grid.vertices()), doctest::Contains("does not exist"),
                       volley::Error);
  std::vector<float> bad = grid.xyz;
  bad[7] = NAN;
  CHECK_THROWS_WITH_AS(accel.update_vertices(0, bad.data(), grid.vertices()), doctest::Contains("vertex 2"),
                       volley::Error);
  // Nothing changed: still committed, the same answers.
  CHECK(accel.intersect(Ray{{0.1f, 0.2f, 1}, 0, {0, 0, -1}, INFINITY}).t == doctest::Approx(1.0f));
}
