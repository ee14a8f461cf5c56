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

#include "accel/wide_build.h"
#include "core/bvh.h"
#include "io/obj_loader.h"
#include "io/scene_desc.h"
#include "simd/dispatch.h"
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
