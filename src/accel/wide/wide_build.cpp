// Collapse of the binary BVH into the wide BVH, and leaf packing (wide_build.h).
#include "accel/wide/wide_build.h"

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

#include "accel/wide/collapse_plan.h"
#include "core/large_alloc.h"
#include "simd/triangle/block_build.h"

namespace volley::accel {
namespace {

constexpr int N = simd::kWideN;
constexpr float kInf = std::numeric_limits<float>::infinity();

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

// The layout of the wide BVH is the one a sequential depth-first walk of the plan makes:
// a node's interior children side by side, then the subtree of the first, of the second,
// ...; the leaves' blocks in the order the walk meets them (a node's leaf children when the
// node is written). The subtrees below the top kTopDepth wide levels are walked in
// parallel, each alone into its own arrays (local indices, local blocks); the few top nodes
// are then laid out around them and the subtrees copied into place with their references
// moved (a serial walk dominated many-thread builds: perf/reports/build.md).
constexpr std::size_t kTopDepth = 3;

// The statistics a walk gathers, summed in a fixed order (the same for any number of
// threads).
struct WalkStats {
  double node_area = 0.0, leaf_area_tris = 0.0, leaf_area_blocks = 0.0;
  std::uint64_t children = 0, triangles = 0;
  std::size_t depth = 0;
  void add(const WalkStats& o) {
    node_area += o.node_area, leaf_area_tris += o.leaf_area_tris, leaf_area_blocks += o.leaf_area_blocks;
    children += o.children, triangles += o.triangles;
    depth = std::max(depth, o.depth);
  }
};

// A wide subtree walked alone: its root at nodes[0], interior references to local indices,
// leaf blocks numbered from 0.
struct LocalTree {
  std::vector<simd::WideNode<N>> nodes;
  std::vector<LeafJob> leaves;
  std::size_t blocks = 0;
  WalkStats stats;
};

// A wide node of the top levels: its children in slot order, each interior one either a
// top node again or a subtree walked alone.
struct TopNode {
  Kids kids;
  std::unique_ptr<TopNode> top[N];
  std::unique_ptr<LocalTree> local[N];
};

template <int W>
class WideLayout {
 public:
  WideLayout(const core::Bvh& bvh, const CollapsePlan& plan) : bvh_(bvh), plan_(plan) {}

  // Collapses the whole tree; fills nodes, leaves and the block count.
  void run(simd::AlignedVector<simd::WideNode<N>>& nodes, std::vector<LeafJob>& leaves) {
    namespace ref = simd::wide_ref;
    TopNode root;
    std::vector<std::pair<std::uint32_t, std::unique_ptr<LocalTree>*>> jobs;
    plan_top(root, 0, 0, jobs);
    tbb::parallel_for(std::size_t{0}, jobs.size(), [&](std::size_t j) {
      *jobs[j].second = std::make_unique<LocalTree>(walk(jobs[j].first, kTopDepth));
    });
    // Sizes first (the limits are checked before anything is written), then the layout.
    std::size_t total_nodes = 1, total_blocks = 0, total_leaves = 0;
    count(root, total_nodes, total_blocks, total_leaves);
    if (total_nodes > ref::kMaxNodes<N>) throw_too_many_nodes();
    if (total_blocks > ref::kMaxBlocks) throw_too_many_blocks();
    nodes.resize(total_nodes);  // uninitialised: every node is written once below
    leaves.resize(total_leaves);
    std::size_t next_node = 1, next_block = 0, next_leaf = 0;
    std::vector<Splice> splices;
    stats_.node_area = bvh_.nodes[0].box.half_area();
    place(root, 0, 0, next_node, next_block, next_leaf, nodes.data(), leaves.data(), splices);
    tbb::parallel_for(std::size_t{0}, splices.size(),
                      [&](std::size_t k) { splice(splices[k], nodes.data(), leaves.data()); });
    blocks_ = total_blocks;
  }

  std::size_t blocks() const { return blocks_; }
  const WalkStats& stats() const { return stats_; }

 private:
  // Where a walked subtree goes: its root at `root`, its other nodes (local j >= 1) at
  // node_base + j - 1, its blocks and leaf jobs after block_base and leaf_base.
  struct Splice {
    const LocalTree* tree;
    std::size_t root, node_base, block_base, leaf_base;
  };

  [[noreturn]] static void throw_too_many_nodes() {
    throw std::length_error("wide BVH: more than " + std::to_string(simd::wide_ref::kMaxNodes<N>) + " nodes");
  }
  [[noreturn]] static void throw_too_many_blocks() {
    throw std::length_error("wide BVH: more than 2^27 triangle blocks");
  }

  static std::size_t leaf_blocks(const core::BvhNode& leaf) {
    const std::size_t count = simd::blocks_for<W>(leaf.count);
    if (count > simd::wide_ref::kMaxLeafBlocks)
      throw std::length_error("wide BVH: a leaf of " + std::to_string(leaf.count) + " triangles needs more than " +
                              std::to_string(simd::wide_ref::kMaxLeafBlocks) + " blocks");
    return count;
  }

  // The wide node of binary node n's children (a lone leaf root: itself), leaves first, then
  // larger boxes first. Closest-hit traversal sorts the children it meets by distance, but
  // any hit takes them in this order, and a leaf can end it at once while a larger box is
  // likelier to hold an occluder (perf/reports/traversal.md). A stable insertion sort.
  Kids ordered_kids(std::uint32_t n) const {
    Kids kids;
    if (bvh_.nodes[n].is_leaf())
      kids.id[kids.size++] = n;
    else
      plan_.children(n, kids);
    auto before = [&](std::uint32_t x, std::uint32_t y) {
      const core::BvhNode &a = bvh_.nodes[x], &b = bvh_.nodes[y];
      if (a.is_leaf() != b.is_leaf()) return a.is_leaf();
      return a.box.half_area() > b.box.half_area();
    };
    for (int i = 1; i < kids.size; ++i) {
      const std::uint32_t k = kids.id[i];
      int j = i;
      for (; j > 0 && before(k, kids.id[j - 1]); --j) kids.id[j] = kids.id[j - 1];
      kids.id[j] = k;
    }
    return kids;
  }

  // Fills `node` with the children's boxes and references: leaves get blocks from
  // next_block (relative to whatever base the caller adds later), interior child i (in slot
  // order) the reference interior(first_inner + i). Appends the leaf jobs, adds the node's
  // statistics.
  void fill(const Kids& kids, std::size_t depth, std::size_t first_inner, std::size_t& next_block,
            simd::WideNode<N>& node, std::vector<LeafJob>& leaves, WalkStats& stats) const {
    namespace ref = simd::wide_ref;
    node = inert_node();
    std::size_t inner = 0;
    stats.children += static_cast<std::uint64_t>(kids.size);
    for (int k = 0; k < kids.size; ++k) {
      const core::BvhNode& kid = bvh_.nodes[kids.id[k]];
      for (int a = 0; a < 3; ++a) {
        node.bounds[2 * a][k] = kid.box.lo[a];
        node.bounds[2 * a + 1][k] = kid.box.hi[a];
      }
      if (!kid.is_leaf()) {
        node.child[k] = ref::interior<N>(first_inner + inner++);
        continue;
      }
      const std::size_t blocks = leaf_blocks(kid);
      if (next_block + blocks > ref::kMaxBlocks) throw_too_many_blocks();
      node.child[k] = ref::leaf(next_block, static_cast<std::uint32_t>(blocks));
      leaves.push_back({kids.id[k], static_cast<std::uint32_t>(next_block)});
      next_block += blocks;
      const double area = kid.box.half_area();
      stats.leaf_area_tris += area * kid.count;
      stats.leaf_area_blocks += area * static_cast<double>(blocks);
      stats.triangles += kid.count;
      stats.depth = std::max(stats.depth, depth + 1);
    }
  }

  // The top levels: kids of each top node, and a walk job for every interior child at
  // depth kTopDepth.
  void plan_top(TopNode& t, std::uint32_t n, std::size_t depth,
                std::vector<std::pair<std::uint32_t, std::unique_ptr<LocalTree>*>>& jobs) {
    t.kids = ordered_kids(n);
    for (int k = 0; k < t.kids.size; ++k) {
      const std::uint32_t kid = t.kids.id[k];
      if (bvh_.nodes[kid].is_leaf()) continue;
      if (depth + 1 < kTopDepth) {
        t.top[k] = std::make_unique<TopNode>();
        plan_top(*t.top[k], kid, depth + 1, jobs);
      } else {
        jobs.push_back({kid, &t.local[k]});
      }
    }
  }

  void count(const TopNode& t, std::size_t& nodes, std::size_t& blocks, std::size_t& leaves) const {
    for (int k = 0; k < t.kids.size; ++k) {
      const core::BvhNode& kid = bvh_.nodes[t.kids.id[k]];
      if (kid.is_leaf()) {
        blocks += leaf_blocks(kid), leaves += 1;
      } else if (t.top[k]) {
        nodes += 1;
        count(*t.top[k], nodes, blocks, leaves);
      } else {
        nodes += t.local[k]->nodes.size(), blocks += t.local[k]->blocks, leaves += t.local[k]->leaves.size();
      }
    }
  }

  // The sequential walk's order: top node t at nodes[w], its interior children side by
  // side from next_node, then their subtrees in slot order.
  void place(const TopNode& t, std::size_t w, std::size_t depth, std::size_t& next_node, std::size_t& next_block,
             std::size_t& next_leaf, simd::WideNode<N>* nodes, LeafJob* leaves, std::vector<Splice>& splices) {
    const std::size_t first_inner = next_node;
    for (int k = 0; k < t.kids.size; ++k) next_node += bvh_.nodes[t.kids.id[k]].is_leaf() ? 0 : 1;
    std::vector<LeafJob> jobs;
    fill(t.kids, depth, first_inner, next_block, nodes[w], jobs, stats_);
    std::copy(jobs.begin(), jobs.end(), leaves + next_leaf);
    next_leaf += jobs.size();
    std::size_t inner = 0;
    for (int k = 0; k < t.kids.size; ++k) {
      if (bvh_.nodes[t.kids.id[k]].is_leaf()) continue;
      const std::size_t index = first_inner + inner++;
      if (t.top[k]) {
        stats_.node_area += bvh_.nodes[t.kids.id[k]].box.half_area();
        place(*t.top[k], index, depth + 1, next_node, next_block, next_leaf, nodes, leaves, splices);
        continue;
      }
      const LocalTree& local = *t.local[k];
      splices.push_back({&local, index, next_node, next_block, next_leaf});
      next_node += local.nodes.size() - 1, next_block += local.blocks, next_leaf += local.leaves.size();
      stats_.add(local.stats);
    }
  }

  // Copies a walked subtree into place, its references moved to the global indices.
  static void splice(const Splice& s, simd::WideNode<N>* nodes, LeafJob* leaves) {
    namespace ref = simd::wide_ref;
    const LocalTree& tree = *s.tree;
    for (std::size_t j = 0; j < tree.nodes.size(); ++j) {
      simd::WideNode<N> node = tree.nodes[j];
      for (int k = 0; k < N; ++k) {
        const std::uint32_t r = node.child[k];
        if (r == ref::kEmptyRef) continue;
        if (r & ref::kLeafBit)
          node.child[k] = r + static_cast<std::uint32_t>(s.block_base);  // fits: total blocks checked
        else
          node.child[k] = ref::interior<N>(s.node_base + r / sizeof(simd::WideNode<N>) - 1);
      }
      nodes[j == 0 ? s.root : s.node_base + j - 1] = node;
    }
    for (std::size_t i = 0; i < tree.leaves.size(); ++i)
      leaves[s.leaf_base + i] = {tree.leaves[i].binary,
                                 tree.leaves[i].first_block + static_cast<std::uint32_t>(s.block_base)};
  }

  // The sequential walk of the wide subtree of binary node n (at `depth`), alone.
  LocalTree walk(std::uint32_t n, std::size_t depth) const {
    // A wide node waiting for its children: the binary node it stands for, its index, depth.
    struct Pending {
      std::uint32_t binary;
      std::uint32_t wide;
      std::size_t depth;
    };
    LocalTree tree;
    tree.nodes.push_back(inert_node());
    std::vector<Pending> stack{{n, 0, depth}};
    while (!stack.empty()) {
      const Pending p = stack.back();
      stack.pop_back();
      tree.stats.node_area += bvh_.nodes[p.binary].box.half_area();
      const Kids kids = ordered_kids(p.binary);
      // Interior children allocated side by side and queued, the first on top (laid out next).
      const std::size_t first_inner = tree.nodes.size();
      Pending queued[N];
      int nqueued = 0;
      for (int k = 0; k < kids.size; ++k) {
        if (bvh_.nodes[kids.id[k]].is_leaf()) continue;
        const std::size_t w = tree.nodes.size();
        if (w >= simd::wide_ref::kMaxNodes<N>) throw_too_many_nodes();
        tree.nodes.push_back(inert_node());
        queued[nqueued++] = {kids.id[k], static_cast<std::uint32_t>(w), p.depth + 1};
      }
      simd::WideNode<N> node;
      fill(kids, p.depth, first_inner, tree.blocks, node, tree.leaves, tree.stats);
      tree.nodes[p.wide] = node;
      for (int q = nqueued - 1; q >= 0; --q) stack.push_back(queued[q]);
    }
    return tree;
  }

  const core::Bvh& bvh_;
  const CollapsePlan& plan_;
  std::size_t blocks_ = 0;
  WalkStats stats_;
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

  // A lone leaf root still gets a node (of one child, itself): its box is then tested, as
  // the oracle's binary BVH tests its root box, and both Accels cull the same rays (an
  // ill-conditioned Moller "hit" far outside the triangle's box is dropped by both).
  const CollapsePlan plan(bvh);
  WideLayout<W> layout(bvh, plan);
  std::vector<LeafJob> leaves;
  layout.run(nodes, leaves);
  root = ref::interior<N>(0);
  const WalkStats& walked = layout.stats();

  // Pack every leaf's triangles into its blocks, leaves in parallel (resize leaves the
  // blocks uninitialised; pack_blocks writes every byte).
  blocks.resize(layout.blocks());
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
  stats.triangles = walked.triangles;
  stats.depth = walked.depth;
  stats.nodes = nodes.size();
  stats.leaves = leaves.size();
  stats.blocks = blocks.size();
  stats.mean_children = double(walked.children) / double(nodes.size());
  if (root_area > 0.0) {
    stats.sah_cost = (walked.node_area + walked.leaf_area_tris) / root_area;
    stats.block_sah_cost = (walked.node_area + walked.leaf_area_blocks) / root_area;
  } else {
    stats.sah_cost = stats.block_sah_cost = std::numeric_limits<double>::quiet_NaN();
  }
  stats.bytes = nodes.size() * sizeof(simd::WideNode<N>) + blocks.size() * sizeof(simd::BlockFor<Test, W>);
  return stats;
}

#define VOLLEY_BUILD_WIDE(test, w)                                                                          \
  template simd::WideStats build_wide<TriangleTest::test, w>(                                                \
      const core::Bvh&, const float*, const std::uint32_t*, simd::AlignedVector<simd::WideNode<N>>&,         \
      simd::AlignedVector<simd::BlockFor<TriangleTest::test, w>>&, std::uint32_t&);
VOLLEY_WIDE_BLOCK_FORMS(VOLLEY_BUILD_WIDE)
#undef VOLLEY_BUILD_WIDE

}  // namespace volley::accel
