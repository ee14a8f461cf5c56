// Instances (Accel::add_instance): an instanced scene answers as the same triangles placed
// in world space by hand (the oracle: the flattened scene), every query form agrees with
// the single-ray answers at every ISA, a closed mesh stays watertight through mirrored and
// scaled instances, instances are disabled and masked like geometries, and bad calls fail.
#include <doctest/doctest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "accel_test_util.h"
#include "simd/isa/dispatch.h"
#include "volley/accel.h"

using volley::Accel;
using volley::Hit;
using volley::Isa;
using volley::kInvalidId;
using volley::Ray;
using volley::TriangleTest;
using accel_test::check_forms;
using accel_test::report;

namespace {

/// [A | t] row by row: scale s (per axis, negative mirrors), rotation about z by `deg`,
/// then translation.
std::vector<float> transform(glm::vec3 s, float deg, glm::vec3 t) {
  const float c = std::cos(glm::radians(deg)), n = std::sin(glm::radians(deg));
  return {c * s.x, -n * s.y, 0, t.x, n * s.x, c * s.y, 0, t.y, 0, 0, s.z, t.z};
}

glm::vec3 apply(const std::vector<float>& m, glm::vec3 p) {
  return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
          m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
}

std::uint32_t add_soup(Accel& accel, const accel_test::Soup& s) {
  std::vector<std::uint32_t> idx(3 * s.size());
  for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
  return accel.add_triangles(s.xyz.data(), 3 * s.size(), idx.data(), s.size());
}

/// A prototype for the instance tests: `soup` committed with the watertight test at `isa`.
Accel prototype_of(const accel_test::Soup& soup, Isa isa) {
  Accel prototype;
  add_soup(prototype, soup);
  prototype.commit({TriangleTest::watertight, isa});
  return prototype;
}

const std::vector<std::vector<float>>& placements() {
  static const std::vector<std::vector<float>> p = {
      transform({1, 1, 1}, 0, {0, 0, 0}),         transform({0.5f, 0.5f, 0.5f}, 30, {25, 0, 0}),
      transform({-1, 1, 1}, 0, {0, 25, 0}),       transform({2, 1, 0.5f}, 75, {-30, -10, 5}),
      transform({1, -1, -1}, 180, {0, -30, -10}), transform({0.25f, 0.25f, 0.25f}, -45, {5, 5, 30})};
  return p;
}

/// Rays from all around aimed at points of the placed triangles (centroids and a little
/// off them), plus some that miss.
std::vector<Ray> aimed_rays(const accel_test::Soup& soup, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), w(0.1f, 0.8f);
  std::vector<Ray> rays;
  for (const std::vector<float>& m : placements())
    for (int i = 0; i < 120; ++i) {
      const std::size_t t = rng() % soup.size();
      const float a = w(rng), b = w(rng) * (1 - a);
      const glm::vec3 target =
          apply(m, (1 - a - b) * soup.vertex(t, 0) + a * soup.vertex(t, 1) + b * soup.vertex(t, 2));
      const glm::vec3 o = target + 60.0f * glm::normalize(glm::vec3(u(rng), u(rng), u(rng)));
      const glm::vec3 d = (target - o) * 0.5f;
      rays.push_back(Ray{{o.x, o.y, o.z}, 0.0f, {d.x, d.y, d.z}, INFINITY});
    }
  return rays;
}

}  // namespace

TEST_CASE("instances: answers of the flattened scene, every query form, every ISA and test") {
  const accel_test::Soup soup = accel_test::random_soup(200, 77), other = accel_test::random_soup(100, 78);
  accel_test::for_each_isa_and_test([&](Isa isa, TriangleTest test) {
    Accel prototype;
    add_soup(prototype, soup);
    prototype.commit({test, isa});
    // The scene: a geometry of its own (id 0), then the instances (ids 1 ..).
    Accel scene, flat;
    add_soup(scene, other);
    add_soup(flat, other);
    for (const std::vector<float>& m : placements()) {
      scene.add_instance(prototype, m.data());
      accel_test::Soup placed;
      for (std::size_t t = 0; t < soup.size(); ++t)
        placed.add(apply(m, soup.vertex(t, 0)), apply(m, soup.vertex(t, 1)), apply(m, soup.vertex(t, 2)));
      add_soup(flat, placed);
    }
    scene.commit({test, isa});
    flat.commit({test, isa});
    CHECK(scene.info().instances == placements().size());
    CHECK(scene.info().instanced_triangles == placements().size() * soup.size());

    const std::vector<Ray> rays = aimed_rays(soup, 5);
    std::vector<Hit> single(rays.size());
    int differ = 0, hits = 0, through = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const Hit h = single[i] = scene.intersect(rays[i]);
      const Hit f = flat.intersect(rays[i]);
      hits += h.hit();
      // The same triangle: an instance hit names it by instance, geometry 0, prim; the
      // flattened scene by geometry 1 + instance order.
      const bool via = h.inst != kInvalidId;
      through += via;
      const std::uint32_t geom = via ? h.inst : h.geom;
      const bool same = h.hit() == f.hit() &&
                        (!h.hit() || (geom == f.geom && h.prim == f.prim && std::fabs(h.t - f.t) <= 1e-4f * f.t));
      if (via) CHECK(h.geom == 0);
      differ += !same;
    }
    CHECK(hits > int(rays.size()) * 3 / 4);
    CHECK(through > int(rays.size()) / 2);
    CHECK(differ <= int(rays.size()) / 200);  // near-ties between triangles may go either way
    report(check_forms(scene, rays, single, 11), "instanced scene: forms against single rays");
  });
}

TEST_CASE("instances: camera packets with spread origins (the top level's frustum walk) answer as single rays") {
  // Rays as the notes' viewport model makes them (from each pixel of a viewport one unit in
  // front of the eye), then an orthographic camera's (one direction, origins on a grid: the
  // walk's interval then rests on the origins' spread alone), 4x4 pixel blocks, so most
  // packets are of one octant and the top level takes the frustum walk with spread origins.
  const accel_test::Soup soup = accel_test::random_soup(1500, 93), own = accel_test::random_soup(60, 94);
  std::vector<Ray> rays, orthographic;
  const int side = 48;
  for (int by = 0; by < side; by += 4)
    for (int bx = 0; bx < side; bx += 4)
      for (int y = by; y < by + 4; ++y)
        for (int x = bx; x < bx + 4; ++x) {
          const glm::vec3 d{0.8f * ((x + 0.5f) / side - 0.5f), 0.8f * ((y + 0.5f) / side - 0.5f), -1.0f};
          const glm::vec3 o = glm::vec3(3.0f, 2.0f, 120.0f) + d;
          rays.push_back(Ray{{o.x, o.y, o.z}, 0.0f, {d.x, d.y, d.z}, INFINITY});
          const glm::vec3 p{80.0f * ((x + 0.5f) / side - 0.5f), 80.0f * ((y + 0.5f) / side - 0.5f), 120.0f};
          orthographic.push_back(Ray{{p.x, p.y, p.z}, 0.0f, {0.05f, 0.03f, -1.0f}, INFINITY});
        }
  rays.insert(rays.end(), orthographic.begin(), orthographic.end());
  for (Isa isa : accel_test::all_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const Accel prototype = prototype_of(soup, isa);
    Accel scene;
    add_soup(scene, own);
    for (const std::vector<float>& m : placements()) scene.add_instance(prototype, m.data());
    scene.commit({TriangleTest::watertight, isa});
    std::vector<Hit> single(rays.size());
    int through = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      single[i] = scene.intersect(rays[i]);
      through += single[i].inst != kInvalidId;
    }
    CHECK(through > int(rays.size()) / 8);
    report(check_forms(scene, rays, single, 23), "camera packets through instances: forms against single rays");
  }
}

TEST_CASE("instances: masked packets and streams answer as masked single rays, every ISA") {
  // The packet walk of the top level takes each lane's mask to the layers and to the
  // prototypes its lanes reach (full and partial packets).
  const accel_test::Soup soup = accel_test::random_soup(200, 91), own = accel_test::random_soup(60, 92);
  for (Isa isa : accel_test::all_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const Accel prototype = prototype_of(soup, isa);
    Accel scene;
    scene.set_geometry_mask(add_soup(scene, own), 0x1);
    std::uint32_t k = 0;
    for (const std::vector<float>& m : placements())
      scene.set_geometry_mask(scene.add_instance(prototype, m.data()), (k++ % 2) ? 0x2 : 0x4);
    scene.commit({TriangleTest::watertight, isa});
    const std::vector<Ray> rays = aimed_rays(soup, 9);
    std::mt19937 rng(17);
    std::vector<std::uint32_t> masks(rays.size());
    for (std::uint32_t& m : masks) m = rng() % 8;  // 0 sees nothing, 7 everything
    std::vector<Hit> want(rays.size());
    std::vector<std::uint8_t> blocked_want(rays.size());
    int through = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      want[i] = scene.intersect(rays[i], masks[i]);
      blocked_want[i] = scene.occluded(rays[i], masks[i]) ? 1 : 0;
      CHECK(blocked_want[i] == (want[i].hit() ? 1 : 0));
      through += want[i].inst != kInvalidId;
    }
    CHECK(through > int(rays.size()) / 4);
    int packet = 0, packet_occluded = 0, inactive = 0;
    for (std::size_t first = 0; first + 16 <= rays.size(); first += 16) {
      volley::RayPacket<16> p;
      volley::load(p, rays.data() + first, 16);
      if ((first / 16) % 3 == 1) p.active = static_cast<std::uint32_t>(rng()) & 0xffffu;  // partial packets
      volley::HitPacket<16> h;
      volley::reset(h);
      scene.intersect(p, h, masks.data() + first);
      const std::uint32_t blocked = scene.occluded(p, masks.data() + first);
      for (int i = 0; i < 16; ++i) {
        if (!((p.active >> i) & 1u)) {
          inactive += h.t[i] != INFINITY || ((blocked >> i) & 1u);
          continue;
        }
        const Hit got = volley::hit_of(h, i), w = want[first + i];
        packet += !(got.hit() == w.hit() && (!w.hit() || (got.prim == w.prim && got.geom == w.geom &&
                                                          got.inst == w.inst && got.t == w.t)));
        packet_occluded += ((blocked >> i) & 1u) != blocked_want[first + i];
      }
    }
    CHECK(packet == 0);
    CHECK(packet_occluded == 0);
    CHECK(inactive == 0);
    std::vector<Hit> hits(rays.size());
    std::vector<std::uint8_t> blocked(rays.size());
    scene.intersect(rays.data(), masks.data(), rays.size(), hits.data());
    scene.occluded(rays.data(), masks.data(), rays.size(), blocked.data());
    int stream = 0;
    for (std::size_t i = 0; i < rays.size(); ++i)
      stream += !(hits[i].hit() == want[i].hit() && hits[i].prim == want[i].prim && hits[i].inst == want[i].inst &&
                  hits[i].t == want[i].t) ||
                blocked[i] != blocked_want[i];
    CHECK(stream == 0);
  }
}

TEST_CASE("instances: a closed mesh stays watertight through mirrored and scaled instances") {
  // An octahedron: rays from inside toward its vertices and edge midpoints must all hit.
  const float v[] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
  const std::uint32_t idx[] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  for (Isa isa : {Isa::scalar, Isa::avx2, Isa::avx512}) {
    if (!volley::simd::cpu_has(isa)) continue;
    CAPTURE(std::string(volley::to_string(isa)));
    Accel oct;
    oct.add_triangles(v, 6, idx, 8);
    oct.commit({TriangleTest::watertight, isa});
    const std::vector<std::vector<float>> ts = {transform({-1, 1, 1}, 0, {3, 0, 0}),
                                                transform({1e3f, 1e-3f, 1}, 33, {-1e4f, 7, 2}),
                                                transform({-0.01f, -0.01f, 0.01f}, 111, {0.5f, 1e5f, -3})};
    for (const std::vector<float>& m : ts) {
      Accel scene;
      scene.add_instance(oct, m.data());
      scene.commit({TriangleTest::watertight, isa});
      const glm::vec3 center = apply(m, {0, 0, 0});
      int misses = 0, rays = 0;
      for (int a = 0; a < 6; ++a)
        for (int b = a; b < 6; ++b) {
          const glm::vec3 pa(v[3 * a], v[3 * a + 1], v[3 * a + 2]), pb(v[3 * b], v[3 * b + 1], v[3 * b + 2]);
          if (a != b && glm::dot(pa, pb) < -0.5f) continue;  // opposite vertices: no edge
          const glm::vec3 target = apply(m, 0.5f * (pa + pb)), d = target - center;
          ++rays;
          misses += !scene.intersect(Ray{{center.x, center.y, center.z}, 0, {d.x, d.y, d.z}, INFINITY}).hit();
        }
      CHECK(rays == 18);
      CHECK(misses == 0);
    }
  }
}

TEST_CASE("instances: disabled, masked, shared, and bad calls") {
  const accel_test::Soup soup = accel_test::random_soup(50, 3);
  const Isa isa = volley::simd::cpu_has(Isa::avx2) ? Isa::avx2 : Isa::sse42;
  Accel scene;
  std::uint32_t a = 0, b = 0;
  const std::vector<float> left = transform({1, 1, 1}, 0, {-40, 0, 0}), right = transform({1, 1, 1}, 0, {40, 0, 0});
  {
    Accel prototype;
    add_soup(prototype, soup);
    CHECK_THROWS_WITH_AS(scene.add_instance(prototype, left.data()), doctest::Contains("commit the prototype"),
                         volley::Error);
    prototype.commit({TriangleTest::watertight, isa});
    a = scene.add_instance(prototype, left.data());
    b = scene.add_instance(prototype, right.data());
    // The prototype goes out of scope here: the instances keep its structure alive.
  }
  scene.commit({TriangleTest::watertight, isa});
  const glm::vec3 c = soup.vertex(0, 0) * (1.0f / 3) + soup.vertex(0, 1) * (1.0f / 3) + soup.vertex(0, 2) * (1.0f / 3);
  const Ray to_a{{c.x - 40, c.y, 50}, 0, {0, 0, -1}, INFINITY}, to_b{{c.x + 40, c.y, 50}, 0, {0, 0, -1}, INFINITY};
  REQUIRE(scene.intersect(to_a).hit());
  CHECK(scene.intersect(to_a).inst == a);
  CHECK(scene.intersect(to_b).inst == b);
  CHECK(scene.info().bytes < 2000);  // the instance BVH only: the prototype is shared
  scene.disable_geometry(a);
  scene.set_geometry_mask(b, 0x4);
  scene.commit({TriangleTest::watertight, isa});
  CHECK(!scene.intersect(to_a).hit());
  CHECK(scene.intersect(to_b, 0x4).inst == b);
  CHECK(!scene.intersect(to_b, 0x2).hit());
  CHECK(!scene.occluded(to_b, 0x2));
  CHECK(scene.occluded(to_b, 0x6));

  const float nan = std::nanf("");
  const std::vector<float> singular = transform({1, 0, 1}, 0, {0, 0, 0});
  std::vector<float> bad = left;
  bad[7] = nan;
  Accel proto2;
  add_soup(proto2, soup);
  proto2.commit();
  Accel other;
  CHECK_THROWS_WITH_AS(other.add_instance(proto2, singular.data()), doctest::Contains("singular"), volley::Error);
  CHECK_THROWS_WITH_AS(other.add_instance(proto2, bad.data()), doctest::Contains("entry 7"), volley::Error);
  CHECK_THROWS_WITH_AS(other.add_instance(proto2, nullptr), doctest::Contains("null"), volley::Error);
  CHECK_THROWS_WITH_AS(proto2.add_instance(proto2, left.data()), doctest::Contains("itself"), volley::Error);
  CHECK_THROWS_WITH_AS(other.add_instance(scene, left.data()), doctest::Contains("one level"), volley::Error);
  CHECK_THROWS_WITH_AS(scene.update_vertices(b, soup.xyz.data(), 3), doctest::Contains("an instance"), volley::Error);
  CHECK_THROWS_WITH_AS(scene.save("/tmp/volley_instances.vacc"), doctest::Contains("instances"), volley::Error);
}

TEST_CASE("geometric_normal: triangles as added, polygons, instances under the inverse transpose, loaded files") {
  namespace fs = std::filesystem;
  // A triangle in z = 1 wound counter-clockwise seen from +z, one wound the other way in
  // z = 2, a degenerate one, and a polygon (a square in x = 5, normal +x by its order).
  const float tris[] = {0, 0, 1, 1, 0, 1, 0, 1, 1,  0, 0, 2, 0, 1, 2, 1, 0, 2,  0, 0, 3, 1, 1, 3, 2, 2, 3};
  const float square[] = {5, 0, 0, 5, 1, 0, 5, 1, 1, 5, 0, 1};
  Accel a;
  const std::uint32_t idx[] = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  const std::uint32_t g = a.add_triangles(tris, 9, idx, 3);
  const std::uint32_t p = a.add_polygon(square, 4);
  CHECK_THROWS_AS(a.geometric_normal(Hit{1.0f, 0, 0, 0, g}), volley::Error);
  a.commit();
  auto normal_is = [](std::array<float, 3> n, float x, float y, float z) {
    return std::fabs(n[0] - x) < 1e-6f && std::fabs(n[1] - y) < 1e-6f && std::fabs(n[2] - z) < 1e-6f;
  };
  CHECK(normal_is(a.geometric_normal(Hit{1.0f, 0, 0, 0, g}), 0, 0, 1));
  CHECK(normal_is(a.geometric_normal(Hit{1.0f, 0, 0, 1, g}), 0, 0, -1));
  CHECK(std::isnan(a.geometric_normal(Hit{1.0f, 0, 0, 2, g})[0]));  // degenerate
  CHECK(normal_is(a.geometric_normal(Hit{1.0f, 0, 0, 0, p}), 1, 0, 0));
  CHECK(std::isnan(a.geometric_normal(Hit{})[0]));                 // a miss
  CHECK(std::isnan(a.geometric_normal(Hit{1.0f, 0, 0, 9, g})[2]));  // no such primitive
  CHECK(std::isnan(a.geometric_normal(Hit{1.0f, 0, 0, 0, 7})[1]));  // no such geometry
  // A ray's hit names the primitive whose normal comes back.
  const Hit down = a.intersect(Ray{{0.2f, 0.2f, 5.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY});
  REQUIRE(down.hit());
  CHECK(normal_is(a.geometric_normal(down), 0, 0, -1));  // the z = 2 triangle, wound clockwise from above

  // Through an instance that scales x by 2 and rotates 90 degrees about z: a plane's normal
  // follows the inverse transpose (a shear-free scale keeps axis normals on their axes).
  Accel scene;
  const float transform[12] = {0, -2, 0, 10,  2, 0, 0, 0,  0, 0, 1, 0};  // (x, y) -> (-2y + 10, 2x)
  const std::uint32_t inst = scene.add_instance(a, transform);
  scene.commit();
  CHECK(normal_is(scene.geometric_normal(Hit{1.0f, 0, 0, 0, p, inst}), 0, 1, 0));  // +x turned to +y
  CHECK(normal_is(scene.geometric_normal(Hit{1.0f, 0, 0, 0, g, inst}), 0, 0, 1));
  const float skew[12] = {1, 1, 0, 0,  0, 1, 0, 0,  0, 0, 1, 0};  // x += y
  Accel sheared;
  const std::uint32_t s = sheared.add_instance(a, skew);
  sheared.commit();
  // The square x = 5 becomes the plane x - y = 5: normal (1, -1, 0) / sqrt 2.
  CHECK(normal_is(sheared.geometric_normal(Hit{1.0f, 0, 0, 0, p, s}), float(M_SQRT1_2), -float(M_SQRT1_2), 0));

  // A loaded Accel reads the vertices from its file.
  const fs::path file = fs::temp_directory_path() / "volley_normals.vacc";
  a.save(file.string());
  const Accel loaded = Accel::load(file.string());
  for (std::uint32_t prim = 0; prim < 3; ++prim) {
    const auto want = a.geometric_normal(Hit{1.0f, 0, 0, prim, g}), got = loaded.geometric_normal(Hit{1.0f, 0, 0, prim, g});
    for (int k = 0; k < 3; ++k) CHECK((got[k] == want[k] || (std::isnan(got[k]) && std::isnan(want[k]))));
  }
  CHECK(normal_is(loaded.geometric_normal(Hit{1.0f, 0, 0, 0, p}), 1, 0, 0));

  // The batch form answers as the single one, hit by hit, whatever the hit names.
  const std::vector<std::pair<const Accel*, Hit>> cases = {
      {&a, Hit{1.0f, 0, 0, 0, g}},      {&a, Hit{1.0f, 0, 0, 1, g}},       {&a, Hit{1.0f, 0, 0, 2, g}},
      {&a, Hit{1.0f, 0, 0, 0, p}},      {&a, Hit{}},                       {&a, Hit{1.0f, 0, 0, 9, g}},
      {&a, Hit{1.0f, 0, 0, 0, 7}},      {&scene, Hit{1.0f, 0, 0, 0, p, inst}}, {&scene, Hit{1.0f, 0, 0, 1, g, inst}},
      {&scene, Hit{1.0f, 0, 0, 0, g, 5}}, {&sheared, Hit{1.0f, 0, 0, 0, p, s}}, {&loaded, Hit{1.0f, 0, 0, 1, g}},
      {&loaded, Hit{1.0f, 0, 0, 2, g}}};
  for (std::size_t c = 0; c < cases.size(); ++c) {
    CAPTURE(c);
    const Accel& owner = *cases[c].first;
    const Hit hits[2] = {cases[c].second, Hit{}};
    float batch[6];
    owner.geometric_normals(hits, 2, batch);
    const auto want = owner.geometric_normal(hits[0]);
    for (int k = 0; k < 3; ++k) CHECK((batch[k] == want[k] || (std::isnan(batch[k]) && std::isnan(want[k]))));
    for (int k = 3; k < 6; ++k) CHECK(std::isnan(batch[k]));
  }
  // On threads: the same normals (the batch split among them), a negative count refused.
  std::vector<Hit> many;
  for (int r = 0; r < 2000; ++r)
    for (std::size_t c = 0; c < 7; ++c) many.push_back(cases[c].second);  // the cases of `a`
  std::vector<float> one(3 * many.size()), spread(3 * many.size());
  a.geometric_normals(many.data(), many.size(), one.data());
  for (const int threads : {0, 3}) {
    a.geometric_normals(many.data(), many.size(), spread.data(), threads);
    CHECK(std::memcmp(one.data(), spread.data(), one.size() * sizeof(float)) == 0);
  }
  CHECK_THROWS_WITH_AS(a.geometric_normals(many.data(), many.size(), spread.data(), -1), doctest::Contains("threads"),
                       volley::Error);
  CHECK_THROWS_WITH_AS(a.geometric_normals(nullptr, 3, spread.data()), doctest::Contains("null"), volley::Error);
  a.geometric_normals(nullptr, 0, nullptr);  // nothing to do
  float none[3];
  CHECK_THROWS_AS(Accel().geometric_normals(&cases[0].second, 1, none), volley::Error);  // not committed
  fs::remove(file);
}
