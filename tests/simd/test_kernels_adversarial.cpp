// The kernels on the inputs that break ray/triangle code (docs/accuracy.md stress catalogue),
// every test x ISA x form, each answer compared with the scalar oracle: NaN/Inf origins
// and directions, zero direction components, odd search intervals, degenerate triangles,
// rays aimed exactly at vertices and edges, origins on the triangle.
#include "simd_test_util.h"

namespace {

using namespace simd_test;

template <class Arch>
void for_each_test(const Soup& soup, const std::vector<Ray>& rays, const std::string& label) {
  for (TriangleTest test : kTests) {
    Agreement a;
    switch (test) {
      case TriangleTest::moller: a = compare_all_forms<Arch, TriangleTest::moller>(soup, rays, label); break;
      case TriangleTest::plane: a = compare_all_forms<Arch, TriangleTest::plane>(soup, rays, label); break;
      case TriangleTest::watertight: a = compare_all_forms<Arch, TriangleTest::watertight>(soup, rays, label); break;
    }
    INFO(name(test), ": ", a.first);
    CHECK(a.mismatches == 0);
  }
}

Ray make_ray(V3 o, V3 d, float tmin = 0.0f, float tmax = kInf) {
  return Ray{{o.x, o.y, o.z}, tmin, {d.x, d.y, d.z}, tmax};
}

/// Triangles on the integer grid of the plane z = 0 (both diagonals) and a tilted one.
Soup grid_patch() {
  Soup s;
  for (int i = -2; i < 2; ++i)
    for (int j = -2; j < 2; ++j) {
      const V3 a(float(i), float(j), 0), b(float(i + 1), float(j), 0), c(float(i + 1), float(j + 1), 0),
          d(float(i), float(j + 1), 0);
      if ((i + j) % 2 == 0) s.add(a, b, c), s.add(a, c, d);
      else s.add(a, b, d), s.add(b, c, d);
    }
  s.add(V3(-1, -1, -1), V3(1, -1, 1), V3(0, 1, 0.5f));
  return s;
}

}  // namespace

TEST_CASE_TEMPLATE("kernels on NaN and Inf origins and directions match the oracle, never NaN out", Arch,
                   VOLLEY_TEST_ARCHES) {
  if (skip_isa<Arch>()) return;
  const Soup soup = grid_patch();
  const float specials[] = {0.0f, -0.0f, kNaN, kInf, -kInf, 1e-30f, 1e30f, 0.5f, -0.25f};
  std::vector<Ray> rays;
  Generator g(5);
  for (int component = 0; component < 6; ++component)
    for (float x : specials)
      for (int rep = 0; rep < 3; ++rep) {
        Ray r = make_ray(V3(g.uniform(-1, 1), g.uniform(-1, 1), 2.0f), V3(g.uniform(-0.3f, 0.3f), g.uniform(-0.3f, 0.3f), -1));
        (component < 3 ? r.org[component] : r.dir[component - 3]) = x;
        rays.push_back(r);
      }
  // Whole-vector specials: zero direction, NaN origin, Inf direction.
  rays.push_back(make_ray(V3(0.1f, 0.2f, 1), V3(0, 0, 0)));
  rays.push_back(make_ray(V3(kNaN), V3(0, 0, -1)));
  rays.push_back(make_ray(V3(0.1f, 0.2f, 1), V3(kInf)));
  rays.push_back(make_ray(V3(0.1f, 0.2f, 1), V3(-kInf)));
  for_each_test<Arch>(soup, rays, "special values");
}

TEST_CASE_TEMPLATE("kernels with odd search intervals match the oracle", Arch, VOLLEY_TEST_ARCHES) {
  if (skip_isa<Arch>()) return;
  const Soup soup = grid_patch();
  std::vector<Ray> rays;
  const V3 o(0.3f, 0.1f, 2.0f), d(0.05f, -0.1f, -1.0f);  // hits z = 0 at t ~ 2
  const float tmins[] = {0.0f, -kInf, 2.5f, kNaN, 2.0f, 1.0f};
  const float tmaxs[] = {kInf, 1.0f, -kInf, kNaN, 2.0f, 0.0f, std::nextafter(2.0f, 3.0f)};
  for (float lo : tmins)
    for (float hi : tmaxs) rays.push_back(make_ray(o, d, lo, hi));  // includes tmin > tmax
  for_each_test<Arch>(soup, rays, "search intervals");
}

TEST_CASE_TEMPLATE("kernels on zero direction components match the oracle", Arch, VOLLEY_TEST_ARCHES) {
  if (skip_isa<Arch>()) return;
  const Soup soup = grid_patch();
  std::vector<Ray> rays;
  // Axis-aligned rays at integer and half-integer grid points (vertices, edges, centres),
  // both senses, signed zeros, and rays with one zero component grazing the grid.
  for (int i = -5; i <= 5; ++i)
    for (int j = -5; j <= 5; ++j) {
      const float x = 0.5f * float(i), y = 0.5f * float(j);
      rays.push_back(make_ray(V3(x, y, 3), V3(0, 0, -1)));
      rays.push_back(make_ray(V3(x, y, -3), V3(-0.0f, 0.0f, 2)));
      rays.push_back(make_ray(V3(x, -3, 1), V3(0, 1, -0.5f)));
      rays.push_back(make_ray(V3(-3, y, 1), V3(2, -0.0f, -0.25f)));
      rays.push_back(make_ray(V3(x, y, 0), V3(1, 0, 0)));  // in the plane
    }
  for_each_test<Arch>(soup, rays, "zero direction components");
}

TEST_CASE_TEMPLATE("degenerate triangles are never hit, as in the oracle", Arch, VOLLEY_TEST_ARCHES) {
  if (skip_isa<Arch>()) return;
  Soup soup;
  const V3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  soup.add(a, a, c, 1);                                          // repeated vertex
  soup.add(a, b, V3(2, 0, 0), 2);                                // collinear
  soup.add(a, b, V3(kNaN, 0, 0), 3);                             // NaN vertex
  soup.add(a, b, V3(0, kInf, 0), 4);                             // Inf vertex
  soup.add(V3(-1e30f, -1e30f, 0), V3(1e30f, -1e30f, 0), V3(0, 1e30f, 0), 5);  // cross product overflows
  soup.add(a, V3(1e-20f, 0, 0), V3(0, 1e-20f, 0), 6);           // cross product underflows to 0
  soup.add(a, a, a, 7);                                          // a point
  std::vector<Ray> rays;
  Generator g(7);
  for (int i = 0; i < 200; ++i) {
    const V3 target(g.uniform(-0.2f, 1.2f) * (i % 3 == 0 ? 1e-20f : 1.0f), g.uniform(-0.2f, 1.2f), 0.0f);
    const V3 org(g.uniform(-1, 1), g.uniform(-1, 1), g.uniform(0.5f, 2));
    rays.push_back(make_ray(org, target - org));
  }
  rays.push_back(make_ray(V3(0.5f, 0, 1), V3(0, 0, -1)));  // exactly through the collinear segment
  for_each_test<Arch>(soup, rays, "degenerate triangles");
  // And nothing at all is hit: every triangle here is degenerate for every test.
  for (const Ray& r : rays) {
    Hit got;
    const auto blocks = pack<Arch, TriangleTest::watertight>(soup);
    volley::simd::RayBlockKernels<Arch, TriangleTest::watertight>::intersect(
        volley::simd::prepare_ray(r), blocks.data(), static_cast<std::uint32_t>(blocks.size()), got);
    CHECK(got.prim == kInvalidPrim);
  }
}

TEST_CASE_TEMPLATE("rays aimed exactly at vertices, edges and diagonals match the oracle", Arch, VOLLEY_TEST_ARCHES) {
  if (skip_isa<Arch>()) return;
  for (float offset : {0.0f, 1000.0f, 100000.0f, 1e6f}) {
    const Soup soup = grid_box(3, offset);
    std::vector<Ray> rays;
    // From several inside points to every half-integer point of every face (vertices,
    // edge midpoints, diagonal midpoints, square centres).
    const V3 origins[] = {V3(1.5f, 1.5f, 1.5f) + offset, V3(0.25f, 2.75f, 1.125f) + offset, V3(2.9f, 0.1f, 0.7f) + offset};
    for (const V3& o : origins)
      for (int axis = 0; axis < 3; ++axis)
        for (float level : {0.0f, 3.0f})
          for (int i = 0; i <= 6; ++i)
            for (int j = 0; j <= 6; ++j) {
              float p[3];
              p[axis] = level + offset;
              p[(axis + 1) % 3] = 0.5f * float(i) + offset;
              p[(axis + 2) % 3] = 0.5f * float(j) + offset;
              rays.push_back(make_ray(o, V3(p[0], p[1], p[2]) - o));
            }
    for_each_test<Arch>(soup, rays, "exact targets, offset " + std::to_string(offset));
  }
}

TEST_CASE_TEMPLATE("random triangles and rays far from the origin match the oracle", Arch, VOLLEY_TEST_ARCHES) {
  // Issue 5: the plane test subtracts nearby coordinates (v0 - org) first; the kernels must
  // do it in the oracle's order to stay bit-identical where those differences matter.
  if (skip_isa<Arch>()) return;
  for (float offset : {1e3f, 1e5f, 1e6f}) {
    Generator g(11);
    Soup soup = g.triangles(3 * kLanes<Arch> + 1);
    std::vector<Ray> rays;
    for (int i = 0; i < 400; ++i) rays.push_back(g.aimed(soup, static_cast<std::size_t>(i) % soup.size()));
    for (float& c : soup.xyz) c += offset;
    for (Ray& r : rays)
      for (float& c : r.org) c += offset;
    for_each_test<Arch>(soup, rays, "random, offset " + std::to_string(offset));
  }
}

TEST_CASE_TEMPLATE("origin on the triangle with tmin = 0 behaves as the oracle", Arch, VOLLEY_TEST_ARCHES) {
  if (skip_isa<Arch>()) return;
  const Soup soup = grid_patch();
  std::vector<Ray> rays;
  Generator g(9);
  for (int i = 0; i < 100; ++i) {
    const V3 o(g.uniform(-2, 2), g.uniform(-2, 2), 0.0f);
    rays.push_back(make_ray(o, V3(g.uniform(-1, 1), g.uniform(-1, 1), g.uniform(-1, 1)), 0.0f));
    rays.push_back(make_ray(o, V3(g.uniform(-1, 1), g.uniform(-1, 1), 0.0f), 0.0f));
  }
  for_each_test<Arch>(soup, rays, "origin on the surface");
}
