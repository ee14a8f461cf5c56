// The spatial-split builder (bvh_spatial.cpp): the boxes of a triangle's references cover
// the whole triangle, every node's box holds its children's, the budget of added
// references holds, left-out triangles stay out, the tree is the same for any number of
// threads, and on long triangles its SAH cost is lower than the binned builder's.
#include <doctest/doctest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include "core/bbox.h"
#include "core/bvh.h"

namespace {

using volley::core::BBox;
using volley::core::Bvh;
using volley::core::BvhBuildOptions;
using volley::core::BvhNode;

struct Triangles {
  std::vector<glm::vec3> v;  // 3 per triangle
  std::vector<BBox> boxes;   // empty: left out
};

// Long slivers and wide quads over [-10, 10]^3 among `small` small triangles; every
// `skip`-th triangle is left out (an empty box), as the Accel leaves out degenerate ones.
Triangles slivers(int small, int skip, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-10.0f, 10.0f), jitter(-0.5f, 0.5f);
  Triangles t;
  auto add = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    t.v.insert(t.v.end(), {a, b, c});
    BBox box;
    if (skip == 0 || t.boxes.size() % static_cast<std::size_t>(skip) != 1) {
      box.extend(a), box.extend(b), box.extend(c);
    }
    t.boxes.push_back(box);
  };
  for (int i = 0; i < 300; ++i) {
    const glm::vec3 a(pos(rng), pos(rng), pos(rng)), b(pos(rng), pos(rng), pos(rng));
    add(a, b, 0.5f * (a + b) + glm::vec3(jitter(rng), jitter(rng), jitter(rng)));
  }
  add({-10, -10, -3}, {10, -10, -3}, {10, 10, -3});
  add({-10, -10, -3}, {10, 10, -3}, {-10, 10, -3});
  for (int i = 0; i < small; ++i) {
    const glm::vec3 c(pos(rng), pos(rng), pos(rng));
    add(c + glm::vec3(jitter(rng), jitter(rng), jitter(rng)), c + glm::vec3(jitter(rng), jitter(rng), jitter(rng)),
        c + glm::vec3(jitter(rng), jitter(rng), jitter(rng)));
  }
  return t;
}

BvhBuildOptions wide_options() {
  BvhBuildOptions o;
  o.max_leaf_size = 16;
  o.intersection_cost = 0.15f;
  o.leaf_block_width = 8;
  o.padding_cost = 0.4f;
  return o;
}

Bvh build(const Triangles& t, int threads, double growth = 1.0) {
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  return volley::core::build_bvh_spatial(t.boxes, t.v.data(), wide_options(), growth);
}

// `box` grown by a few ulps on every side (a float sample of a triangle's point may lie an
// ulp or two off the exact triangle).
BBox widened(const BBox& box) {
  BBox w = box;
  for (int k = 0; k < 3; ++k) {
    const float pad = 4.0f * std::numeric_limits<float>::epsilon() * std::max(std::abs(box.lo[k]), std::abs(box.hi[k]));
    w.lo[k] -= pad, w.hi[k] += pad;
  }
  return w;
}

}  // namespace

TEST_CASE("bvh spatial: references cover their triangles, nodes hold their children, nothing left out is in") {
  const Triangles t = slivers(3000, 7, 3);
  const Bvh bvh = build(t, 2);
  REQUIRE(!bvh.nodes.empty());
  std::vector<std::vector<BBox>> leaf_boxes(t.boxes.size());
  std::size_t bad_nesting = 0;
  for (const BvhNode& n : bvh.nodes) {
    if (n.is_leaf()) {
      for (std::uint32_t k = 0; k < n.count; ++k) leaf_boxes[bvh.prim_index[n.first_or_child + k]].push_back(n.box);
      continue;
    }
    bad_nesting += !n.box.contains(bvh.nodes[n.first_or_child].box) || !n.box.contains(bvh.nodes[n.first_or_child + 1].box);
  }
  CHECK(bad_nesting == 0);
  std::size_t left_out_in = 0, missing = 0, uncovered = 0, cut = 0;
  for (std::size_t i = 0; i < t.boxes.size(); ++i) {
    if (t.boxes[i].empty()) {
      left_out_in += !leaf_boxes[i].empty();
      continue;
    }
    missing += leaf_boxes[i].empty();
    cut += leaf_boxes[i].size() > 1;
    // Points of the triangle on a barycentric grid, vertices and edges included.
    const glm::vec3 *v = &t.v[3 * i];
    for (int a = 0; a <= 8; ++a)
      for (int b = 0; a + b <= 8; ++b) {
        const float u = float(a) / 8.0f, w = float(b) / 8.0f;
        const glm::vec3 p = (1.0f - u - w) * v[0] + u * v[1] + w * v[2];
        bool inside = false;
        for (const BBox& box : leaf_boxes[i]) inside = inside || widened(box).contains(p);
        uncovered += !inside;
      }
  }
  CHECK(left_out_in == 0);
  CHECK(missing == 0);
  CHECK(uncovered == 0);
  CHECK(cut > 50);  // the slivers were cut
}

TEST_CASE("bvh spatial: the same tree for 1 and 2 threads, within the budget, cheaper by SAH on long triangles") {
  const Triangles t = slivers(20000, 0, 5);  // nodes of thousands of references: parallel tasks
  const Bvh one = build(t, 1), two = build(t, 2);
  CHECK(one.prim_index == two.prim_index);
  REQUIRE(one.nodes.size() == two.nodes.size());
  CHECK(std::memcmp(one.nodes.data(), two.nodes.data(), one.nodes.size() * sizeof(BvhNode)) == 0);
  for (const double growth : {0.0, 0.1, 1.0}) {
    CAPTURE(growth);
    const Bvh b = build(t, 2, growth);
    CHECK(double(b.prim_index.size()) <= (1.0 + growth) * double(t.boxes.size()));
    if (growth == 0.0) CHECK(b.prim_index.size() == t.boxes.size());
  }
  const Bvh binned = volley::core::build_bvh(t.boxes, wide_options());
  const double spatial_sah = volley::core::bvh_stats(one, wide_options()).sah_cost;
  const double binned_sah = volley::core::bvh_stats(binned, wide_options()).sah_cost;
  MESSAGE("SAH cost: binned ", binned_sah, ", spatial splits ", spatial_sah);
  CHECK(spatial_sah < 0.9 * binned_sah);
}

TEST_CASE("bvh spatial: bad options and budgets are rejected, no triangles give an empty tree") {
  const Triangles t = slivers(10, 0, 7);
  BvhBuildOptions bad = wide_options();
  bad.bins = 1;
  CHECK_THROWS_AS(volley::core::build_bvh_spatial(t.boxes, t.v.data(), bad), std::invalid_argument);
  CHECK_THROWS_AS(volley::core::build_bvh_spatial(t.boxes, t.v.data(), wide_options(), -0.5), std::invalid_argument);
  CHECK_THROWS_AS(volley::core::build_bvh_spatial(t.boxes, t.v.data(), wide_options(), std::nan("")), std::invalid_argument);
  const std::vector<BBox> none(5);  // all left out
  CHECK(volley::core::build_bvh_spatial(none, t.v.data()).nodes.empty());
  CHECK(volley::core::build_bvh_spatial({}, nullptr).nodes.empty());
}

TEST_CASE("bvh spatial: extreme coordinates (huge, tiny, flat, at one point) build and stay covered") {
  Triangles t;
  auto add = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    t.v.insert(t.v.end(), {a, b, c});
    BBox box;
    box.extend(a), box.extend(b), box.extend(c);
    t.boxes.push_back(box);
  };
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  for (int i = 0; i < 400; ++i) {
    const float scale = i % 4 == 0 ? 1e37f : i % 4 == 1 ? 1e-36f : i % 4 == 2 ? 1.0f : 0.0f;
    const glm::vec3 a(unit(rng), unit(rng), unit(rng)), b(unit(rng), unit(rng), unit(rng));
    // Long slivers at every scale, flat in z for some, and all three vertices at one point for scale 0.
    add(scale * a, scale * b, scale * (0.5f * (a + b) + glm::vec3(0.01f * unit(rng), 0.01f * unit(rng), 0.0f)));
    add(scale * glm::vec3(a.x, a.y, 0), scale * glm::vec3(b.x, b.y, 0), scale * glm::vec3(a.x, b.y, 0));
  }
  const Bvh bvh = volley::core::build_bvh_spatial(t.boxes, t.v.data(), wide_options());
  REQUIRE(!bvh.nodes.empty());
  std::vector<std::vector<BBox>> leaf_boxes(t.boxes.size());
  for (const BvhNode& n : bvh.nodes)
    if (n.is_leaf())
      for (std::uint32_t k = 0; k < n.count; ++k) leaf_boxes[bvh.prim_index[n.first_or_child + k]].push_back(n.box);
  std::size_t uncovered = 0;
  for (std::size_t i = 0; i < t.boxes.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      bool inside = false;
      for (const BBox& box : leaf_boxes[i]) inside = inside || box.contains(t.v[3 * i + k]);
      uncovered += !inside;  // every vertex in one of its triangle's leaves, exactly
    }
  CHECK(uncovered == 0);
}
