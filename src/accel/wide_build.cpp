// Collapse of the binary BVH into the wide BVH, and leaf packing (wide_build.h).
#include "accel/wide_build.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "simd/block_build.h"

namespace volley::accel {
namespace {

constexpr int N = simd::kWideN;
constexpr float kInf = std::numeric_limits<float>::infinity();

// A wide node waiting for its children: the binary node it stands for, its index, depth.
struct Pending {
  std::uint32_t binary;
  std::uint32_t wide;
  std::uint32_t depth;
};

// A leaf of the wide BVH: the binary leaf and its first block.
struct LeafJob {
  std::uint32_t binary;
  std::uint32_t first_block;
};

simd::WideNode<N> inert_node() {
  simd::WideNode<N> node;
  for (int j = 0; j < N; ++j) {
    for (int a = 0; a < 3; ++a) {
      node.bounds[2 * a][j] = kInf;
      node.bounds[2 * a + 1][j] = -kInf;
    }
    node.child[j] = simd::wide_ref::kEmptyRef;
  }
  return node;
}

}  // namespace

template <TriangleTest Test, int W>
simd::WideStats build_wide(const core::Bvh& bvh, const float* xyz, const std::uint32_t* ids,
                           simd::AlignedVector<simd::WideNode<N>>& nodes,
                           simd::AlignedVector<simd::BlockFor<Test, W>>& blocks, std::uint32_t& root) {
  namespace ref = simd::wide_ref;
  simd::WideStats stats;
  nodes.clear();
  blocks.clear();
  root = ref::kEmptyRef;
  if (bvh.nodes.empty() || bvh.nodes[0].box.empty()) return stats;

  std::vector<LeafJob> leaves;
  std::size_t total_blocks = 0;
  double node_area = 0.0, leaf_area_tris = 0.0, leaf_area_blocks = 0.0;
  std::size_t children = 0;
  // The reference of a binary leaf; its blocks follow those of the leaves met before.
  auto leaf_ref = [&](std::uint32_t b, std::size_t depth) {
    const core::BvhNode& leaf = bvh.nodes[b];
    const std::size_t count = simd::blocks_for<W>(leaf.count);
    if (count > ref::kMaxLeafBlocks)
      throw std::length_error("wide BVH: a leaf of " + std::to_string(leaf.count) + " triangles needs more than " +
                              std::to_string(ref::kMaxLeafBlocks) + " blocks");
    if (total_blocks + count > ref::kMaxBlocks) throw std::length_error("wide BVH: more than 2^27 triangle blocks");
    leaves.push_back({b, static_cast<std::uint32_t>(total_blocks)});
    const std::uint32_t r = ref::kLeafBit | (static_cast<std::uint32_t>(count) << ref::kCountShift) |
                            static_cast<std::uint32_t>(total_blocks);
    total_blocks += count;
    const double area = leaf.box.half_area();
    leaf_area_tris += area * leaf.count;
    leaf_area_blocks += area * static_cast<double>(count);
    stats.triangles += leaf.count;
    stats.depth = std::max(stats.depth, depth);
    return r;
  };

  // A lone leaf root still gets a node (of one child, itself): its box is then tested, as
  // the oracle's binary BVH tests its root box, and both Accels cull the same rays (an
  // ill-conditioned Moller "hit" far outside the triangle's box is dropped by both).
  root = 0;
  nodes.push_back(inert_node());
  std::vector<Pending> stack{{0, 0, 0}};
  while (!stack.empty()) {
    const Pending p = stack.back();
    stack.pop_back();
    node_area += bvh.nodes[p.binary].box.half_area();
    // Open the interior child of largest area until N children or only leaves.
    std::uint32_t kids[N];
    int n = 2;
    if (bvh.nodes[p.binary].is_leaf()) {  // only the root: a lone leaf
      kids[0] = p.binary;
      n = 1;
    } else {
      kids[0] = bvh.nodes[p.binary].first_or_child;
      kids[1] = kids[0] + 1;
    }
    while (n < N) {
      int best = -1;
      float best_area = -1.0f;
      for (int k = 0; k < n; ++k) {
        const core::BvhNode& c = bvh.nodes[kids[k]];
        if (c.is_leaf()) continue;
        const float area = c.box.half_area();
        if (area > best_area) {
          best_area = area;
          best = k;
        }
      }
      if (best < 0) break;
      const std::uint32_t opened = bvh.nodes[kids[best]].first_or_child;
      kids[best] = opened;
      kids[n++] = opened + 1;
    }
    // Fill the node: boxes bit for bit, leaves referenced, interior children allocated
    // side by side and queued (the first child on top, so it is laid out next).
    simd::WideNode<N> node = inert_node();
    int used = 0;
    Pending queued[N];
    int nqueued = 0;
    for (int k = 0; k < n; ++k) {
      const core::BvhNode& c = bvh.nodes[kids[k]];
      if (c.box.empty()) continue;
      for (int a = 0; a < 3; ++a) {
        node.bounds[2 * a][used] = c.box.lo[a];
        node.bounds[2 * a + 1][used] = c.box.hi[a];
      }
      if (c.is_leaf()) {
        node.child[used] = leaf_ref(kids[k], p.depth + 1);
      } else {
        const std::uint32_t w = static_cast<std::uint32_t>(nodes.size());
        if (w & ref::kLeafBit) throw std::length_error("wide BVH: more than 2^31 nodes");
        nodes.push_back(inert_node());
        node.child[used] = w;
        queued[nqueued++] = {kids[k], w, p.depth + 1};
      }
      ++used;
    }
    children += static_cast<std::size_t>(used);
    nodes[p.wide] = node;
    for (int q = nqueued - 1; q >= 0; --q) stack.push_back(queued[q]);
  }

  // Pack every leaf's triangles into its blocks, leaves in parallel.
  blocks.resize(total_blocks);
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, leaves.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
        std::vector<float> tri_xyz;
        std::vector<std::uint32_t> tri_ids;
        for (std::size_t l = r.begin(); l < r.end(); ++l) {
          const core::BvhNode& leaf = bvh.nodes[leaves[l].binary];
          tri_xyz.resize(9 * std::size_t{leaf.count});
          tri_ids.resize(leaf.count);
          for (std::uint32_t i = 0; i < leaf.count; ++i) {
            const std::uint32_t prim = bvh.prim_index[leaf.first_or_child + i];
            std::copy_n(xyz + 9 * std::size_t{prim}, 9, tri_xyz.data() + 9 * std::size_t{i});
            tri_ids[i] = ids[prim];
          }
          simd::pack_blocks<Test, W>(tri_xyz.data(), tri_ids.data(), leaf.count, blocks.data() + leaves[l].first_block);
        }
      });

  const double root_area = bvh.nodes[0].box.half_area();
  stats.nodes = nodes.size();
  stats.leaves = leaves.size();
  stats.blocks = total_blocks;
  stats.mean_children = nodes.empty() ? 0.0 : double(children) / double(nodes.size());
  if (root_area > 0.0) {
    stats.sah_cost = (node_area + leaf_area_tris) / root_area;
    stats.block_sah_cost = (node_area + leaf_area_blocks) / root_area;
  } else {
    stats.sah_cost = stats.block_sah_cost = std::numeric_limits<double>::quiet_NaN();
  }
  stats.bytes = nodes.size() * sizeof(simd::WideNode<N>) + blocks.size() * sizeof(simd::BlockFor<Test, W>);
  return stats;
}

// Every test at every block width (W = 4, 8, 16: SSE4.2, AVX2, AVX-512 lanes).
template simd::WideStats build_wide<TriangleTest::moller, 4>(
    const core::Bvh&, const float*, const std::uint32_t*, simd::AlignedVector<simd::WideNode<N>>&,
    simd::AlignedVector<simd::BlockFor<TriangleTest::moller, 4>>&, std::uint32_t&);
template simd::WideStats build_wide<TriangleTest::moller, 8>(
    const core::Bvh&, const float*, const std::uint32_t*, simd::AlignedVector<simd::WideNode<N>>&,
    simd::AlignedVector<simd::BlockFor<TriangleTest::moller, 8>>&, std::uint32_t&);
template simd::WideStats build_wide<TriangleTest::moller, 16>(
    const core::Bvh&, const float*, const std::uint32_t*, simd::AlignedVector<simd::WideNode<N>>&,
    simd::AlignedVector<simd::BlockFor<TriangleTest::moller, 16>>&, std::uint32_t&);
template simd::WideStats build_wide<TriangleTest::plane, 4>(
    const core::Bvh&, const float*, const std::uint32_t*, simd::AlignedVector<simd::WideNode<N>>&,
    simd::AlignedVector<simd::BlockFor<TriangleTest::plane, 4>>&, std::uint32_t&);
template simd::WideStats build_wide<TriangleTest::plane, 8>(
    const core::Bvh&, const float*, const std::uint32_t*, simd::AlignedVector<simd::WideNode<N>>&,
    simd::AlignedVector<simd::BlockFor<TriangleTest::plane, 8>>&, std::uint32_t&);
template simd::WideStats build_wide<TriangleTest::plane, 16>(
    const core::Bvh&, const float*, const std::uint32_t*, simd::AlignedVector<simd::WideNode<N>>&,
    simd::AlignedVector<simd::BlockFor<TriangleTest::plane, 16>>&, std::uint32_t&);
template simd::WideStats build_wide<TriangleTest::watertight, 4>(
    const core::Bvh&, const float*, const std::uint32_t*, simd::AlignedVector<simd::WideNode<N>>&,
    simd::AlignedVector<simd::BlockFor<TriangleTest::watertight, 4>>&, std::uint32_t&);
template simd::WideStats build_wide<TriangleTest::watertight, 8>(
    const core::Bvh&, const float*, const std::uint32_t*, simd::AlignedVector<simd::WideNode<N>>&,
    simd::AlignedVector<simd::BlockFor<TriangleTest::watertight, 8>>&, std::uint32_t&);
template simd::WideStats build_wide<TriangleTest::watertight, 16>(
    const core::Bvh&, const float*, const std::uint32_t*, simd::AlignedVector<simd::WideNode<N>>&,
    simd::AlignedVector<simd::BlockFor<TriangleTest::watertight, 16>>&, std::uint32_t&);

}  // namespace volley::accel
