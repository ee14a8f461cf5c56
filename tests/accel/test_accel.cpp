// The public Accel API: input validation, prim ids, closest hit across triangles and
// polygons, occlusion, and agreement with brute force over the scalar oracle.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

#include "core/triangle.h"
#include "simd/isa/dispatch.h"
#include "volley/accel.h"

using volley::Accel;
using volley::Hit;
using volley::Ray;
using volley::Isa;
using volley::TriangleTest;

namespace {

Ray make_ray(glm::vec3 o, glm::vec3 d, float tmin = 0.0f, float tmax = INFINITY) {
  return Ray{{o.x, o.y, o.z}, tmin, {d.x, d.y, d.z}, tmax};
}

const volley::TriangleTest kTests[] = {volley::TriangleTest::plane, volley::TriangleTest::moller,
                                       volley::TriangleTest::watertight};

}  // namespace

TEST_CASE("accel: bad input is rejected with a message") {
  Accel accel;
  const float xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::uint32_t bad[] = {0, 1, 3};
  CHECK_THROWS_WITH_AS(accel.add_triangles(xyz, 3, bad, 1), doctest::Contains("vertex index 3"), volley::Error);
  const float nan_xyz[] = {0, 0, 0, NAN, 0, 0, 0, 1, 0};
  const std::uint32_t ok[] = {0, 1, 2};
  CHECK_THROWS_WITH_AS(accel.add_triangles(nan_xyz, 3, ok, 1), doctest::Contains("non-finite"), volley::Error);
  const float bent[] = {0, 0, 0, 1, 0, 0, 1, 1, 0.5f, 0, 1, 0};
  CHECK_THROWS_AS(accel.add_polygon(bent, 4), volley::Error);
  Accel fresh;
  CHECK_THROWS_WITH_AS(fresh.intersect(make_ray({0, 0, 0}, {0, 0, 1})), doctest::Contains("commit"), volley::Error);
}

TEST_CASE("accel: each add call is a geometry, hits name it and the primitive within it, and the closest of triangles and polygons wins") {
  for (auto test : kTests) {
    CAPTURE(std::string(volley::to_string(test)));
    Accel accel;
    // Two triangles at z = 5 and z = 3, then a square polygon at z = 4.
    const float tris[] = {-1, -1, 5, 1, -1, 5, 0, 1, 5, -1, -1, 3, 1, -1, 3, 0, 1, 3};
    const std::uint32_t idx[] = {0, 1, 2, 3, 4, 5};
    CHECK(accel.add_triangles(tris, 6, idx, 2) == 0);
    const float square[] = {-2, -2, 4, 2, -2, 4, 2, 2, 4, -2, 2, 4};
    CHECK(accel.add_polygon(square, 4) == 1);
    accel.commit({test, volley::Isa::scalar});
    Hit h = accel.intersect(make_ray({0, 0, 0}, {0, 0, 1}));
    CHECK(h.geom == 0);
    CHECK(h.prim == 1);
    CHECK(h.inst == volley::kInvalidId);
    CHECK(h.t == doctest::Approx(3.0f));
    h = accel.intersect(make_ray({0, 0, 0}, {0, 0, 1}, 3.5f));
    CHECK(h.geom == 1);
    CHECK(h.prim == 0);
    CHECK(h.t == doctest::Approx(4.0f));
    h = accel.intersect(make_ray({1.5f, 1.5f, 0}, {0, 0, 1}));  // outside the triangles
    CHECK(h.geom == 1);
    CHECK(h.prim == 0);
    CHECK(accel.intersect(make_ray({5, 5, 0}, {0, 0, 1})).geom == volley::kInvalidId);
    CHECK(!accel.intersect(make_ray({5, 5, 0}, {0, 0, 1})).hit());
    CHECK(accel.occluded(make_ray({0, 0, 0}, {0, 0, 1})));
    CHECK(!accel.occluded(make_ray({0, 0, 0}, {0, 0, 1}, 0.0f, 3.0f)));  // half-open: t = 3 excluded
    CHECK(!accel.occluded(make_ray({0, 0, 0}, {0, 0, -1})));
    const auto info = accel.info();
    CHECK(info.triangles == 2);
    CHECK(info.polygons == 1);
    CHECK(info.geometries == 2);
  }
}

TEST_CASE("accel: empty geometries take an id and are never reported") {
  const float tris[] = {-1, -1, 5, 1, -1, 5, 0, 1, 5, -1, -1, 3, 1, -1, 3, 0, 1, 3};
  const std::uint32_t first[] = {0, 1, 2}, second[] = {3, 4, 5};
  for (Isa isa : {Isa::scalar, Isa::avx2}) {
    if (!volley::simd::cpu_has(isa)) continue;
    Accel accel;
    CHECK(accel.add_triangles(tris, 6, first, 0) == 0);
    CHECK(accel.add_triangles(tris, 6, first, 1) == 1);
    CHECK(accel.add_triangles(tris, 6, first, 0) == 2);
    CHECK(accel.add_triangles(tris, 6, second, 1) == 3);
    accel.commit({TriangleTest::watertight, isa});
    const Hit near = accel.intersect(make_ray({0, 0, 0}, {0, 0, 1}));
    CHECK(near.geom == 3);
    CHECK(near.prim == 0);
    const Hit far = accel.intersect(make_ray({0, 0, 0}, {0, 0, 1}, 4.0f));
    CHECK(far.geom == 1);
    CHECK(far.prim == 0);
    CHECK(accel.info().geometries == 4);
  }
}

TEST_CASE("accel: a disabled geometry is left out from the next commit until it is enabled again") {
  const float tris[] = {-1, -1, 5, 1, -1, 5, 0, 1, 5, -1, -1, 3, 1, -1, 3, 0, 1, 3};
  const std::uint32_t first[] = {0, 1, 2}, second[] = {3, 4, 5};
  const float square[] = {-2, -2, 4, 2, -2, 4, 2, 2, 4, -2, 2, 4};
  for (Isa isa : {Isa::scalar, Isa::sse42, Isa::avx2, Isa::avx512}) {
    if (!volley::simd::cpu_has(isa)) continue;
    CAPTURE(std::string(volley::to_string(isa)));
    Accel accel;
    CHECK(accel.add_triangles(tris, 6, first, 1) == 0);   // z = 5
    CHECK(accel.add_triangles(tris, 6, second, 1) == 1);  // z = 3
    CHECK(accel.add_polygon(square, 4) == 2);             // z = 4
    const Ray up = make_ray({0, 0, 0}, {0, 0, 1});
    accel.commit({TriangleTest::watertight, isa});
    CHECK(accel.intersect(up).geom == 1);
    CHECK(accel.intersect(up).prim == 0);  // the index within geometry 1, not scene-wide
    accel.disable_geometry(1);
    CHECK_THROWS_WITH_AS(accel.intersect(up), doctest::Contains("commit"), volley::Error);
    accel.commit({TriangleTest::watertight, isa});
    CHECK(accel.intersect(up).geom == 2);
    CHECK(accel.info().disabled == 1);
    accel.disable_geometry(2);
    accel.commit({TriangleTest::watertight, isa});
    CHECK(accel.intersect(up).geom == 0);
    accel.disable_geometry(0);
    accel.commit({TriangleTest::watertight, isa});
    CHECK(!accel.intersect(up).hit());
    CHECK(!accel.occluded(up));
    accel.enable_geometry(1);
    accel.enable_geometry(1);  // enabling an enabled geometry changes nothing
    accel.commit({TriangleTest::watertight, isa});
    CHECK(accel.intersect(up).geom == 1);
    CHECK(accel.info().disabled == 2);
    CHECK_THROWS_WITH_AS(accel.disable_geometry(3), doctest::Contains("geometry 3 does not exist"), volley::Error);
    CHECK_THROWS_WITH_AS(accel.enable_geometry(0xffffffffu), doctest::Contains("does not exist"), volley::Error);
  }
}

TEST_CASE("accel: an empty accel commits and misses everything") {
  Accel accel;
  accel.commit();
  CHECK(!accel.intersect(make_ray({0, 0, 0}, {0, 0, 1})).hit());
  CHECK(!accel.occluded(make_ray({0, 0, 0}, {0, 0, 1})));
}

TEST_CASE("accel: closest hit equals brute force over the scalar oracle on a random soup") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> pos(-10.0f, 10.0f), small(-1.0f, 1.0f);
  const int n = 2000;
  std::vector<float> xyz;
  std::vector<std::uint32_t> idx;
  for (int i = 0; i < n; ++i) {
    const glm::vec3 c(pos(rng), pos(rng), pos(rng));
    for (int k = 0; k < 3; ++k) {
      xyz.insert(xyz.end(), {c.x + small(rng), c.y + small(rng), c.z + small(rng)});
      idx.push_back(std::uint32_t(3 * i + k));
    }
  }
  for (auto isa : {volley::Isa::scalar, volley::Isa::sse42, volley::Isa::avx2, volley::Isa::avx512})
  for (auto test : kTests) {
    if (!volley::simd::cpu_has(isa)) {
      MESSAGE("skipped: this CPU lacks " << std::string(volley::to_string(isa)));
      continue;
    }
    CAPTURE(std::string(volley::to_string(test)));
    CAPTURE(std::string(volley::to_string(isa)));
    Accel accel;
    accel.add_triangles(xyz.data(), xyz.size() / 3, idx.data(), n);
    accel.commit({test, isa});
    CHECK(accel.info().isa == isa);
    int hits = 0, mismatches = 0;
    for (int r = 0; r < 3000; ++r) {
      const glm::vec3 o(pos(rng) * 2, pos(rng) * 2, pos(rng) * 2);
      const glm::vec3 d = glm::vec3(pos(rng), pos(rng), pos(rng)) - o;
      const Ray ray = make_ray(o, d);
      const Hit h = accel.intersect(ray);
      // Brute force with the same oracle test, in its variant for `isa`.
      float best = INFINITY;
      std::uint32_t best_prim = volley::kInvalidPrim;
      for (int i = 0; i < n; ++i) {
        const glm::vec3 p0(xyz[9 * i], xyz[9 * i + 1], xyz[9 * i + 2]);
        const glm::vec3 p1(xyz[9 * i + 3], xyz[9 * i + 4], xyz[9 * i + 5]);
        const glm::vec3 p2(xyz[9 * i + 6], xyz[9 * i + 7], xyz[9 * i + 8]);
        volley::core::TriHit<float> th;
        if (volley::core::intersect_triangle(test, volley::core::RayT<float>{o, 0.0f, d, best}, p0, p1, p2, th, isa)) {
          best = th.t;
          best_prim = std::uint32_t(i);
        }
      }
      hits += best_prim != volley::kInvalidPrim;
      if (h.prim != best_prim && !(h.hit() && h.t == best)) ++mismatches;
      CHECK(accel.occluded(ray) == (best_prim != volley::kInvalidPrim));
    }
    CHECK(mismatches == 0);
    CHECK(hits > 300);  // the generator really produces hits
    CHECK(hits < 2700); // and misses
  }
}
