// The crossing queries (Accel::intersect_all, count_intersections, contains): every ISA's
// hits are the scalar twin's (core::intersect_watertight with the crossing rule, in the
// ISA's fused variant) hit for hit; rays from inside closed meshes aimed exactly at
// vertices, edge midpoints and diagonals cross an odd number of times at offsets up to
// 1e6, and on axis-aligned box meshes with axis-aligned rays; rays from outside an even
// number; contains agrees with a double-precision winding number away from the surface.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "accel_test_util.h"
#include "accuracy/closed_meshes.h"
#include "core/triangle_watertight.h"
#include "simd/isa/dispatch.h"
#include "volley/accel.h"

using volley::Accel;
using volley::Hit;
using volley::Isa;
using volley::Ray;
using volley::TriangleTest;
using volley::accuracy::ClosedMesh;

namespace {

Accel mesh_accel(const volley::accuracy::Mesh& m, Isa isa, float offset = 0.0f, TriangleTest test = TriangleTest::watertight) {
  std::vector<float> xyz = m.xyz;
  for (float& x : xyz) x = volley::accuracy::to_float(double(x) + offset);
  Accel a;
  a.add_triangles(xyz.data(), m.vertices(), m.idx.data(), m.triangles());
  a.commit(volley::Options{test, isa});
  return a;
}

std::vector<Isa> every_isa() {
  std::vector<Isa> isas{Isa::scalar};
  for (Isa i : accel_test::simd_isas()) isas.push_back(i);
  return isas;
}

/// The scalar twin: every triangle by brute force, crossing rule, the ISA's fused variant.
std::vector<Hit> twin_hits(const accel_test::Soup& soup, const Ray& ray, Isa isa) {
  std::vector<Hit> out;
  if (!accel_test::finite_ray(ray)) return out;
  const volley::core::RayT<float> r{{ray.org[0], ray.org[1], ray.org[2]}, ray.tmin, {ray.dir[0], ray.dir[1], ray.dir[2]}, ray.tmax};
  for (std::size_t i = 0; i < soup.size(); ++i) {
    if (volley::core::is_degenerate(soup.vertex(i, 0), soup.vertex(i, 1), soup.vertex(i, 2))) continue;
    volley::core::TriHit<float> h;
    const bool hit = volley::core::watertight_fused_for(isa)
                         ? volley::core::intersect_watertight<float, true, true>(r, soup.vertex(i, 0), soup.vertex(i, 1), soup.vertex(i, 2), h)
                         : volley::core::intersect_watertight<float, false, true>(r, soup.vertex(i, 0), soup.vertex(i, 1), soup.vertex(i, 2), h);
    if (hit) out.push_back(Hit{h.t, h.u, h.v, static_cast<std::uint32_t>(i), 0});
  }
  std::sort(out.begin(), out.end(), [](const Hit& x, const Hit& y) { return x.t != y.t ? x.t < y.t : x.prim < y.prim; });
  return out;
}

accel_test::Soup soup_of(const volley::accuracy::Mesh& m, float offset = 0.0f) {
  accel_test::Soup s;
  for (std::size_t t = 0; t < m.triangles(); ++t) {
    glm::vec3 v[3];
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) v[k][a] = volley::accuracy::to_float(double(m.xyz[3 * m.idx[3 * t + k] + a]) + offset);
    s.add(v[0], v[1], v[2]);
  }
  return s;
}

std::vector<Hit> all_of(const Accel& a, const Ray& ray) {
  std::vector<Hit> hits(a.count_intersections(ray) + 4);
  const std::size_t n = a.intersect_all(ray, hits.data(), hits.size());
  hits.resize(n);
  return hits;
}

/// Rays from every interior origin of the mesh toward every exact target, unbounded.
std::vector<Ray> aimed_rays(const ClosedMesh& c, float offset) {
  std::size_t exact = 0, origins = 0;
  std::vector<Ray> rays = volley::accuracy::closed_mesh_rays(c, offset, exact, origins);
  for (Ray& r : rays) r.tmax = accel_test::kInf;
  return rays;
}

}  // namespace

TEST_CASE("crossings: every ISA's hits are the scalar twin's, hit for hit") {
  const ClosedMesh cube = volley::accuracy::grid_cube(3);
  const ClosedMesh sphere = volley::accuracy::icosphere(2, 40.0);
  for (const ClosedMesh* c : {&cube, &sphere}) {
    for (float offset : {0.0f, 1e5f}) {
      const accel_test::Soup soup = soup_of(c->mesh, offset);
      std::vector<Ray> rays = aimed_rays(*c, offset);
      // Random rays through the mesh's box, and rays the API rejects.
      std::mt19937 rng(7);
      std::uniform_real_distribution<float> u(-0.2f * float(c->size), 1.2f * float(c->size)), d(-1.0f, 1.0f);
      for (int i = 0; i < 300; ++i)
        rays.push_back(accel_test::make_ray(glm::vec3(u(rng), u(rng), u(rng)) + offset, {d(rng), d(rng), d(rng)}));
      rays.push_back(accel_test::make_ray({accel_test::kNaN, 0, 0}, {1, 0, 0}));
      rays.push_back(accel_test::make_ray({1, 1, 1}, {0, 0, 0}));
      for (Isa isa : every_isa()) {
        const Accel a = soup.accel(TriangleTest::watertight, isa);
        std::size_t wrong = 0;
        for (const Ray& r : rays) {
          const std::vector<Hit> got = all_of(a, r), want = twin_hits(soup, r, isa);
          bool same = got.size() == want.size();
          for (std::size_t k = 0; same && k < got.size(); ++k)
            same = got[k].t == want[k].t && got[k].u == want[k].u && got[k].v == want[k].v && got[k].prim == want[k].prim &&
                   got[k].geom == 0 && got[k].inst == volley::kInvalidId;
          wrong += !same;
        }
        INFO(c->name << " offset " << offset << " " << volley::to_string(isa));
        CHECK(wrong == 0);
      }
    }
  }
}

TEST_CASE("crossings: rays from inside closed meshes aimed at vertices, edges and diagonals cross an odd number of times") {
  const ClosedMesh meshes[] = {volley::accuracy::grid_cube(4), volley::accuracy::icosphere(2, 40.0),
                               volley::accuracy::icosphere(3, 200.0)};
  for (const ClosedMesh& c : meshes) {
    for (float offset : {0.0f, 1e3f, 1e5f, 1e6f}) {
      const std::vector<Ray> rays = aimed_rays(c, offset);
      REQUIRE(rays.size() > 100);
      for (Isa isa : every_isa()) {
        const Accel a = mesh_accel(c.mesh, isa, offset);
        std::size_t even = 0, batch_even = 0;
        for (const Ray& r : rays) even += a.count_intersections(r) % 2 == 0;
        // The batch form (runs of 16 rays as packets where the stream policy says so).
        std::vector<std::uint32_t> counts(rays.size());
        a.count_intersections(rays.data(), rays.size(), counts.data(), 1);
        for (std::uint32_t n : counts) batch_even += n % 2 == 0;
        INFO(c.name << " offset " << offset << " " << volley::to_string(isa) << ": " << rays.size() << " rays");
        CHECK(even == 0);
        CHECK(batch_even == 0);
      }
    }
  }
}

TEST_CASE("crossings: axis-aligned rays through the vertices and edges of a box mesh cross once, from outside twice or never") {
  const ClosedMesh c = volley::accuracy::grid_cube(4);
  for (Isa isa : every_isa()) {
    const Accel a = mesh_accel(c.mesh, isa);
    std::size_t wrong_inside = 0, odd_outside = 0, rays = 0;
    for (int i = 0; i <= 8; ++i)
      for (int j = 0; j <= 8; ++j)
        for (int axis = 0; axis < 3; ++axis)
          for (float sign : {1.0f, -1.0f}) {
            // Along `axis` at half-integer coordinates of the other two: through vertices,
            // edges and quad diagonals' midpoints of the faces it meets.
            float o[3], d[3] = {0, 0, 0};
            o[(axis + 1) % 3] = 0.5f * i, o[(axis + 2) % 3] = 0.5f * j;
            d[axis] = sign;
            const bool inside = i > 0 && i < 8 && j > 0 && j < 8;
            o[axis] = 2.25f;  // inside the cube [0, 4]^3 when the others are
            const std::uint32_t n = a.count_intersections(Ray{{o[0], o[1], o[2]}, 0.0f, {d[0], d[1], d[2]}, accel_test::kInf});
            // From outside the box entirely: the ray enters and leaves (or grazes a face).
            o[axis] = sign > 0 ? -1.0f : 5.0f;
            const std::uint32_t m = a.count_intersections(Ray{{o[0], o[1], o[2]}, 0.0f, {d[0], d[1], d[2]}, accel_test::kInf});
            ++rays;
            if (inside) wrong_inside += n != 1;
            odd_outside += m % 2;
          }
    INFO(volley::to_string(isa) << ": " << rays << " rays");
    CHECK(wrong_inside == 0);
    CHECK(odd_outside == 0);
  }
}

TEST_CASE("crossings: rays from outside aimed at the surface's vertices and edges cross an even number of times") {
  const ClosedMesh c = volley::accuracy::icosphere(2, 40.0);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (Isa isa : every_isa()) {
    const Accel a = mesh_accel(c.mesh, isa);
    std::size_t odd = 0, rays = 0;
    for (int k = 0; k < 6; ++k) {
      // Origins well outside, including silhouette-grazing directions at the targets.
      const double dir[3] = {u(rng), u(rng), u(rng)};
      const double len = std::sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
      float o[3];
      for (int i = 0; i < 3; ++i) o[i] = float(c.size + 3.0 * c.size * dir[i] / len);
      for (const auto& t : c.targets) {
        const Ray r{{o[0], o[1], o[2]}, 0.0f, {float(t[0]) - o[0], float(t[1]) - o[1], float(t[2]) - o[2]}, accel_test::kInf};
        odd += a.count_intersections(r) % 2;
        ++rays;
      }
    }
    INFO(volley::to_string(isa) << ": " << rays << " rays");
    CHECK(odd == 0);
  }
}

TEST_CASE("crossings: contains agrees with a double-precision reference away from the surface") {
  const ClosedMesh meshes[] = {volley::accuracy::grid_cube(3), volley::accuracy::icosphere(2, 40.0)};
  for (const ClosedMesh& c : meshes) {
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(-0.1f * float(c.size), 2.1f * float(c.size));
    std::vector<float> xyz;
    std::vector<int> want;
    while (want.size() < 2000) {
      const std::array<double, 3> p{u(rng), u(rng), u(rng)};
      // grid_cube winds opposite faces alike (the leak tests need it), so its reference is
      // the box itself; the icosphere's is its winding number.
      int inside = 0;
      if (c.name.rfind("cube", 0) == 0) {
        const double depth = c.depth(p, c.size);
        if (std::abs(depth) < 1e-3) continue;  // near the surface: no sure reference
        inside = depth > 0;
      } else {
        const double w = volley::accuracy::winding_number(c.mesh, p);
        if (std::abs(w - std::round(w)) > 1e-3) continue;
        inside = std::lround(w) != 0;
      }
      xyz.insert(xyz.end(), {float(p[0]), float(p[1]), float(p[2])});
      want.push_back(inside);
    }
    for (Isa isa : every_isa()) {
      const Accel a = mesh_accel(c.mesh, isa);
      std::vector<std::uint8_t> got(want.size());
      a.contains(xyz.data(), want.size(), got.data(), 0);
      std::size_t wrong = 0;
      for (std::size_t i = 0; i < want.size(); ++i) {
        wrong += got[i] != want[i];
        CHECK(a.contains(&xyz[3 * i]) == bool(got[i]));
      }
      INFO(c.name << " " << volley::to_string(isa));
      CHECK(wrong == 0);
    }
  }
}

TEST_CASE("crossings: batches on 0, 1 and 3 threads give the single-ray answers, lists are in ray order") {
  const accel_test::Soup soup = accel_test::random_soup(400, 21);
  const Accel a = soup.accel(TriangleTest::watertight, Isa::automatic);
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-12.0f, 12.0f);
  std::vector<Ray> rays;
  for (int i = 0; i < 3000; ++i)
    rays.push_back(accel_test::make_ray({u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}));
  for (int threads : {0, 1, 3}) {
    std::vector<std::uint32_t> counts(rays.size());
    a.count_intersections(rays.data(), rays.size(), counts.data(), threads);
    const volley::HitLists lists = a.intersect_all(rays.data(), rays.size(), threads);
    REQUIRE(lists.offsets.size() == rays.size() + 1);
    CHECK(lists.offsets.back() == lists.hits.size());
    std::size_t wrong = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const std::vector<Hit> one = all_of(a, rays[i]);
      wrong += counts[i] != one.size() || lists.offsets[i + 1] - lists.offsets[i] != one.size();
      for (std::size_t k = 0; k < one.size() && k < lists.offsets[i + 1] - lists.offsets[i]; ++k)
        wrong += lists.hits[lists.offsets[i] + k].t != one[k].t || lists.hits[lists.offsets[i] + k].prim != one[k].prim;
    }
    INFO(threads << " threads");
    CHECK(wrong == 0);
  }
  CHECK_THROWS_AS(a.count_intersections(rays.data(), rays.size(), nullptr, 0), volley::Error);
  std::uint32_t one = 0;
  CHECK_THROWS_AS(a.count_intersections(rays.data(), 1, &one, -1), volley::Error);
}

TEST_CASE("crossings: a short buffer gets the nearest hits and the full count, polygons, geometries and instances are attributed") {
  // Two parallel quads as triangles (geometry 0), a square polygon between them (geometry 1).
  const float quads[] = {0, 0, 0, 4, 0, 0, 4, 4, 0, 0, 4, 0, 0, 0, 2, 4, 0, 2, 4, 4, 2, 0, 4, 2};
  const std::uint32_t idx[] = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
  const float square[] = {0, 0, 1, 4, 0, 1, 4, 4, 1, 0, 4, 1};
  Accel proto;
  proto.add_triangles(quads, 8, idx, 4);
  proto.add_polygon(square, 4);
  proto.commit();
  // Through the shared diagonal of both quads: one hit per quad, not two.
  const Ray diag{{1, 1, -1}, 0.0f, {0, 0, 1}, accel_test::kInf};
  Hit hits[2];
  REQUIRE(proto.intersect_all(diag, hits, 2) == 3);
  CHECK(hits[0].t == 1.0f);
  CHECK(hits[0].geom == 0);
  CHECK(hits[1].t == 2.0f);
  CHECK(hits[1].geom == 1);
  CHECK(hits[1].prim == 0);
  CHECK(proto.count_intersections(diag) == 3);
  CHECK(proto.intersect_all(diag, nullptr, 0) == 3);
  CHECK_THROWS_AS(proto.intersect_all(diag, nullptr, 1), volley::Error);
  // Masks select layers as for intersect.
  CHECK(proto.count_intersections(diag, 0u) == 0);
  // The same through two instances, 10 apart along z.
  Accel scene;
  const float at0[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0}, at10[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 10};
  const std::uint32_t i0 = scene.add_instance(proto, at0), i1 = scene.add_instance(proto, at10);
  scene.commit();
  Hit six[6];
  REQUIRE(scene.intersect_all(diag, six, 6) == 6);
  CHECK(six[0].inst == i0);
  CHECK(six[5].inst == i1);
  CHECK(six[5].t == 13.0f);
  CHECK(scene.count_intersections(Ray{{2, 2, 0.5f}, 0.0f, {0, 0, 1}, accel_test::kInf}) == 5);
}
