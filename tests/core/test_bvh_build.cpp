// The parallel BVH build (bvh_build.cpp): the same tree for any number of threads, and
// leaves sized to blocks (BvhBuildOptions::leaf_block_width).
#include <doctest/doctest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>
#include <xmmintrin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
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

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// n small boxes clustered along a few curves (so that neighbours in input order are close,
// as in a mesh), plus `invalid` boxes that are empty or non-finite, spread over the input.
std::vector<BBox> clustered_boxes(std::size_t n, std::size_t invalid, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::vector<BBox> boxes;
  boxes.reserve(n + invalid);
  for (std::size_t i = 0; i < n; ++i) {
    const float s = static_cast<float>(i) / static_cast<float>(n);
    const glm::vec3 c(std::sin(40.0f * s) + 0.05f * unit(rng), 20.0f * s + 0.05f * unit(rng),
                      std::cos(7.0f * s) + 0.05f * unit(rng));
    const glm::vec3 d(0.01f * unit(rng), 0.01f * unit(rng), 0.01f * unit(rng));
    boxes.push_back({c - d, c + d});
  }
  for (std::size_t i = 0; i < invalid; ++i) {
    const std::size_t at = rng() % (boxes.size() + 1);
    const BBox bad = i % 3 == 0   ? BBox{}
                     : i % 3 == 1 ? BBox{glm::vec3(kNaN), glm::vec3(1)}
                                  : BBox{glm::vec3(0), glm::vec3(kInf)};
    boxes.insert(boxes.begin() + static_cast<std::ptrdiff_t>(at), bad);
  }
  return boxes;
}

Bvh build_with_threads(const std::vector<BBox>& boxes, const BvhBuildOptions& opt, int threads) {
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  return volley::core::build_bvh(boxes, opt);
}

// Bit for bit: boxes (NaN and the sign of zero included), links, counts, prim order.
bool identical(const Bvh& a, const Bvh& b) {
  return a.nodes.size() == b.nodes.size() && a.prim_index == b.prim_index &&
         std::memcmp(a.nodes.data(), b.nodes.data(), a.nodes.size() * sizeof(BvhNode)) == 0;
}

// Stored primitives / block slots, leaves padded to whole blocks of w.
double block_fill(const Bvh& bvh, std::uint32_t w) {
  double prims = 0, slots = 0;
  for (const BvhNode& node : bvh.nodes) {
    if (!node.is_leaf()) continue;
    prims += node.count;
    slots += static_cast<double>((node.count + w - 1) / w * w);
  }
  return prims / slots;
}

BvhBuildOptions wide16_options(int block_width) {
  BvhBuildOptions o;
  o.max_leaf_size = 16;
  o.intersection_cost = 0.15f;
  o.leaf_block_width = block_width;
  return o;
}

}  // namespace

TEST_CASE("bvh build: the same tree for 1 and 2 threads") {
  // 200k primitives: nodes big enough for parallel binning (2^15) and tasks (2^12) on the
  // top levels, sequential subtrees below, and a subtree of invalid primitives.
  const std::vector<BBox> boxes = clustered_boxes(200000, 500, 7);
  for (const BvhBuildOptions& opt :
       {BvhBuildOptions{}, wide16_options(1), wide16_options(16), BvhBuildOptions{4, 4, 1, 1.0f, 1.0f, 4}}) {
    CAPTURE(opt.bins);
    CAPTURE(opt.leaf_block_width);
    const Bvh one = build_with_threads(boxes, opt, 1);
    const Bvh two = build_with_threads(boxes, opt, 2);
    CHECK(identical(one, two));
    CHECK(identical(one, build_with_threads(boxes, opt, 2)));  // and again: no run-to-run variation
    CHECK(one.prim_index.size() == boxes.size());
  }
}

TEST_CASE("bvh build: the same tree with flush-to-zero and denormals-are-zero set") {
  // A build on threads with DAZ once read every bin count as 0 (counts are subnormal
  // patterns in a float lane) and chose its planes blind. oneTBB runs tasks under the FP
  // settings captured when their arena was made (as Embree's were with DAZ on, in the test
  // that found this): made here with DAZ on this thread.
  const std::vector<BBox> boxes = clustered_boxes(100000, 200, 3);
  const BvhBuildOptions opt = wide16_options(8);
  for (int threads : {1, 2}) {
    CAPTURE(threads);
    const Bvh plain = build_with_threads(boxes, opt, threads);
    const unsigned csr = _mm_getcsr();
    _mm_setcsr(csr | 0x8040u);  // bit 15 FTZ, bit 6 DAZ
    Bvh daz;
    tbb::task_arena arena(threads);
    arena.execute([&] { daz = volley::core::build_bvh(boxes, opt); });
    _mm_setcsr(csr);
    CHECK(identical(plain, daz));
  }
}

TEST_CASE("bvh build: leaves sized to blocks fill them, within max_leaf_size") {
  const std::vector<BBox> boxes = clustered_boxes(50000, 0, 11);
  const Bvh plain = volley::core::build_bvh(boxes, wide16_options(1));
  const Bvh blocked = volley::core::build_bvh(boxes, wide16_options(16));
  const double fill_plain = block_fill(plain, 16);
  const double fill_blocked = block_fill(blocked, 16);
  MESSAGE("16-wide block fill: ", fill_plain, " by triangle count, ", fill_blocked, " with leaf_block_width 16");
  CHECK(fill_blocked > fill_plain + 0.1);
  CHECK(fill_blocked > 0.7);
  std::vector<int> seen(boxes.size(), 0);
  for (const BvhNode& node : blocked.nodes) {
    if (!node.is_leaf()) continue;
    CHECK(node.count <= 16u);
    for (std::uint32_t k = node.first_or_child; k < node.first_or_child + node.count; ++k) {
      ++seen[blocked.prim_index[k]];
      CHECK(node.box.contains(boxes[blocked.prim_index[k]]));
    }
  }
  CHECK(std::count(seen.begin(), seen.end(), 1) == static_cast<std::ptrdiff_t>(boxes.size()));
  // Width 1 is the plain SAH.
  const Bvh width_one = volley::core::build_bvh(boxes, wide16_options(1));
  CHECK(identical(plain, width_one));
}

TEST_CASE("bvh build: leaf_block_width outside [1, 64] is rejected") {
  const std::vector<BBox> boxes(4, BBox{glm::vec3(0), glm::vec3(1)});
  CHECK_THROWS_AS(volley::core::build_bvh(boxes, {16, 8, 1, 1, 1, 0}), std::invalid_argument);
  CHECK_THROWS_AS(volley::core::build_bvh(boxes, {16, 8, 1, 1, 1, 65}), std::invalid_argument);
  CHECK_NOTHROW(volley::core::build_bvh(boxes, {16, 8, 1, 1, 1, 64}));
}
