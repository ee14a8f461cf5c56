// Scalar ray/triangle oracle (core/triangle.h) at vertices and edges: rays exactly at the
// vertices and edge points of float-exact triangles, watertight's exact decision where a
// float edge function rounds to zero, no ray aimed at the shared vertices and edges of a
// closed indexed mesh leaking, and the watertight test's axis choice (make_woop_ray) as its
// branching definition. The rest is in test_triangle.cpp.
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <utility>
#include <vector>

#include "core/triangle.h"
#include "triangle_test_util.h"

namespace {

using namespace triangle_test;

TEST_CASE("triangle: rays exactly at vertices and edge points of float-exact triangles") {
  std::mt19937 rng(99);
  std::uniform_int_distribution<int> coord(-8, 8), off(-7, 7), axis(0, 2), sign(0, 1), eighth(1, 7);
  int rays = 0, misses[3] = {}, vertex_hits_checked = 0;
  while (rays < 3000) {
    const Tri tri{Vec3f(coord(rng), coord(rng), coord(rng)), Vec3f(coord(rng), coord(rng), coord(rng)),
                  Vec3f(coord(rng), coord(rng), coord(rng))};
    if (is_degenerate(tri.p0, tri.p1, tri.p2)) continue;
    const Vec3f p[3] = {tri.p0, tri.p1, tri.p2};
    const int which = rays % 3;
    const int i = axis(rng), j = (i + 1) % 3;
    Vec3f target;
    float want_u = -1, want_v = -1;  // expected barycentrics for vertex targets
    if (which == 0) {
      target = p[i];
      want_u = i == 1 ? 1.0f : 0.0f;
      want_v = i == 2 ? 1.0f : 0.0f;
    } else if (which == 1) {
      target = 0.5f * (p[i] + p[j]);
    } else {
      target = p[i] + (float(eighth(rng)) / 8) * (p[j] - p[i]);
    }
    Vec3f offset(float(off(rng)), float(off(rng)), float(off(rng)));
    offset[axis(rng)] = sign(rng) ? 8.0f : -8.0f;
    const Vec3f org = target + offset;
    const RayT<float> ray{org, 0.0f, target - org, kInf};
    // Skip rays in the triangle's plane (the projected triangle is degenerate there).
    const Vec3d n = glm::cross(Vec3d(tri.p1 - tri.p0), Vec3d(tri.p2 - tri.p0));
    if (std::abs(glm::dot(glm::normalize(n), glm::normalize(Vec3d(ray.dir)))) < 1e-3) continue;
    ++rays;
    for (int k = 0; k < 3; ++k) {
      TriHit<float> h{};
      const bool hit = run(kTests[k], ray, tri, h);
      misses[k] += !hit;
      if (kTests[k] != TriangleTest::watertight) continue;
      CAPTURE(which);
      REQUIRE(hit);
      CHECK(h.t == doctest::Approx(1.0).epsilon(1e-6));
      if (want_u >= 0) {
        CHECK(h.u == want_u);
        CHECK(h.v == want_v);
        ++vertex_hits_checked;
      }
    }
  }
  CHECK(misses[2] == 0);
  CHECK(vertex_hits_checked > 500);
  MESSAGE("boundary-aimed misses out of " << rays << ": plane " << misses[0] << ", moller "
                                          << misses[1] << ", watertight " << misses[2]);
}

// The ray (down +z from the origin, so the shear is exact) passes 2^-46 beside the edge
// B-C shared by two triangles. In float both products of that edge function round to
// -(1 + 2^-22), so it is exactly 0; the double recomputation (paper, section 3.4) recovers
// its sign, and exactly one of the two triangles takes the ray. Without the fallback both do.
TEST_CASE("triangle: watertight decides exactly where a float edge function rounds to zero") {
  const float e22 = std::ldexp(1.0f, -22), e23 = std::ldexp(1.0f, -23);
  const Vec3f b(-(1 + e22), -(1 + e23), 1), c(1 + e23, 1, 1);
  const Tri near_side{Vec3f(-1, 1, 1), b, c};  // exact edge functions all negative: inside
  const Tri far_side{Vec3f(1, -1, 1), c, b};   // across B-C: outside by 2^-46
  REQUIRE(float(c.x * b.y) == float(c.y * b.x));  // the float products do tie
  const RayT<float> ray{Vec3f(0), 0.0f, Vec3f(0, 0, 1), kInf};
  TriHit<float> hf{};
  TriHit<double> hd{};
  CHECK(run(TriangleTest::watertight, ray, near_side, hf));
  CHECK_FALSE(run(TriangleTest::watertight, ray, far_side, hf));
  CHECK(run(TriangleTest::watertight, ray, near_side, hd));
  CHECK_FALSE(run(TriangleTest::watertight, ray, far_side, hd));
}

// ---- watertightness on a closed mesh ---------------------------------------------------------

struct Mesh {
  std::vector<Vec3f> vertices;
  std::vector<std::array<int, 3>> triangles;
};

// Surface of a k x k x k grid cube, spacing 4, every vertex jittered by an integer in
// [-1, 1]^3: closed, indexed, non-convex, with all coordinates small integers, so vertices,
// edge midpoints and edge points at k/8 are float-exact.
Mesh jittered_cube(int k, std::mt19937& rng) {
  Mesh mesh;
  std::map<std::array<int, 3>, int> index;
  std::uniform_int_distribution<int> jitter(-1, 1);
  const auto vertex = [&](std::array<int, 3> g) {
    auto [it, added] = index.emplace(g, int(mesh.vertices.size()));
    if (added) {
      Vec3f p;
      for (int a = 0; a < 3; ++a) p[a] = float(4 * g[a] - 2 * k + jitter(rng));
      mesh.vertices.push_back(p);
    }
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side <= k; side += k) {
      const int ua = (axis + 1) % 3, va = (axis + 2) % 3;
      for (int a = 0; a < k; ++a) {
        for (int b = 0; b < k; ++b) {
          int q[4];
          const int corner[4][2] = {{a, b}, {a + 1, b}, {a + 1, b + 1}, {a, b + 1}};
          for (int c = 0; c < 4; ++c) {
            std::array<int, 3> g{};
            g[axis] = side;
            g[ua] = corner[c][0];
            g[va] = corner[c][1];
            q[c] = vertex(g);
          }
          // Alternate the diagonal so both kinds of shared edge occur.
          if ((a + b) % 2) {
            mesh.triangles.push_back({q[0], q[1], q[2]});
            mesh.triangles.push_back({q[0], q[2], q[3]});
          } else {
            mesh.triangles.push_back({q[0], q[1], q[3]});
            mesh.triangles.push_back({q[1], q[2], q[3]});
          }
        }
      }
    }
  }
  return mesh;
}

template <class T>
bool hits_mesh(TriangleTest test, const RayT<float>& ray, const Mesh& mesh) {
  for (const auto& tri : mesh.triangles) {
    TriHit<T> h{};
    if (run(test, ray, Tri{mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]]}, h))
      return true;
  }
  return false;
}

TEST_CASE("triangle: watertight leaks no ray aimed at shared vertices and edges of a closed mesh") {
  std::mt19937 rng(5);
  const Mesh base = jittered_cube(6, rng);
  // Every vertex is shared by 4-7 triangles; every edge by exactly 2 (closed manifold).
  std::map<std::pair<int, int>, int> edge_use;
  for (const auto& t : base.triangles)
    for (int e = 0; e < 3; ++e)
      edge_use[std::minmax(t[e], t[(e + 1) % 3])]++;
  for (const auto& [edge, use] : edge_use) REQUIRE(use == 2);

  // Targets: every vertex, and on every edge its midpoint and the points at 1/8, 3/8, 3/4.
  std::vector<Vec3f> targets_local(base.vertices);
  for (const auto& [edge, use] : edge_use) {
    const Vec3f a = base.vertices[edge.first], b = base.vertices[edge.second];
    for (float f : {0.5f, 0.125f, 0.375f, 0.75f}) targets_local.push_back(a + f * (b - a));
  }
  // Interior origins: dyadic ones (exact directions) and two arbitrary floats.
  const std::vector<Vec3f> origins_local = {Vec3f(0), Vec3f(0.5f, -0.25f, 0.125f), Vec3f(3, -2, 1),
                                            Vec3f(-5.5f, 4.25f, -2.75f), uniform3(rng, -5, 5)};

  for (float shift : {0.0f, 1e3f, 1e6f}) {
    Mesh mesh = base;
    for (Vec3f& v : mesh.vertices) v += Vec3f(shift, -shift, shift);
    int rays = 0, leaks[3] = {}, leaks_double[3] = {};
    for (const Vec3f& o : origins_local) {
      const Vec3f org = o + Vec3f(shift, -shift, shift);
      for (const Vec3f& t : targets_local) {
        const Vec3f target = t + Vec3f(shift, -shift, shift);
        const RayT<float> ray{org, 0.0f, target - org, kInf};
        ++rays;
        for (int k = 0; k < 3; ++k) {
          leaks[k] += !hits_mesh<float>(kTests[k], ray, mesh);
          if (shift == 0) leaks_double[k] += !hits_mesh<double>(kTests[k], ray, mesh);
        }
      }
    }
    CAPTURE(shift);
    MESSAGE("closed mesh (" << mesh.triangles.size() << " triangles) shifted by " << shift << ": "
                            << rays << " rays, float leaks: plane " << leaks[0] << ", moller "
                            << leaks[1] << ", watertight " << leaks[2]);
    if (shift == 0)
      MESSAGE("  double leaks: plane " << leaks_double[0] << ", moller " << leaks_double[1]
                                       << ", watertight " << leaks_double[2]);
    CHECK(leaks[2] == 0);
    if (shift == 0) CHECK(leaks_double[2] == 0);
  }
}

}  // namespace

TEST_CASE("triangle: make_woop_ray picks the axes of its branching definition for every special direction") {
  // The axis choice is a lookup (core::kWoopAxes, no branches); this is the definition it encodes:
  // kz the largest |component| (first of ties by the comparisons below), kx, ky the next
  // axes cyclically, swapped when dir[kz] < 0. NaN compares false everywhere.
  auto expected = [](const Vec3f& dir) {
    const float ax = std::abs(dir.x), ay = std::abs(dir.y), az = std::abs(dir.z);
    const int kz = ax >= ay ? (ax >= az ? 0 : 2) : (ay >= az ? 1 : 2);
    int kx = kz + 1 == 3 ? 0 : kz + 1;
    int ky = kx + 1 == 3 ? 0 : kx + 1;
    if (dir[kz] < 0) std::swap(kx, ky);
    return std::array<int, 3>{kx, ky, kz};
  };
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  const std::array<float, 11> values = {0.0f, -0.0f, 1.0f, -1.0f, 2.0f, -2.0f, inf, -inf, nan, 1e-45f, -1e-45f};
  int checked = 0;
  for (float x : values)
    for (float y : values)
      for (float z : values) {
        const Vec3f dir(x, y, z);
        const auto w = volley::core::make_woop_ray(dir);
        const auto e = expected(dir);
        CAPTURE(x);
        CAPTURE(y);
        CAPTURE(z);
        CHECK(w.kx == e[0]);
        CHECK(w.ky == e[1]);
        CHECK(w.kz == e[2]);
        const float sz = 1.0f / dir[e[2]];
        CHECK((w.sz == sz || (std::isnan(w.sz) && std::isnan(sz))));
        ++checked;
      }
  CHECK(checked == 1331);
}
