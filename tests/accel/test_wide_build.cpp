// Building the wide BVH (wide_build.cpp over bvh_build.cpp): the same nodes and blocks for
// any number of threads, and the memory and block fill of the default AVX-512 layout on the
// shared meshes (issue #4: at most 65 bytes per triangle).
#include <doctest/doctest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "accel/wide/wide_build.h"
#include "core/bvh.h"
#include "io/obj_loader.h"
#include "io/scene_desc.h"
#include "simd/isa/dispatch.h"
#include "volley/accel.h"

namespace {

using volley::TriangleTest;
using Block = volley::simd::BlockFor<TriangleTest::watertight, 16>;
using Node = volley::simd::WideNode<volley::simd::kWideN>;

struct WideBuild {
  volley::simd::AlignedVector<Node> nodes;
  volley::simd::AlignedVector<Block> blocks;
  std::uint32_t root = 0;
  volley::simd::WideStats stats;
};

// A soup of n small triangles along a curve (neighbours in input order are close, as in a mesh).
std::vector<float> curve_soup(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f);
  std::vector<float> xyz;
  for (std::size_t i = 0; i < n; ++i) {
    const float s = static_cast<float>(i) / static_cast<float>(n);
    const float c[3] = {std::sin(30.0f * s), 10.0f * s, std::cos(9.0f * s)};
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) xyz.push_back(c[a] + 0.01f * unit(rng));
  }
  return xyz;
}

// The binary BVH the wide build collapses, with the AVX-512 layout's options.
volley::core::Bvh binary_bvh(const std::vector<float>& xyz) {
  const std::size_t n = xyz.size() / 9;
  std::vector<volley::core::BBox> boxes(n);
  for (std::size_t i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k)
      boxes[i].extend(glm::vec3(xyz[9 * i + 3 * k], xyz[9 * i + 3 * k + 1], xyz[9 * i + 3 * k + 2]));
  volley::core::BvhBuildOptions opt;
  opt.max_leaf_size = 16;
  opt.intersection_cost = 0.15f;
  opt.leaf_block_width = 16;
  return volley::core::build_bvh(boxes, opt);
}

// The SAH cost (wide_bvh.h's WideStats::sah_cost) of the greedy collapse the optimal one
// replaced: open the interior child of largest area until N children or only leaves.
double greedy_collapse_sah(const volley::core::Bvh& bvh) {
  constexpr int N = volley::simd::kWideN;
  double node_area = 0.0, leaf_area = 0.0;
  std::vector<std::uint32_t> roots{0};
  while (!roots.empty()) {
    const std::uint32_t r = roots.back();
    roots.pop_back();
    node_area += bvh.nodes[r].box.half_area();
    std::vector<std::uint32_t> kids{bvh.nodes[r].first_or_child, bvh.nodes[r].first_or_child + 1};
    while (kids.size() < std::size_t{N}) {
      int best = -1;
      for (std::size_t k = 0; k < kids.size(); ++k)
        if (!bvh.nodes[kids[k]].is_leaf() &&
            (best < 0 || bvh.nodes[kids[k]].box.half_area() > bvh.nodes[kids[std::size_t(best)]].box.half_area()))
          best = int(k);
      if (best < 0) break;
      const std::uint32_t first = bvh.nodes[kids[std::size_t(best)]].first_or_child;
      kids[std::size_t(best)] = first;
      kids.push_back(first + 1);
    }
    for (const std::uint32_t k : kids) {
      const volley::core::BvhNode& c = bvh.nodes[k];
      if (c.box.empty()) continue;
      if (c.is_leaf())
        leaf_area += double(c.box.half_area()) * c.count;
      else
        roots.push_back(k);
    }
  }
  return (node_area + leaf_area) / bvh.nodes[0].box.half_area();
}

WideBuild build(const std::vector<float>& xyz, int threads) {
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  const std::size_t n = xyz.size() / 9;
  std::vector<volley::core::BBox> boxes(n);
  std::vector<std::uint32_t> ids(n);
  for (std::size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k)
      boxes[i].extend(glm::vec3(xyz[9 * i + 3 * k], xyz[9 * i + 3 * k + 1], xyz[9 * i + 3 * k + 2]));
    ids[i] = static_cast<std::uint32_t>(i);
  }
  volley::core::BvhBuildOptions opt;
  opt.max_leaf_size = 16;
  opt.intersection_cost = 0.15f;
  opt.leaf_block_width = 16;
  const volley::core::Bvh bvh = volley::core::build_bvh(boxes, opt);
  WideBuild out;
  out.stats = volley::accel::build_wide<TriangleTest::watertight, 16>(bvh, xyz.data(), ids.data(), out.nodes,
                                                                      out.blocks, out.root);
  return out;
}

}  // namespace

TEST_CASE("wide build: the same nodes and blocks for 1 and 2 threads") {
  const std::vector<float> xyz = curve_soup(100000, 5);
  const WideBuild one = build(xyz, 1);
  const WideBuild two = build(xyz, 2);
  CHECK(one.root == two.root);
  REQUIRE(one.nodes.size() == two.nodes.size());
  REQUIRE(one.blocks.size() == two.blocks.size());
  // Field by field: the nodes' alignment padding is never written.
  std::size_t differing_nodes = 0;
  for (std::size_t i = 0; i < one.nodes.size(); ++i) {
    differing_nodes += std::memcmp(one.nodes[i].bounds, two.nodes[i].bounds, sizeof(Node::bounds)) != 0 ||
                       std::memcmp(one.nodes[i].child, two.nodes[i].child, sizeof(Node::child)) != 0;
  }
  CHECK(differing_nodes == 0);
  CHECK(std::memcmp(one.blocks.data(), two.blocks.data(), one.blocks.size() * sizeof(Block)) == 0);
  CHECK(one.stats.triangles == xyz.size() / 9);
}

TEST_CASE("wide build: the AVX-512 layout stays within 65 bytes per triangle, blocks mostly full") {
  if (!volley::simd::cpu_has(volley::Isa::avx512)) {
    MESSAGE("skipped: this CPU lacks AVX-512");
    return;
  }
  const std::filesystem::path dir = VOLLEY_SHARED_SCENES;
  for (const char* name : {"stanford-bunny.obj", "sponza_dabrovic.obj", "conference.obj"}) {
    const std::filesystem::path file = dir / name;
    if (!std::filesystem::exists(file)) {
      MESSAGE("skipped: " << file.string() << " not found");
      continue;
    }
    const std::string scene = name;
    CAPTURE(scene);
    volley::io::SceneDesc desc;
    volley::io::load_obj(file, glm::mat4(1.0f), std::nullopt, desc);
    const auto& m = desc.mesh;
    volley::Accel accel;
    accel.add_triangles(&m.positions[0].x, m.positions.size(), m.indices.data(), m.triangle_count());
    accel.commit({TriangleTest::watertight, volley::Isa::avx512});
    const volley::AccelInfo info = accel.info();
    const double per_triangle = static_cast<double>(info.bytes) / static_cast<double>(info.triangles - info.degenerate);
    MESSAGE(scene, ": ", per_triangle, " bytes per stored triangle, block fill ", info.block_fill, ", ",
            info.mean_children, " children per node");
    CHECK(per_triangle <= 65.0);
    CHECK(info.block_fill >= 0.7);
  }
}

TEST_CASE("wide build: the SAH-optimal collapse is never worse than the greedy one, and keeps every triangle") {
  for (const std::size_t n : {std::size_t{40}, std::size_t{1000}, std::size_t{30000}}) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      CAPTURE(n);
      CAPTURE(seed);
      const std::vector<float> xyz = curve_soup(n, seed);
      const WideBuild wide = build(xyz, 1);
      const double greedy = greedy_collapse_sah(binary_bvh(xyz));
      CHECK(wide.stats.triangles == n);
      CHECK(wide.stats.sah_cost <= greedy * (1.0 + 1e-12));
      CHECK(wide.stats.mean_children <= double(volley::simd::kWideN));
      if (n == 30000)
        MESSAGE("SAH cost ", wide.stats.sah_cost, " (greedy ", greedy, "), ", wide.stats.nodes, " nodes, ",
                wide.stats.mean_children, " children each");
    }
  }
}
