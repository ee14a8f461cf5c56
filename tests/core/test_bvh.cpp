// The scalar BVH (bbox.h, bvh.h, bvh_build.cpp, bvh_traverse.h): structural invariants
// of the binned-SAH build, and closest-hit / any-hit traversal against brute force over
// every primitive, on random soups, axis-aligned grids with rays on slab planes
// (docs/accuracy.md stress item 4), degenerate inputs and the shared benchmark meshes.
// The boxes and the slab test alone: test_bbox.cpp.
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "bvh_test_util.h"
#include "common/slab_grid.h"
#include "core/bbox.h"
#include "core/bvh.h"
#include "core/bvh_traverse.h"
#include "core/geometry.h"
#include "core/triangle.h"
#include "volley/options.h"

using namespace bvh_test;

TEST_CASE("bvh: build invariants on random soups, for several build options") {
  std::mt19937 rng(1);
  for (std::size_t n : {1u, 2u, 3u, 9u, 1000u, 20000u}) {
    const Soup soup = random_soup(n, rng);
    const std::vector<BBox> boxes = soup.boxes();
    for (BvhBuildOptions opt : {BvhBuildOptions{}, BvhBuildOptions{2, 1, 1, 1, 1},
                                BvhBuildOptions{32, 4, 2, 1.0f, 2.0f}, BvhBuildOptions{8, 16, 4, 3.0f, 1.0f}}) {
      CAPTURE(n);
      CAPTURE(opt.bins);
      CAPTURE(opt.max_leaf_size);
      const Bvh bvh = volley::core::build_bvh(boxes, opt);
      check_structure(bvh, boxes, opt);
    }
  }
}

TEST_CASE("bvh: invalid build options are rejected") {
  const std::vector<BBox> boxes(4, BBox{glm::vec3(0), glm::vec3(1)});
  CHECK_THROWS_AS(volley::core::build_bvh(boxes, {1, 8, 1, 1, 1}), std::invalid_argument);
  CHECK_THROWS_AS(volley::core::build_bvh(boxes, {16, 0, 1, 1, 1}), std::invalid_argument);
  CHECK_THROWS_AS(volley::core::build_bvh(boxes, {16, 4, 5, 1, 1}), std::invalid_argument);
  CHECK_THROWS_AS(volley::core::build_bvh(boxes, {16, 4, 1, kNaN, 1}), std::invalid_argument);
}

TEST_CASE("bvh: closest and any hit equal brute force on random triangle soups") {
  std::mt19937 rng(2);
  struct Case {
    std::size_t tris, rays;
    BvhBuildOptions opt;
  };
  for (const Case& c : {Case{1000, 3000, {}}, Case{10000, 600, {}}, Case{10000, 300, {2, 1, 1, 1, 1}},
                        Case{10000, 300, {32, 16, 4, 1, 1}}, Case{50000, 200, {}}}) {
    CAPTURE(c.tris);
    CAPTURE(c.opt.max_leaf_size);
    const Soup soup = random_soup(c.tris, rng);
    const std::vector<BBox> boxes = soup.boxes();
    const Bvh bvh = volley::core::build_bvh(boxes, c.opt);
    check_structure(bvh, boxes, c.opt);
    const std::vector<Ray> rays = random_rays(bounds_of(boxes), c.rays, rng);
    // Traversal hands every primitive whose box the ray touches to the leaf callback,
    // also for rays aimed exactly at box edges and corners (where an unpadded slab
    // test skips boxes, see above).
    std::vector<Ray> edge_rays = rays;
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (std::size_t i = 0; i < c.rays; ++i) {
      const BBox& b = boxes[rng() % boxes.size()];
      glm::vec3 target;
      const int free_axis = static_cast<int>(rng() % 4);  // 3: a corner
      for (int a = 0; a < 3; ++a)
        target[a] = a == free_axis ? b.lo[a] + unit(rng) * (b.hi[a] - b.lo[a])
                                   : (rng() % 2 ? b.hi[a] : b.lo[a]);
      edge_rays.push_back({rays[i].org, 0, target - rays[i].org, kInf});
    }
    std::size_t touched = 0;
    CHECK(count_skipped_boxes(bvh, boxes, edge_rays, touched) == 0);
    const Agreement g = compare_with_brute_force(bvh, soup, rays);
    CHECK(g.hits > c.rays / 4);  // the generator really makes both
    CHECK(g.misses > c.rays / 20);
    CHECK(g.closest_wrong == 0);
    CHECK(g.any_wrong == 0);
  }
}

TEST_CASE("bvh: axis-aligned rays with origins on slab planes of flat boxes (stress item 4)") {
  // Rays in the slab planes of many leaf boxes, through shared edges and vertices.
  Soup soup;
  const std::vector<Ray> rays = volley::test::slab_plane_grid<Ray>(16, soup, [](glm::vec3 o, glm::vec3 d) {
    return Ray{o, 0, d, kInf};
  });
  const std::vector<BBox> boxes = soup.boxes();
  for (BvhBuildOptions opt : {BvhBuildOptions{}, BvhBuildOptions{16, 1, 1, 1, 1}}) {
    const Bvh bvh = volley::core::build_bvh(boxes, opt);
    check_structure(bvh, boxes, opt);
    std::size_t touched = 0;
    CHECK(count_skipped_boxes(bvh, boxes, rays, touched) == 0);
    CHECK(touched > rays.size());
    for (auto test : {volley::TriangleTest::plane, volley::TriangleTest::moller,
                      volley::TriangleTest::watertight}) {
      CAPTURE(volley::to_string(test));
      CAPTURE(opt.max_leaf_size);
      soup.test = test;
      const Agreement g = compare_with_brute_force(bvh, soup, rays);
      MESSAGE("grid, ", volley::to_string(test), ": ", g.rays, " rays, ", g.hits, " hits, ",
              g.tie_prims, " ties at equal t");
      CHECK(g.hits > g.rays / 2);
      CHECK(g.misses > 0);
      CHECK(g.closest_wrong == 0);
      CHECK(g.any_wrong == 0);
    }
  }
}

TEST_CASE("bvh: degenerate inputs build, stay within bounds and agree with brute force") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> pos(-1.0f, 1.0f);
  auto rand3 = [&] { return glm::vec3(pos(rng), pos(rng), pos(rng)); };

  SUBCASE("all identical triangles") {
    Soup soup;
    for (int i = 0; i < 5000; ++i) soup.add({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    const auto boxes = soup.boxes();
    const Bvh bvh = volley::core::build_bvh(boxes);
    check_structure(bvh, boxes, {});
    std::vector<Ray> rays;
    for (int i = 0; i < 50; ++i) rays.push_back({glm::vec3(0.3f, 0.2f, 1) + 0.1f * rand3(), 0, {0, 0, -1}, kInf});
    rays.push_back({{2, 2, 1}, 0, {0, 0, -1}, kInf});
    const Agreement g = compare_with_brute_force(bvh, soup, rays);
    CHECK(g.hits == 50);
    CHECK(g.closest_wrong == 0);
    CHECK(g.any_wrong == 0);
  }
  SUBCASE("zero-area triangles (repeated vertices, collinear, points) among regular ones") {
    Soup soup;
    for (int i = 0; i < 3000; ++i) {
      const glm::vec3 p = rand3(), q = rand3();
      switch (i % 4) {
        case 0: soup.add(p, p, q); break;                          // repeated vertex
        case 1: soup.add(p, 0.5f * p + 0.5f * q, q); break;        // collinear
        case 2: soup.add(p, p, p); break;                          // a point
        default: soup.add(p, p + 0.1f * rand3(), p + 0.1f * rand3()); break;
      }
    }
    check_random_rays(soup, rng);
  }
  SUBCASE("many coincident centroids (nested triangles of every size)") {
    Soup soup;
    for (int i = 0; i < 4000; ++i) {
      const float s = 0.001f + 0.001f * static_cast<float>(i % 997);
      const glm::vec3 a = s * rand3(), b = s * rand3();
      soup.add(a, b, -a - b);  // centroid exactly 0 up to rounding: boxes differ, centres coincide or nearly
    }
    for (int i = 0; i < 2000; ++i) {
      const glm::vec3 c = glm::vec3(0.5f, 0.5f, 0.5f);
      const float s = 0.01f * static_cast<float>(1 + i % 50);
      soup.add(c + glm::vec3(-s, -s, 0), c + glm::vec3(s, -s, 0), c + glm::vec3(0, s, 0) + glm::vec3(0, 0, 0.0f));
    }
    check_random_rays(soup, rng);
  }
  SUBCASE("NaN and Inf vertices (empty and infinite boxes) among regular triangles") {
    Soup soup = random_soup(2000, rng);
    for (int i = 0; i < 300; ++i) {
      const glm::vec3 p = rand3();
      switch (i % 5) {
        case 0: soup.add(glm::vec3(kNaN), glm::vec3(kNaN), glm::vec3(kNaN)); break;  // empty box
        case 1: soup.add(p, glm::vec3(kNaN, 0, 0), p + 0.1f); break;
        case 2: soup.add(p, glm::vec3(kInf, 0, 0), p + 0.1f); break;
        case 3: soup.add(glm::vec3(-kInf), glm::vec3(kInf), p); break;
        default: soup.add(p, p + glm::vec3(0.1f, 0, 0), glm::vec3(p.x, p.y, kNaN)); break;
      }
    }
    const auto boxes = soup.boxes();
    const Bvh bvh = volley::core::build_bvh(boxes);
    check_structure(bvh, boxes, {});
    BBox finite;
    for (std::size_t i = 0; i < 2000; ++i) finite.extend(boxes[i]);
    const std::vector<Ray> rays = random_rays(finite, 1000, rng);
    std::size_t touched = 0;
    CHECK(count_skipped_boxes(bvh, boxes, rays, touched) == 0);
    const Agreement g = compare_with_brute_force(bvh, soup, rays);
    CHECK(g.hits > 0);
    CHECK(g.closest_wrong == 0);
    CHECK(g.any_wrong == 0);
  }
  SUBCASE("coordinates near +-FLT_MAX (extents and areas overflow to inf)") {
    // Centroid extents of 6e38 overflow: such an axis cannot be binned, and its
    // (centroid - min) * 0 is NaN: it must still map to a valid bin.
    Soup soup;
    const float big = 3e38f;
    for (int i = 0; i < 2000; ++i) {
      const glm::vec3 p = big * rand3();
      const glm::vec3 q = glm::vec3(p.x, 0.5f * p.y, 0.25f * p.z);
      soup.add(q, q + glm::vec3(0, 0, 1e37f), q + glm::vec3(0, 1e37f, 0));
    }
    const auto boxes = soup.boxes();
    const Bvh bvh = volley::core::build_bvh(boxes);
    check_structure(bvh, boxes, {});
    std::vector<Ray> rays;
    for (int i = 0; i < 200; ++i) {
      const glm::vec3 q = soup.v[3 * (i * 7)] + glm::vec3(0, 1e36f, 1e36f);
      rays.push_back({glm::vec3(-big, q.y, q.z), 0, {1, 0, 0}, kInf});
    }
    // The triangle tests overflow at this scale (normals of 1e37-long edges), so the
    // traversal is checked against the boxes themselves.
    std::size_t touched = 0;
    CHECK(count_skipped_boxes(bvh, boxes, rays, touched) == 0);
    CHECK(touched >= rays.size());
    const Agreement g = compare_with_brute_force(bvh, soup, rays);
    CHECK(g.closest_wrong == 0);
    CHECK(g.any_wrong == 0);
  }
  SUBCASE("geometrically spaced boxes over the whole float range (depth guard)") {
    // Centroids 2^(k/8) from 2^-140 to 2^120: binned SAH keeps splitting off the top
    // bins, a chain far deeper than kBvhMaxDepth without the depth guard. (Below about
    // 2^-60 Moller's determinant underflows to 0, so those triangles are never hit.)
    Soup soup;
    for (int k = -8 * 140; k < 8 * 120; ++k) {
      const float x = std::exp2(static_cast<float>(k) / 8.0f);
      const glm::vec3 p(x, x, x);
      soup.add(p, p + glm::vec3(0.01f * x, 0, 0), p + glm::vec3(0, 0.01f * x, 0));
    }
    const auto boxes = soup.boxes();
    const Bvh bvh = volley::core::build_bvh(boxes);
    check_structure(bvh, boxes, {});
    MESSAGE("geometric spacing: depth ", volley::core::bvh_stats(bvh).depth);
    std::vector<Ray> rays;
    for (int k = -8 * 140 + 3; k < 8 * 120; k += 37) {
      const float x = std::exp2(static_cast<float>(k) / 8.0f);
      rays.push_back({{x * 1.001f, x * 1.001f, -1.0f}, 0, {0, 0, 1}, kInf});
    }
    const Agreement g = compare_with_brute_force(bvh, soup, rays);
    CHECK(g.hits > rays.size() / 3);
    CHECK(g.closest_wrong == 0);
    CHECK(g.any_wrong == 0);
  }
}

TEST_CASE("bvh: empty, single-primitive and non-finite rays") {
  const Soup one = [] {
    Soup s;
    s.add({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    return s;
  }();
  std::size_t calls = 0;
  auto count_calls = [&](std::uint32_t, float&) {
    ++calls;
    return true;
  };
  const Ray down{{0.25f, 0.25f, 1}, 0, {0, 0, -1}, kInf};

  const Bvh empty = volley::core::build_bvh({});
  CHECK(empty.nodes.empty());
  CHECK(!volley::core::traverse<false>(empty, down, count_calls));
  CHECK(calls == 0);
  CHECK(volley::core::bvh_stats(empty).nodes == 0);

  const Bvh bvh = volley::core::build_bvh(one.boxes());
  check_structure(bvh, one.boxes(), {});
  CHECK(bvh_closest(bvh, one, down).t == 1.0f);
  CHECK(volley::core::bvh_stats(bvh).sah_cost == 1.0);

  // Non-finite rays: no hit and no leaf call, whatever is NaN or infinite.
  std::vector<Ray> bad;
  for (float x : {kNaN, kInf, -kInf}) {
    bad.push_back({{x, 0.25f, 1}, 0, {0, 0, -1}, kInf});
    bad.push_back({{0.25f, 0.25f, x}, 0, {0, 0, -1}, kInf});
    bad.push_back({{0.25f, 0.25f, 1}, 0, {0, 0, x}, kInf});
    bad.push_back({{0.25f, 0.25f, 1}, 0, {x, 0, -1}, kInf});
  }
  bad.push_back({{0.25f, 0.25f, 1}, kNaN, {0, 0, -1}, kInf});
  bad.push_back({{0.25f, 0.25f, 1}, 0, {0, 0, -1}, kNaN});
  for (const Ray& r : bad) {
    CAPTURE(describe(r));
    calls = 0;
    CHECK(!volley::core::traverse<false>(bvh, r, count_calls));
    CHECK(!volley::core::traverse<true>(bvh, r, count_calls));
    CHECK(calls == 0);
  }
  // tmin > tmax, a zero direction, tmax at the hit: no hit, terminates.
  CHECK(!bvh_closest(bvh, one, {{0.25f, 0.25f, 1}, 2, {0, 0, -1}, 1}).hit);
  CHECK(!bvh_closest(bvh, one, {{0.25f, 0.25f, 0}, 0, {0, 0, 0}, kInf}).hit);
  CHECK(!bvh_closest(bvh, one, {{0.25f, 0.25f, 1}, 0, {0, 0, -1}, 1.0f}).hit);
  CHECK(bvh_closest(bvh, one, {{0.25f, 0.25f, 1}, 1.0f, {0, 0, -1}, 1.5f}).hit);
}

TEST_CASE("bvh: one million primitives, random and all identical, build without trouble") {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> pos(0.0f, 100.0f);
  std::uniform_real_distribution<float> size(0.0f, 0.2f);
  constexpr std::size_t n = 1000000;
  std::vector<BBox> boxes(n);
  for (BBox& b : boxes) {
    b.lo = glm::vec3(pos(rng), pos(rng), pos(rng));
    b.hi = b.lo + glm::vec3(size(rng), size(rng), size(rng));
  }
  auto t0 = std::chrono::steady_clock::now();
  const Bvh bvh = volley::core::build_bvh(boxes);
  const double secs = seconds_since(t0);
  const auto stats = volley::core::bvh_stats(bvh);
  MESSAGE("1M random boxes: build ", secs, " s = ", 1e-6 * n / secs, " M prims/s, SAH cost ",
          stats.sah_cost, ", depth ", stats.depth, ", mean leaf ", stats.mean_leaf_size);
  check_structure(bvh, boxes, {});

  const std::vector<BBox> same(n, BBox{glm::vec3(1, 2, 3), glm::vec3(2, 3, 4)});
  t0 = std::chrono::steady_clock::now();
  const Bvh flat = volley::core::build_bvh(same);
  MESSAGE("1M identical boxes: build ", seconds_since(t0), " s");
  check_structure(flat, same, {});
  std::size_t calls = 0;
  const Ray ray{{1.5f, 2.5f, 0}, 0, {0, 0, 1}, kInf};
  CHECK(!volley::core::traverse<false>(flat, ray, [&](std::uint32_t, float&) {
    ++calls;
    return false;
  }));
  CHECK(calls == n);  // every leaf visited, none skipped, the stack never overflows
}

TEST_CASE("bvh: shared meshes (bunny, teapot) against brute force") {
  for (const std::string name : {"stanford-bunny.obj", "teapot.obj"}) {
    const std::string path = VOLLEY_SHARED_SCENES "/" + name;
    Soup soup = read_obj(path);
    soup.test = volley::TriangleTest::watertight;
    if (soup.size() == 0) {
      MESSAGE("skipped: ", path, " not found");
      continue;
    }
    CAPTURE(name);
    const auto boxes = soup.boxes();
    const auto t0 = std::chrono::steady_clock::now();
    const Bvh bvh = volley::core::build_bvh(boxes);
    const double secs = seconds_since(t0);
    const auto stats = volley::core::bvh_stats(bvh);
    MESSAGE(name, ": ", soup.size(), " tris, build ", 1e3 * secs, " ms = ",
            1e-6 * soup.size() / secs, " M prims/s, SAH cost ", stats.sah_cost, ", depth ",
            stats.depth, ", ", stats.nodes, " nodes, mean leaf ", stats.mean_leaf_size);
    check_structure(bvh, boxes, {});

    // Rays aimed at random triangle centroids from outside (hits), from inside the
    // bounds in random directions, and random rays (misses).
    std::mt19937 rng(5);
    const BBox bounds = bounds_of(boxes);
    std::vector<Ray> rays = random_rays(bounds, 300, rng);
    std::uniform_int_distribution<std::uint32_t> pick(0, static_cast<std::uint32_t>(soup.size() - 1));
    std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
    for (int i = 0; i < 300; ++i) {
      const std::uint32_t p = pick(rng);
      const glm::vec3 target = (soup.v[3 * p] + soup.v[3 * p + 1] + soup.v[3 * p + 2]) / 3.0f;
      const glm::vec3 org = bounds.center() + 2.0f * glm::length(bounds.diagonal()) *
                                                  glm::normalize(glm::vec3(unit(rng), unit(rng), unit(rng)));
      rays.push_back({org, 0, target - org, kInf});
    }
    const Agreement g = compare_with_brute_force(bvh, soup, rays);
    MESSAGE(name, ": ", g.rays, " rays, ", g.hits, " hits, ", g.tie_prims, " ties at equal t");
    CHECK(g.hits > 300);
    CHECK(g.misses > 25);
    CHECK(g.closest_wrong == 0);
    CHECK(g.any_wrong == 0);
  }
}
