// The point queries (Accel::closest_point, distance, signed_distance): every ISA's answers
// are the scalar oracle's bit for bit (same per-triangle operations, core/point_triangle.h),
// within float rounding of a double-precision brute force (the bound stated in
// docs/crossings.md), with polygons, search radii, signs from contains, and clear errors.
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "accel_test_util.h"
#include "accuracy/closed_meshes.h"
#include "core/point_triangle.h"
#include "simd/isa/dispatch.h"
#include "volley/accel.h"

using volley::Accel;
using volley::ClosestPoint;
using volley::Isa;
using volley::TriangleTest;

namespace {

/// Points around a random soup: uniform in a box twice its size, and just off triangles.
std::vector<float> points_near(const accel_test::Soup& soup, int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-20.0f, 20.0f), w(0.0f, 1.0f), off(-1e-3f, 1e-3f);
  std::uniform_int_distribution<std::size_t> pick(0, soup.size() - 1);
  std::vector<float> xyz;
  for (int i = 0; i < n; ++i) {
    if (i % 2) {
      xyz.insert(xyz.end(), {u(rng), u(rng), u(rng)});
      continue;
    }
    const std::size_t t = pick(rng);
    float a = w(rng), b = w(rng);
    if (a + b > 1) a = 1 - a, b = 1 - b;
    const glm::vec3 p = soup.vertex(t, 0) + a * (soup.vertex(t, 1) - soup.vertex(t, 0)) + b * (soup.vertex(t, 2) - soup.vertex(t, 0));
    xyz.insert(xyz.end(), {p.x + off(rng), p.y + off(rng), p.z + off(rng)});
  }
  return xyz;
}

/// Double-precision brute force: the nearest distance and the largest vertex distance of
/// the winning triangle (the scale of the float answer's rounding).
struct Reference {
  double distance;
  double scale;
  std::size_t prim;
};
Reference brute_force(const accel_test::Soup& soup, const float* p) {
  Reference best{INFINITY, 0.0, 0};
  for (std::size_t t = 0; t < soup.size(); ++t) {
    if (volley::core::is_degenerate(soup.vertex(t, 0), soup.vertex(t, 1), soup.vertex(t, 2))) continue;
    const glm::dvec3 a(soup.vertex(t, 0)), b(soup.vertex(t, 1)), c(soup.vertex(t, 2)), q(p[0], p[1], p[2]);
    const glm::dvec3 w = q - a, e1 = b - a, e2 = c - a;
    const auto r = volley::core::nearest_on_triangle<double, volley::core::ScalarLaneOps<double>>(w.x, w.y, w.z, e1.x, e1.y,
                                                                                                 e1.z, e2.x, e2.y, e2.z);
    const double d = std::sqrt(r.d2);
    // The scale: the farthest vertex, over the sine of the triangle's angle at a (the
    // rounding of its normal, relative to its length, grows as the triangle thins).
    const double sine = glm::length(glm::cross(e1, e2)) / (glm::length(e1) * glm::length(e2));
    if (d < best.distance)
      best = {d, std::max({glm::length(q - a), glm::length(q - b), glm::length(q - c)}) / sine, t};
  }
  return best;
}

}  // namespace

TEST_CASE("points: every ISA's closest points are the scalar oracle's, and within float rounding of double") {
  const accel_test::Soup soup = accel_test::random_soup(500, 33);
  const std::vector<float> xyz = points_near(soup, 3000, 4);
  const std::size_t n = xyz.size() / 3;
  for (TriangleTest test : {TriangleTest::watertight, TriangleTest::moller}) {
    const Accel oracle = soup.accel(test, Isa::scalar);
    std::vector<ClosestPoint> want(n);
    oracle.closest_points(xyz.data(), n, want.data());
    // Against double: |d - d_ref| <= 8 eps (d_ref + scale), scale = the farthest vertex of
    // the nearest triangle from the point over the sine of its angle at the first vertex
    // (measured: 1.14 eps on these points).
    double worst = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const Reference r = brute_force(soup, &xyz[3 * i]);
      REQUIRE(want[i].found());
      const double ratio = std::abs(double(want[i].distance) - r.distance) / (0x1p-24 * (r.distance + r.scale));
      worst = std::max(worst, ratio);
    }
    MESSAGE(volley::to_string(test) << ": largest |d - d_ref| = " << worst << " eps (d_ref + scale)");
    CHECK(worst <= 8.0);
    for (Isa isa : accel_test::simd_isas()) {
      const Accel a = soup.accel(test, isa);
      std::vector<ClosestPoint> got(n);
      a.closest_points(xyz.data(), n, got.data());
      std::size_t wrong = 0;
      for (std::size_t i = 0; i < n; ++i) {
        const bool same_prim = got[i].prim == want[i].prim;
        wrong += got[i].distance != want[i].distance || (same_prim && (got[i].point[0] != want[i].point[0] ||
                                                                       got[i].point[1] != want[i].point[1] ||
                                                                       got[i].point[2] != want[i].point[2] ||
                                                                       got[i].u != want[i].u || got[i].v != want[i].v));
      }
      INFO(volley::to_string(test) << " " << volley::to_string(isa));
      CHECK(wrong == 0);
    }
  }
}

TEST_CASE("points: the search radius, the nearest point's place, batches and threads") {
  const accel_test::Soup soup = accel_test::random_soup(300, 8);
  const Accel a = soup.accel(TriangleTest::watertight, Isa::automatic);
  const std::vector<float> xyz = points_near(soup, 1000, 9);
  const std::size_t n = xyz.size() / 3;
  std::vector<ClosestPoint> all(n), near(n), three(n);
  a.closest_points(xyz.data(), n, all.data(), INFINITY, 1);
  a.closest_points(xyz.data(), n, near.data(), 0.5f, 0);
  a.closest_points(xyz.data(), n, three.data(), INFINITY, 3);
  std::vector<float> d(n), sd(n);
  a.distances(xyz.data(), n, d.data(), false);
  a.distances(xyz.data(), n, sd.data(), true);
  for (std::size_t i = 0; i < n; ++i) {
    // The batches search in Morton order from the previous answer; one point alone does not.
    CHECK(a.closest_point(&xyz[3 * i]).distance == all[i].distance);
    CHECK(three[i].distance == all[i].distance);
    CHECK(d[i] == all[i].distance);
    CHECK(std::abs(sd[i]) == all[i].distance);  // random soups: the sign is the parity's
    if (all[i].distance < 0.5f) {
      CHECK(near[i].distance == all[i].distance);
    } else {
      CHECK(!near[i].found());
      CHECK(near[i].distance == INFINITY);
    }
    // The point lies on its triangle, at its barycentrics, at the distance reported.
    const ClosestPoint& c = all[i];
    const glm::vec3 p0 = soup.vertex(c.prim, 0), p1 = soup.vertex(c.prim, 1), p2 = soup.vertex(c.prim, 2);
    const glm::vec3 at = p0 + c.u * (p1 - p0) + c.v * (p2 - p0);
    CHECK(glm::length(at - glm::vec3(c.point[0], c.point[1], c.point[2])) <= 1e-5f * (1 + glm::length(at)));
    CHECK(c.u >= 0.0f);
    CHECK(c.v >= 0.0f);
    CHECK(c.u + c.v <= 1.0f + 1e-6f);
    CHECK(c.geom == 0);
  }
}

TEST_CASE("points: polygons, signed distance inside a closed mesh, and what is refused") {
  Accel a;
  const float square[] = {0, 0, 0, 4, 0, 0, 4, 4, 0, 0, 4, 0};
  a.add_polygon(square, 4);
  a.commit();
  const float above[3] = {1, 2, 3}, beside[3] = {7, 2, 4};
  const ClosestPoint c = a.closest_point(above);
  CHECK(c.distance == 3.0f);
  CHECK(c.point[0] == 1.0f);
  CHECK(c.point[1] == 2.0f);
  CHECK(c.point[2] == 0.0f);
  CHECK(c.geom == 0);
  CHECK(a.distance(beside) == 5.0f);  // to the edge x = 4: (3, 0, 4)
  const float nan_point[3] = {NAN, 0, 0};
  CHECK(!a.closest_point(nan_point).found());
  CHECK_THROWS_AS(a.closest_point(above, -1.0f), volley::Error);
  CHECK_THROWS_AS(a.closest_point(nullptr), volley::Error);

  // Signed distance: negative inside the icosphere, and |sd| = distance.
  const auto sphere = volley::accuracy::icosphere(2, 40.0);
  for (Isa isa : {Isa::scalar, Isa::automatic}) {
    Accel s;
    s.add_triangles(sphere.mesh.xyz.data(), sphere.mesh.vertices(), sphere.mesh.idx.data(), sphere.mesh.triangles());
    s.commit(volley::Options{TriangleTest::watertight, isa});
    const float centre[3] = {40, 40, 40}, far[3] = {200, 40, 40};
    CHECK(s.signed_distance(centre) < -30.0f);
    CHECK(s.signed_distance(far) > 100.0f);
    CHECK(s.signed_distance(centre) == -s.distance(centre));
  }

  // The plane test's blocks keep no vertices; instances are not point-queried.
  const accel_test::Soup soup = accel_test::random_soup(50, 1);
  const Accel plane = soup.accel(TriangleTest::plane, Isa::automatic);
  CHECK_THROWS_AS(plane.closest_point(above), volley::Error);
  Accel scene;
  const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  scene.add_instance(a, identity);
  scene.commit();
  CHECK_THROWS_AS(scene.closest_point(above), volley::Error);
  Accel empty;
  empty.commit();
  CHECK(!empty.closest_point(above).found());
  CHECK(empty.distance(above) == INFINITY);
  Accel uncommitted;
  CHECK_THROWS_AS(uncommitted.closest_point(above), volley::Error);
}
