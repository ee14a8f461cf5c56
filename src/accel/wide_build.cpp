// Collapse of the binary BVH into the wide BVH, and leaf packing (wide_build.h).
#include "accel/wide_build.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <utility>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/large_alloc.h"
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

// The SAH-optimal collapse of Ylitie, Karras and Laine, "Efficient incoherent ray traversal
// on GPUs through compressed wide BVHs" (HPG 2017), with the binary leaves kept as they
// are: a wide node for binary node n gets the forest of at most N subtrees below n whose
// own wide nodes have the least total area. Leaves are fixed, so their cost is the same in
// every collapse and the SAH cost of the wide BVH is sum A(wide node) + the leaves' term.
// Dynamic programming over the binary tree, children before parents:
//   forest(n, 1) = A(n) + split(n, N) for interior n (n becomes a wide node), 0 for a leaf;
//   forest(n, i) = min(forest(n, 1), split(n, i)), i = 2 .. N (n opened into i slots);
//   split(n, i)  = min over j of forest(left, j) + forest(right, i - j).
// A child with an empty box (the builder's subtree of degenerate triangles, which no ray can
// hit) takes no slot and costs nothing.
class CollapsePlan {
 public:
  explicit CollapsePlan(const core::Bvh& bvh)
      : bvh_(bvh),
        cost_(bvh.nodes.size()),
        choice_(bvh.nodes.size()),
        split_(bvh.nodes.size()) {
    // Children before parents. build_bvh lays a node's children out after it (depth first),
    // so the reverse of the array order is one; any other layout takes the post order.
    bool children_after = true;
    for (std::size_t n = 0; n < bvh.nodes.size(); ++n)
      if (!bvh.nodes[n].is_leaf() && bvh.nodes[n].first_or_child <= n) children_after = false;
    if (children_after) {
      for (std::size_t n = bvh.nodes.size(); n-- > 0;) solve(static_cast<std::uint32_t>(n));
      return;
    }
    // Post order with an explicit stack (no recursion: a binary BVH may be 64 deep).
    std::vector<std::pair<std::uint32_t, bool>> stack{{0u, false}};
    while (!stack.empty()) {
      const auto [n, expanded] = stack.back();
      stack.pop_back();
      const core::BvhNode& node = bvh.nodes[n];
      if (!node.is_leaf() && !expanded) {
        stack.push_back({n, true});
        stack.push_back({node.first_or_child, false});
        stack.push_back({node.first_or_child + 1, false});
        continue;
      }
      solve(n);
    }
  }

  /// The binary nodes that become the children of the wide node for interior node n, in
  /// binary-tree order (left subtree first). Empty boxes left out.
  void children(std::uint32_t n, std::vector<std::uint32_t>& out) const { collect_split(n, N, out); }

 private:
  // cost_[n][i - 1] = forest(n, i); choice_[n][i - 1] (i >= 2): 0 = n as one slot, 1 = opened;
  // split_[n][i - 1] = the left child's slots in split(n, i) (the right child gets the rest).
  void solve(std::uint32_t n) {
    const core::BvhNode& node = bvh_.nodes[n];
    auto& cost = cost_[n];
    auto& choice = choice_[n];
    if (node.is_leaf()) {
      cost.fill(0.0);
      choice.fill(0);
      return;
    }
    const std::uint32_t l = node.first_or_child, r = l + 1;
    const bool lempty = bvh_.nodes[l].box.empty(), rempty = bvh_.nodes[r].box.empty();
    // split(n, i) for i = 1 .. N, with the left child's slot count behind it.
    std::array<double, N> split;
    std::array<std::uint8_t, N> split_left;
    for (int i = 1; i <= N; ++i) {
      double best = kInfD;
      int best_j = 0;
      if (lempty || rempty) {
        // An empty child takes no slot: all i go to the other (j = i: the left child, j = 0:
        // the right one; two empty children cost nothing).
        if (lempty && rempty) {
          best = 0.0, best_j = 0;
        } else if (rempty) {
          best = cost_[l][i - 1], best_j = i;
        } else {
          best = cost_[r][i - 1], best_j = 0;
        }
      } else {
        for (int j = 1; j < i; ++j) {
          const double c = cost_[l][j - 1] + cost_[r][i - j - 1];
          if (c < best) best = c, best_j = j;
        }
      }
      split[i - 1] = best;
      split_left[i - 1] = static_cast<std::uint8_t>(best_j);
    }
    split_[n] = split_left;
    const double as_node = node.box.half_area() + split[N - 1];
    cost[0] = as_node;
    choice[0] = 0;
    for (int i = 2; i <= N; ++i) {
      if (split[i - 1] < as_node) {
        cost[i - 1] = split[i - 1];
        choice[i - 1] = 1;
      } else {
        cost[i - 1] = as_node;
        choice[i - 1] = 0;
      }
    }
  }

  // n's subtree as at most i slots.
  void collect(std::uint32_t n, int i, std::vector<std::uint32_t>& out) const {
    if (bvh_.nodes[n].box.empty()) return;
    if (bvh_.nodes[n].is_leaf() || i == 1 || choice_[n][i - 1] == 0) {
      out.push_back(n);
      return;
    }
    collect_split(n, i, out);
  }

  // n's two children as at most i slots.
  void collect_split(std::uint32_t n, int i, std::vector<std::uint32_t>& out) const {
    const std::uint32_t l = bvh_.nodes[n].first_or_child;
    const int j = split_[n][i - 1];
    if (j > 0) collect(l, j, out);
    if (i - j > 0) collect(l + 1, i - j, out);
  }

  static constexpr double kInfD = std::numeric_limits<double>::infinity();
  const core::Bvh& bvh_;
  // Uninitialised: solve() writes every entry a node's parent and collect() read.
  core::LargeArray<std::array<double, N>> cost_;
  core::LargeArray<std::array<std::uint8_t, N>> choice_;
  core::LargeArray<std::array<std::uint8_t, N>> split_;
};

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
  const CollapsePlan plan(bvh);
  root = ref::interior<N>(0);
  nodes.push_back(inert_node());
  std::vector<Pending> stack{{0, 0, 0}};
  std::vector<std::uint32_t> kids;
  while (!stack.empty()) {
    const Pending p = stack.back();
    stack.pop_back();
    node_area += bvh.nodes[p.binary].box.half_area();
    kids.clear();
    if (bvh.nodes[p.binary].is_leaf())  // only the root: a lone leaf
      kids.push_back(p.binary);
    else
      plan.children(p.binary, kids);
    // Child order: leaves first, then larger boxes first. Closest-hit traversal sorts the
    // children it meets by distance, but any hit takes them in this order, and a leaf can end
    // it at once while a larger box is likelier to hold an occluder: occluded1 +3-7% on
    // Sponza, conference and kitchen (bunny within noise; closest hit within noise).
    // A stable insertion sort by hand: std::stable_sort calls memmove for these <= N ids.
    auto before = [&](std::uint32_t x, std::uint32_t y) {
      const core::BvhNode &a = bvh.nodes[x], &b = bvh.nodes[y];
      if (a.is_leaf() != b.is_leaf()) return a.is_leaf();
      return a.box.half_area() > b.box.half_area();
    };
    for (std::size_t i = 1; i < kids.size(); ++i) {
      const std::uint32_t k = kids[i];
      std::size_t j = i;
      for (; j > 0 && before(k, kids[j - 1]); --j) kids[j] = kids[j - 1];
      kids[j] = k;
    }
    // Fill the node: boxes bit for bit, leaves referenced, interior children allocated
    // side by side and queued (the first child on top, so it is laid out next).
    simd::WideNode<N> node = inert_node();
    int used = 0;
    Pending queued[N];
    int nqueued = 0;
    for (const std::uint32_t kid : kids) {
      const core::BvhNode& c = bvh.nodes[kid];
      for (int a = 0; a < 3; ++a) {
        node.bounds[2 * a][used] = c.box.lo[a];
        node.bounds[2 * a + 1][used] = c.box.hi[a];
      }
      if (c.is_leaf()) {
        node.child[used] = leaf_ref(kid, p.depth + 1);
      } else {
        const std::size_t w = nodes.size();
        if (w >= ref::kMaxNodes<N>)
          throw std::length_error("wide BVH: more than " + std::to_string(ref::kMaxNodes<N>) + " nodes");
        nodes.push_back(inert_node());
        node.child[used] = ref::interior<N>(w);
        queued[nqueued++] = {kid, static_cast<std::uint32_t>(w), p.depth + 1};
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
            // memcpy of a constant size is inlined; std::copy_n's memmove was a call per triangle.
            std::memcpy(tri_xyz.data() + 9 * std::size_t{i}, xyz + 9 * std::size_t{prim}, 9 * sizeof(float));
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
