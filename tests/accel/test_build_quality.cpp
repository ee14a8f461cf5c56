// BuildQuality::high (spatial splits): on a soup of long slivers and wide quads crossing
// many small triangles, where the builder cuts triangles into references with clipped
// boxes, every query form on every ISA and triangle test gives the brute-force oracle's
// answers, rays aimed exactly at vertices and at points of the long edges included; the
// crossing queries report each triangle once; closest points, save/load and refit keep
// the answers.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "accel_test_util.h"
#include "volley/accel.h"

using namespace accel_test;
using volley::BuildQuality;

namespace {

/// Long slivers across [-10, 10]^3, two wide quads (a floor and a wall) and small triangles:
/// the object split's children overlap near the root, so the builder cuts.
Soup sliver_soup(std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-10.0f, 10.0f), small(-0.5f, 0.5f);
  Soup soup;
  for (int i = 0; i < 120; ++i) {
    const glm::vec3 a(pos(rng), pos(rng), pos(rng)), b(pos(rng), pos(rng), pos(rng));
    const glm::vec3 c = 0.5f * (a + b) + glm::vec3(small(rng), small(rng), small(rng));
    soup.add(a, b, c);
  }
  soup.add({-10, -10, -3}, {10, -10, -3}, {10, 10, -3});
  soup.add({-10, -10, -3}, {10, 10, -3}, {-10, 10, -3});
  soup.add({4, -10, -10}, {4, 10, -10}, {4, 10, 10});
  soup.add({4, -10, -10}, {4, 10, 10}, {4, -10, 10});
  const Soup dust = random_soup(500, seed + 1);
  soup.xyz.insert(soup.xyz.end(), dust.xyz.begin(), dust.xyz.end());
  return soup;
}

/// mixed_rays, plus rays from random origins aimed exactly at every vertex and at float
/// points along the first triangles' long edges (where clipped boxes end).
std::vector<Ray> probing_rays(const Soup& soup, std::uint32_t seed) {
  std::vector<Ray> rays = mixed_rays(40, 10.0f, seed);
  std::mt19937 rng(seed + 1);
  std::uniform_real_distribution<float> pos(-20.0f, 20.0f), unit(0.0f, 1.0f);
  for (std::size_t t = 0; t < soup.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 o(pos(rng), pos(rng), pos(rng));
      rays.push_back(make_ray(o, soup.vertex(t, k) - o));
    }
  for (std::size_t t = 0; t < 124; ++t)
    for (int e = 0; e < 3; ++e)
      for (int s = 0; s < 6; ++s) {
        const glm::vec3 p = soup.vertex(t, e) + unit(rng) * (soup.vertex(t, (e + 1) % 3) - soup.vertex(t, e));
        const glm::vec3 o(pos(rng), pos(rng), pos(rng));
        rays.push_back(make_ray(o, p - o));
      }
  return rays;
}

volley::Options high(TriangleTest test, Isa isa) {
  volley::Options o{test, isa};
  o.quality = BuildQuality::high;
  return o;
}

std::vector<Isa> every_isa() {
  std::vector<Isa> isas{Isa::scalar};
  for (Isa i : simd_isas()) isas.push_back(i);
  return isas;
}

std::string name(TriangleTest test, Isa isa) {
  return std::string(volley::to_string(test)) + " " + std::string(volley::to_string(isa));
}

}  // namespace

TEST_CASE("build quality high: spatial splits happen, and every form on every ISA and test gives the oracle's answers") {
  const Soup soup = sliver_soup(3);
  const std::vector<Ray> rays = probing_rays(soup, 5);
  for (TriangleTest test : kTests)
    for (Isa isa : every_isa()) {
      const std::string what = name(test, isa);
      CAPTURE(what);
      const Accel accel = soup.accel(high(test, isa));
      const volley::AccelInfo info = accel.info();
      CHECK(info.quality == BuildQuality::high);
      CHECK(info.references > soup.size());       // triangles were cut
      CHECK(info.references <= 2 * soup.size());  // within the builder's budget
      report(check_forms(accel, rays, brute_force_all(soup, test, rays, isa), 9), what);
    }
}

TEST_CASE("build quality high: crossings count each triangle once, as the medium build does") {
  const Soup soup = sliver_soup(11);
  const std::vector<Ray> rays = probing_rays(soup, 13);
  for (Isa isa : every_isa()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const Accel medium = soup.accel(TriangleTest::watertight, isa);
    const Accel cut = soup.accel(high(TriangleTest::watertight, isa));
    std::size_t wrong = 0, crossings = 0;
    for (const Ray& r : rays) {
      const std::uint32_t n = medium.count_intersections(r);
      crossings += n;
      std::vector<Hit> a(n + 2), b(n + 2);
      const std::size_t na = medium.intersect_all(r, a.data(), a.size());
      const std::size_t nb = cut.intersect_all(r, b.data(), b.size());
      bool same = na == nb && cut.count_intersections(r) == n;
      for (std::size_t k = 0; same && k < na; ++k) same = a[k].t == b[k].t && a[k].prim == b[k].prim;
      wrong += !same;
    }
    CHECK(crossings > rays.size());  // rays cross several triangles
    CHECK(wrong == 0);
    // Batches go through the packet form of the every-hit walk.
    std::vector<std::uint32_t> counts(rays.size()), want(rays.size());
    cut.count_intersections(rays.data(), rays.size(), counts.data(), 1);
    medium.count_intersections(rays.data(), rays.size(), want.data(), 1);
    CHECK(counts == want);
  }
}

TEST_CASE("build quality high: closest points are the medium build's") {
  const Soup soup = sliver_soup(17);
  std::mt19937 rng(19);
  std::uniform_real_distribution<float> pos(-12.0f, 12.0f);
  for (Isa isa : every_isa()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const Accel medium = soup.accel(TriangleTest::watertight, isa);
    const Accel cut = soup.accel(high(TriangleTest::watertight, isa));
    std::size_t wrong = 0;
    for (int i = 0; i < 2000; ++i) {
      const float p[3] = {pos(rng), pos(rng), pos(rng)};
      const volley::ClosestPoint a = medium.closest_point(p), b = cut.closest_point(p);
      wrong += a.distance != b.distance;
    }
    CHECK(wrong == 0);
  }
}

TEST_CASE("build quality high: a saved structure loads with its quality and answers, a refit keeps them right") {
  const Soup soup = sliver_soup(23);
  const std::vector<Ray> rays = probing_rays(soup, 29);
  const std::string path = "test_build_quality.volley";
  for (Isa isa : every_isa()) {
    const std::string what = name(TriangleTest::watertight, isa);
    CAPTURE(what);
    Accel accel = soup.accel(high(TriangleTest::watertight, isa));
    accel.save(path);
    const Accel loaded = Accel::load(path);
    CHECK(loaded.info().quality == BuildQuality::high);
    CHECK(loaded.info().references == accel.info().references);
    report(check_forms(loaded, rays, brute_force_all(soup, TriangleTest::watertight, rays, isa), 31), what + " loaded");

    // Moved vertices: the sliver soup's refit (boxes of whole triangles now, no longer
    // clipped) grows the SAH past kRefitRebuildGrowth, so the commit builds anew.
    Soup moved = soup;
    for (std::size_t i = 0; i < moved.xyz.size(); ++i) moved.xyz[i] += 0.1f * std::sin(float(i));
    accel.update_vertices(0, moved.xyz.data(), moved.xyz.size() / 3);
    accel.commit(high(TriangleTest::watertight, isa));
    CHECK(!accel.info().refitted);
    report(check_forms(accel, rays, brute_force_all(moved, TriangleTest::watertight, rays, isa), 37), what + " rebuilt");

    // Small triangles with a few cuts near the root: refitted, repeated references and all.
    const Soup dust = random_soup(3000, 41);
    Accel fine = dust.accel(high(TriangleTest::watertight, isa));
    CHECK(fine.info().references > dust.size());
    Soup shaken = dust;
    for (std::size_t i = 0; i < shaken.xyz.size(); ++i) shaken.xyz[i] += 0.05f * std::sin(float(i));
    fine.update_vertices(0, shaken.xyz.data(), shaken.xyz.size() / 3);
    fine.commit(high(TriangleTest::watertight, isa));
    CHECK(fine.info().refitted);
    report(check_forms(fine, rays, brute_force_all(shaken, TriangleTest::watertight, rays, isa), 43), what + " refitted");
  }
  std::remove(path.c_str());
}
