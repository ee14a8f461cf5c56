// The excluding queries (Accel::intersect_excluding, occluded_excluding and the batch forms
// with QueryArguments::excluded): a ray answers as the scene without the one primitive it
// names, at every ISA and test, against brute force over the scalar oracle's triangle test
// with that triangle left out; rays that start on a triangle (no origin offset) never hit
// it; NaN, Inf and zero-direction rays miss; rays through an edge shared with the excluded
// triangle still hit its neighbour (from the edge itself too, at t = 0); instances leave it out in their own copy only; bad
// names are errors that say which.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "accel_test_util.h"
#include "volley/accel.h"
#include "volley/volley.h"

using volley::Accel;
using volley::Hit;
using volley::Isa;
using volley::kInvalidId;
using volley::kInvalidPrim;
using volley::QueryArguments;
using volley::Ray;
using volley::TriangleTest;
using accel_test::agree;
using accel_test::make_ray;
using accel_test::Soup;

namespace {

/// brute_force (accel_test_util.h) with triangle `skipped` left out.
Hit brute_force_excluding(const Soup& soup, TriangleTest test, const Ray& ray, std::uint32_t skipped, Isa isa) {
  Hit best;
  if (!accel_test::finite_ray(ray)) return best;
  const glm::vec3 o(ray.org[0], ray.org[1], ray.org[2]), d(ray.dir[0], ray.dir[1], ray.dir[2]);
  float upper = ray.tmax;
  for (std::size_t i = 0; i < soup.size(); ++i) {
    if (i == skipped) continue;
    volley::core::TriHit<float> h;
    if (volley::core::intersect_triangle(test, volley::core::RayT<float>{o, ray.tmin, d, upper}, soup.vertex(i, 0),
                                         soup.vertex(i, 1), soup.vertex(i, 2), h, isa)) {
      upper = h.t;
      best = {h.t, h.u, h.v, static_cast<std::uint32_t>(i), 0u};
    }
  }
  return best;
}

/// A soup with degenerate triangles among the random ones, moved by `offset` (far offsets).
Soup test_soup(glm::vec3 offset) {
  Soup soup = accel_test::random_soup(300, 7);
  const glm::vec3 p(1.0f, 2.0f, 3.0f);
  soup.add(p, p, p);                                  // a point
  soup.add(p, p + glm::vec3(1.0f), p + glm::vec3(2.0f));  // a segment
  for (std::size_t i = 0; i < soup.xyz.size(); ++i) soup.xyz[i] += offset[int(i % 3)];
  return soup;
}

/// Rays and the triangle each excludes: rays that start on a triangle (a point inside it,
/// at a vertex, on an edge) going anywhere, rays from outside aimed at a triangle's vertex
/// excluding that triangle, random rays excluding a random triangle, and rays the oracle
/// rejects (NaN, Inf, zero direction).
void make_rays(const Soup& soup, std::vector<Ray>& rays, std::vector<std::uint32_t>& skipped) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f), dir(-1.0f, 1.0f);
  const std::uint32_t n = static_cast<std::uint32_t>(soup.size());
  for (int k = 0; k < 1500; ++k) {
    const std::uint32_t t = static_cast<std::uint32_t>(rng() % n);
    float u = unit(rng), v = unit(rng);
    if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
    if (k % 7 == 0) u = 0.0f, v = 0.0f;   // a vertex
    if (k % 7 == 1) v = 1.0f - u;         // the edge p1 p2
    const glm::vec3 p = (1.0f - u - v) * soup.vertex(t, 0) + u * soup.vertex(t, 1) + v * soup.vertex(t, 2);
    rays.push_back(make_ray(p, glm::vec3(dir(rng), dir(rng), dir(rng))));
    skipped.push_back(t);
  }
  for (int k = 0; k < 600; ++k) {
    const std::uint32_t t = static_cast<std::uint32_t>(rng() % n);
    const glm::vec3 target = soup.vertex(t, static_cast<int>(rng() % 3));
    const glm::vec3 o = target + 8.0f * glm::vec3(dir(rng), dir(rng), dir(rng));
    rays.push_back(make_ray(o, target - o));
    skipped.push_back(k % 5 == 0 ? kInvalidPrim : t);
  }
  const glm::vec3 c = soup.vertex(0, 0);
  rays.push_back(make_ray(c, glm::vec3(0.0f)));
  rays.push_back(make_ray(glm::vec3(accel_test::kNaN, 0.0f, 0.0f), glm::vec3(1.0f, 0.0f, 0.0f)));
  rays.push_back(make_ray(c, glm::vec3(accel_test::kInf, 1.0f, 0.0f)));
  rays.push_back(make_ray(c, glm::vec3(1.0f, 0.0f, 0.0f), accel_test::kNaN));
  for (int k = 0; k < 4; ++k) skipped.push_back(0);
}

/// The hit that names triangle `t` of geometry 0 (a miss for kInvalidPrim).
Hit naming(std::uint32_t t) {
  Hit h;
  if (t != kInvalidPrim) h.prim = t, h.geom = 0, h.t = 0.0f;
  return h;
}

}  // namespace

TEST_CASE("excluding: each ray answers as the scene without its excluded triangle, every ISA, test and form") {
  for (const glm::vec3 offset : {glm::vec3(0.0f), glm::vec3(1e5f, -3e4f, 2e5f)}) {
    const Soup soup = test_soup(offset);
    std::vector<Ray> rays;
    std::vector<std::uint32_t> skipped;
    make_rays(soup, rays, skipped);
    std::vector<Hit> excluded(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) excluded[i] = naming(skipped[i]);
    std::vector<Isa> isas = accel_test::simd_isas();
    isas.insert(isas.begin(), Isa::scalar);
    for (const Isa isa : isas)
      for (const TriangleTest test : accel_test::kTests) {
        CAPTURE(std::string(volley::to_string(isa)));
        CAPTURE(std::string(volley::to_string(test)));
        CAPTURE(offset.x);
        const Accel accel = soup.accel(test, isa);
        std::size_t single = 0, occluded = 0, batch = 0, batch_occluded = 0, self = 0, plain_self = 0, masked = 0;
        std::vector<Hit> hits(rays.size());
        std::vector<std::uint8_t> blocked(rays.size(), 7);
        accel.intersect(rays.data(), rays.size(), hits.data(), QueryArguments{nullptr, excluded.data(), 3});
        accel.occluded(rays.data(), rays.size(), blocked.data(), QueryArguments{nullptr, excluded.data(), 1});
        // With masks: all meeting the scene's (the stream walk on SIMD ISAs), and one ray's
        // meeting nothing (that ray a miss, the batch then ray by ray).
        std::vector<std::uint32_t> all(rays.size(), volley::kMaskAll), one_off = all;
        one_off[5] = 0;
        std::vector<Hit> hits_all(rays.size()), hits_one_off(rays.size());
        std::vector<std::uint8_t> blocked_all(rays.size(), 7), blocked_one_off(rays.size(), 7);
        accel.intersect(rays.data(), rays.size(), hits_all.data(), QueryArguments{all.data(), excluded.data(), 1});
        accel.intersect(rays.data(), rays.size(), hits_one_off.data(),
                        QueryArguments{one_off.data(), excluded.data(), 1});
        accel.occluded(rays.data(), rays.size(), blocked_all.data(), QueryArguments{all.data(), excluded.data(), 1});
        accel.occluded(rays.data(), rays.size(), blocked_one_off.data(),
                       QueryArguments{one_off.data(), excluded.data(), 1});
        for (std::size_t i = 0; i < rays.size(); ++i) {
          const Hit want = brute_force_excluding(soup, test, rays[i], skipped[i], isa);
          const Hit got = accel.intersect_excluding(rays[i], excluded[i]);
          single += !agree(got, want);
          occluded += accel.occluded_excluding(rays[i], excluded[i]) != want.hit();
          batch += !agree(hits[i], want);
          batch_occluded += blocked[i] != (want.hit() ? 1 : 0);
          const bool off = one_off[i] == 0;
          masked += !agree(hits_all[i], want) || blocked_all[i] != (want.hit() ? 1 : 0);
          masked += off ? hits_one_off[i].hit() || blocked_one_off[i] != 0
                        : !agree(hits_one_off[i], want) || blocked_one_off[i] != (want.hit() ? 1 : 0);
          self += got.hit() && got.prim == skipped[i];
          plain_self += accel.intersect(rays[i]).prim == skipped[i];
        }
        CHECK(single == 0);
        CHECK(occluded == 0);
        CHECK(batch == 0);
        CHECK(batch_occluded == 0);
        CHECK(masked == 0);
        CHECK(self == 0);
        // Without the exclusion, rays that start on a triangle meet it again (the failure the
        // query exists for): the test would prove nothing if they did not.
        CHECK(plain_self > 100);
      }
  }
}

TEST_CASE("excluding: a ray through an edge shared with the excluded triangle hits its neighbour") {
  // Two triangles of a square share the diagonal (0,0)-(1,1); rays from below hit points on
  // it and at the shared vertices, excluding one of the two.
  Soup soup;
  soup.add({0, 0, 0}, {1, 0, 0}, {1, 1, 0});
  soup.add({0, 0, 0}, {1, 1, 0}, {0, 1, 0});
  std::vector<Isa> isas = accel_test::simd_isas();
  isas.insert(isas.begin(), Isa::scalar);
  for (const Isa isa : isas) {
    CAPTURE(std::string(volley::to_string(isa)));
    const Accel accel = soup.accel(TriangleTest::watertight, isa);
    for (const float s : {0.0f, 0.25f, 0.5f, 1.0f}) {
      const Ray r = make_ray({s, s, -1.0f}, {0.0f, 0.0f, 1.0f});
      for (std::uint32_t t : {0u, 1u}) {
        const Hit h = accel.intersect_excluding(r, naming(t));
        CHECK(h.prim == 1u - t);
        CHECK(h.t == 1.0f);
        CHECK(accel.occluded_excluding(r, naming(t)));
      }
      // The rule's limit, as documented: a ray leaving a point of the shared edge still meets
      // the neighbour there, at t = 0 (one primitive is left out, not the surface).
      const Ray up = make_ray({s, s, 0.0f}, {0.0f, 0.0f, 1.0f});
      const Hit again = accel.intersect_excluding(up, naming(0));
      CHECK(again.prim == 1u);
      CHECK(again.t == 0.0f);
    }
  }
}

TEST_CASE("excluding: instances leave the primitive out of the named instance only, and polygons are excluded too") {
  Soup soup;
  soup.add({-1, -1, 0}, {1, -1, 0}, {0, 1, 0});
  Accel proto = soup.accel(TriangleTest::watertight, Isa::automatic);
  for (const Isa isa : {Isa::scalar, Isa::automatic}) {
    Accel scene;
    const float near[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 1};  // z = 1
    const float far[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 2};   // z = 2
    const std::uint32_t a = scene.add_instance(proto, near), b = scene.add_instance(proto, far);
    const float square[] = {-5, -5, 3, 5, -5, 3, 5, 5, 3, -5, 5, 3};
    const std::uint32_t poly = scene.add_polygon(square, 4);
    scene.commit(volley::Options{TriangleTest::watertight, isa});
    const Ray r = make_ray({0, 0, 0}, {0, 0, 1});
    Hit in_a;
    in_a.prim = 0, in_a.geom = 0, in_a.inst = a;
    const Hit h = scene.intersect_excluding(r, in_a);
    CHECK(h.inst == b);
    CHECK(h.t == 2.0f);
    Hit in_b = in_a;
    in_b.inst = b;
    CHECK(scene.intersect_excluding(r, in_b).inst == a);
    // The polygon behind both, excluded by its geometry id (prim 0).
    const Ray from_top = make_ray({0, 0, 4}, {0, 0, -1});
    Hit polygon;
    polygon.prim = 0, polygon.geom = poly;
    CHECK(scene.intersect(from_top).geom == poly);
    CHECK(scene.intersect_excluding(from_top, polygon).inst == b);
    CHECK(!scene.occluded_excluding(make_ray({0, 0, 2.5f}, {0, 0, 1}), polygon));
    CHECK(scene.occluded_excluding(make_ray({0, 0, 2.5f}, {0, 0, 1}), in_a));
  }
}

TEST_CASE("excluding: a hit that names nothing is an error naming the field, in C too") {
  Soup soup = accel_test::random_soup(20, 1);
  const Accel accel = soup.accel(TriangleTest::watertight, Isa::automatic);
  const Ray r = make_ray({0, 0, -20}, {0, 0, 1});
  Hit bad;
  bad.geom = 3, bad.prim = 0;
  CHECK_THROWS_WITH_AS(accel.intersect_excluding(r, bad), doctest::Contains("geom 3"), volley::Error);
  bad.geom = 0, bad.prim = 20;
  CHECK_THROWS_WITH_AS(accel.occluded_excluding(r, bad), doctest::Contains("prim 20"), volley::Error);
  bad.inst = 0;
  CHECK_THROWS_WITH_AS(accel.intersect_excluding(r, bad), doctest::Contains("inst 0"), volley::Error);
  std::vector<Ray> rays(5, r);
  std::vector<Hit> excluded(5), hits(5);
  excluded[3].prim = 99, excluded[3].geom = 0;
  CHECK_THROWS_WITH_AS(accel.intersect(rays.data(), rays.size(), hits.data(), QueryArguments{nullptr, excluded.data(), 1}),
                       doctest::Contains("excluded[3]"), volley::Error);
  // A miss excludes nothing: the plain answer.
  CHECK(agree(accel.intersect_excluding(r, Hit{}), accel.intersect(r)));

  volley_scene* scene = nullptr;
  REQUIRE(volley_scene_create(&scene) == VOLLEY_OK);
  std::vector<std::uint32_t> idx(3 * soup.size());
  for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
  std::uint32_t geom = 0;
  REQUIRE(volley_scene_add_triangles(scene, soup.xyz.data(), 3 * soup.size(), idx.data(), soup.size(), &geom) ==
          VOLLEY_OK);
  REQUIRE(volley_scene_commit(scene, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AUTO) == VOLLEY_OK);
  volley_ray cr;
  std::memcpy(&cr, &r, sizeof cr);
  volley_hit ex{}, out{};
  ex.prim = 1000, ex.geom = 0, ex.inst = VOLLEY_INVALID_ID;
  CHECK(volley_intersect1_excluding(scene, &cr, &ex, &out) == VOLLEY_ERROR_INVALID_ARGUMENT);
  CHECK(std::string(volley_last_error()).find("prim 1000") != std::string::npos);
  CHECK(volley_intersect1_excluding(scene, &cr, nullptr, &out) == VOLLEY_ERROR_INVALID_ARGUMENT);
  volley_hit h0{};
  REQUIRE(volley_intersect1(scene, &cr, &h0) == VOLLEY_OK);
  if (h0.prim != VOLLEY_INVALID_PRIM) {
    REQUIRE(volley_intersect1_excluding(scene, &cr, &h0, &out) == VOLLEY_OK);
    CHECK(out.prim != h0.prim);
    int blocked = -1;
    CHECK(volley_occluded1_excluding(scene, &cr, &h0, &blocked) == VOLLEY_OK);
    CHECK(blocked == (out.prim != VOLLEY_INVALID_PRIM ? 1 : 0));
    volley_hit many[3];
    const volley_ray three[3] = {cr, cr, cr};
    const volley_hit exs[3] = {h0, h0, h0};
    CHECK(volley_intersect_batch_excluding(scene, three, nullptr, exs, 3, many, 2) == VOLLEY_OK);
    CHECK(many[2].prim == out.prim);
    std::uint8_t occ[3] = {9, 9, 9};
    CHECK(volley_occluded_batch_excluding(scene, three, nullptr, exs, 3, occ, 0) == VOLLEY_OK);
    CHECK(occ[1] == blocked);
  }
  volley_scene_destroy(scene);
}
