// Binned SAH BVH builder (Wald 2007). See bvh.h for the contract; the split decision is in
// bvh_splitter.h, the statistics in bvh_stats.cpp.
//
// The passes over a node's primitives (binning, partition, the first pass over the input
// and the median split's bounds) and the sweep over the bins use SSE2/SSE4.1 intrinsics,
// part of the x86-64-v2 baseline every volley object is compiled for: a box is two 4-lane
// registers (x, y, z and a 4th lane: 0, or a bin's count), extended with one minps and one
// maxps; the sweep prices the three axes in the lanes of one register. Each is written to
// evaluate the float operations of the scalar formulation it replaced (BBox, one axis at
// a time), so the tree is bit for bit the one those gave (perf/reports/build.md).
//
// Parallel build (oneTBB): a node of at least kTaskNode primitives is split by the
// top-level recursion, which builds its two children as parallel tasks (and bins the
// biggest nodes in parallel chunks, merged in a fixed order); a smaller node is built by
// a sequential SubtreeBuilder into a node array of its own, and the arrays are spliced
// into one depth-first layout at the end. Which path a node takes depends only on its
// primitive count, never on the number of threads, so the tree is the same for any.
#include <immintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_scan.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/bvh.h"
#include "build/bvh_bins.h"
#include "build/bvh_splitter.h"
#include "core/large_alloc.h"

namespace volley::core {
namespace {

// Item, Box4, BinGrid, Bins and their SSE helpers (bvh_bins.h).
using namespace bvh_build_detail;

// Nodes with at least this many primitives become parallel tasks; below it a subtree is
// built sequentially (big enough that a task's overhead is noise, small enough that a
// megatriangle scene makes hundreds of tasks).
constexpr std::uint32_t kTaskNode = 1u << 12;

}  // namespace

void check_build_options(const BvhBuildOptions& o, const char* builder) {
  auto fail = [builder](const std::string& what) { throw std::invalid_argument(std::string(builder) + ": " + what); };
  if (o.bins < 2 || o.bins > 256) fail("bins must be in [2, 256], got " + std::to_string(o.bins));
  if (o.max_leaf_size < 1) fail("max_leaf_size must be >= 1");
  if (o.min_leaf_size < 1 || o.min_leaf_size > o.max_leaf_size) fail("min_leaf_size must be in [1, max_leaf_size]");
  if (!(o.traversal_cost > 0.0f) || !(o.intersection_cost > 0.0f))
    fail("traversal_cost and intersection_cost must be > 0");
  if (o.leaf_block_width < 1 || o.leaf_block_width > 64)
    fail("leaf_block_width must be in [1, 64], got " + std::to_string(o.leaf_block_width));
  if (!(o.padding_cost >= 0.0f && o.padding_cost <= 1.0f)) fail("padding_cost must be in [0, 1]");
}

namespace {

// Builds the subtree of one task depth first into its own node array: nodes[0] is the
// task's node, child indices are local, leaves index the shared item array.
class SubtreeBuilder {
 public:
  SubtreeBuilder(const BvhBuildOptions& options, Item* items) : splitter_(options, items) {}

  // Callers hold an ExactSubnormals (Builder::build_top).
  std::vector<BvhNode> build(Task root, const BBox& box) {
    nodes_.reserve(2 * std::size_t{root.end - root.begin} - 1);
    nodes_.push_back({box, 0, 0});
    root.node = 0;
    // Iteratively: the task stack holds at most one pending sibling per level.
    tasks_.push_back(root);
    while (!tasks_.empty()) {
      const Task t = tasks_.back();
      tasks_.pop_back();
      Split s;
      if (!splitter_.split(t, nodes_[t.node].box, false, s)) {
        nodes_[t.node].first_or_child = t.begin;
        nodes_[t.node].count = t.end - t.begin;
        continue;
      }
      const std::uint32_t child = static_cast<std::uint32_t>(nodes_.size());
      nodes_[t.node].first_or_child = child;
      nodes_[t.node].count = 0;
      nodes_.push_back({s.lbox, 0, 0});
      nodes_.push_back({s.rbox, 0, 0});
      // Right first so that the left child is processed next (depth-first layout).
      tasks_.push_back({child + 1, s.mid, t.end, t.depth + 1, s.rcbox, t.spatial});
      tasks_.push_back({child, t.begin, s.mid, t.depth + 1, s.lcbox, t.spatial});
    }
    return std::move(nodes_);
  }

 private:
  Splitter splitter_;
  std::vector<BvhNode> nodes_;
  std::vector<Task> tasks_;
};

// A node of the parallel top levels: either split (left and right set) or the root of
// a subtree built sequentially (`subtree`, root first, local child indices).
struct TopNode {
  BBox box;
  std::unique_ptr<TopNode> left, right;
  std::vector<BvhNode> subtree;
};

class Builder {
 public:
  Builder(std::span<const BBox> boxes, const BvhBuildOptions& options)
      : opt_(options), n_(static_cast<std::uint32_t>(boxes.size())), items_(boxes.size()) {
    // Valid primitives (non-empty box, finite centroid, hence finite bounds) go to the
    // front in input order, the others to the back (written back to front, reversed below);
    // both sets are bounded. A parallel prefix scan over the counts: one pass on one thread,
    // on more a counting pass where oneTBB needs the prefix of a range it has not reached
    // (serial, this pass showed in many-thread builds). The bounds join with min / max that
    // keep the first of equal values (as BBox::extend): the same for any split.
    const Scan total = tbb::parallel_scan(
        tbb::blocked_range<std::uint32_t>(0, n_, kInputChunk), Scan{},
        [&](const tbb::blocked_range<std::uint32_t>& r, Scan sum, bool is_final) {
          const ExactSubnormals exact;
          for (std::uint32_t i = r.begin(); i < r.end(); ++i) {
            const Classified p = classify(boxes[i]);
            if (is_final) {
              Item& item = items_[p.valid ? sum.valid : n_ - 1 - sum.invalid];
              _mm_storeu_ps(&item.lo.x, p.lo);
              _mm_storeu_ps(&item.hi.x,
                            _mm_castsi128_ps(_mm_insert_epi32(_mm_castps_si128(p.hi), static_cast<int>(i), 3)));
            }
            if (p.valid) {
              ++sum.valid;
              sum.box.lo = _mm_min_ps(p.lo, sum.box.lo);
              sum.box.hi = _mm_max_ps(p.hi, sum.box.hi);
              sum.cbox.lo = _mm_min_ps(p.c, sum.cbox.lo);
              sum.cbox.hi = _mm_max_ps(p.c, sum.cbox.hi);
            } else {
              ++sum.invalid;
              sum.invalid_box.extend(boxes[i]);
            }
          }
          return sum;
        },
        [](const Scan& left, const Scan& right) {
          Scan s = left;
          s.valid += right.valid;
          s.invalid += right.invalid;
          s.box.lo = _mm_min_ps(right.box.lo, left.box.lo);
          s.box.hi = _mm_max_ps(right.box.hi, left.box.hi);
          s.cbox.lo = _mm_min_ps(right.cbox.lo, left.cbox.lo);
          s.cbox.hi = _mm_max_ps(right.cbox.hi, left.cbox.hi);
          s.invalid_box.extend(right.invalid_box);
          return s;
        });
    valid_box_ = total.box.to_bbox();
    valid_cbox_ = total.cbox.to_bbox();
    invalid_box_ = total.invalid_box;
    n_valid_ = total.valid;
    std::reverse(items_.get() + n_valid_, items_.get() + n_);
  }

  Bvh run() {
    TopNode root;
    root.box = valid_box_;
    root.box.extend(invalid_box_);
    if (n_valid_ == n_ || n_valid_ == 0) {
      build_top(root, {0, 0, n_, 0, valid_cbox_, n_valid_ == n_});
    } else {
      // Root = (valid subtree, invalid subtree).
      root.left = std::make_unique<TopNode>();
      root.right = std::make_unique<TopNode>();
      root.left->box = valid_box_;
      root.right->box = invalid_box_;
      tbb::parallel_invoke(
          [&] {
            build_top(*root.left, {0, 0, n_valid_, 1, valid_cbox_, true});
          },
          [&] {
            build_top(*root.right, {0, n_valid_, n_, 1, BBox{}, false});
          });
    }

    Bvh bvh;
    bvh.nodes.reserve(2 * std::size_t{n_} - 1);
    bvh.nodes.push_back({});
    std::vector<Splice> splices;
    place(root, 0, bvh.nodes, splices);
    tbb::parallel_for(std::size_t{0}, splices.size(), [&](std::size_t k) { splice(splices[k], bvh.nodes); });
    bvh.prim_index.resize(n_);
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n_, 1u << 14), [&](const auto& r) {
      for (std::uint32_t i = r.begin(); i < r.end(); ++i) bvh.prim_index[i] = items_[i].prim;
    });
    return bvh;
  }

 private:
  // A sequentially built subtree's place in the final array: its root at `root`, its
  // other nodes (local index j >= 1) at base + j - 1.
  struct Splice {
    const std::vector<BvhNode>* nodes;
    std::uint32_t root;
    std::uint32_t base;
  };

  // Recursion depth <= tree depth < kBvhMaxDepth.
  void build_top(TopNode& node, const Task& t) {
    const ExactSubnormals exact;
    const std::uint32_t count = t.end - t.begin;
    if (count < kTaskNode || !t.spatial) {
      node.subtree = SubtreeBuilder(opt_, items_.get()).build(t, node.box);
      return;
    }
    Split s;
    if (!Splitter(opt_, items_.get()).split(t, node.box, count >= kParallelBinning, s)) {
      node.subtree = {BvhNode{node.box, t.begin, count}};
      return;
    }
    node.left = std::make_unique<TopNode>();
    node.right = std::make_unique<TopNode>();
    node.left->box = s.lbox;
    node.right->box = s.rbox;
    tbb::parallel_invoke(
        [&] {
          build_top(*node.left, {0, t.begin, s.mid, t.depth + 1, s.lcbox, t.spatial});
        },
        [&] {
          build_top(*node.right, {0, s.mid, t.end, t.depth + 1, s.rcbox, t.spatial});
        });
  }

  // Lays out the top levels depth first as SubtreeBuilder would (a node's children as a
  // pair, then the left subtree, then the right) and reserves room for each subtree.
  static void place(const TopNode& node, std::uint32_t index, std::vector<BvhNode>& out, std::vector<Splice>& splices) {
    if (node.left) {
      const std::uint32_t child = static_cast<std::uint32_t>(out.size());
      out[index] = {node.box, child, 0};
      out.push_back({node.left->box, 0, 0});
      out.push_back({node.right->box, 0, 0});
      place(*node.left, child, out, splices);
      place(*node.right, child + 1, out, splices);
      return;
    }
    const std::uint32_t base = static_cast<std::uint32_t>(out.size());
    out.resize(out.size() + node.subtree.size() - 1);
    splices.push_back({&node.subtree, index, base});
  }

  static void splice(const Splice& s, std::vector<BvhNode>& out) {
    const std::vector<BvhNode>& sub = *s.nodes;
    auto to_global = [&](std::uint32_t j) { return j == 0 ? s.root : s.base + j - 1; };
    for (std::uint32_t j = 0; j < sub.size(); ++j) {
      BvhNode node = sub[j];
      if (!node.is_leaf()) node.first_or_child = to_global(node.first_or_child);
      out[to_global(j)] = node;
    }
  }

  // Input boxes per task of the constructor's scan.
  static constexpr std::uint32_t kInputChunk = 1u << 14;
  // The constructor's running sums: valid and invalid counts, their bounds.
  struct Scan {
    std::uint32_t valid = 0, invalid = 0;
    Box4 box, cbox;
    BBox invalid_box;
  };
  // An input box as an item's two lanes (lo, 0), (hi, -), its centroid, and whether it is
  // valid: !b.empty() (lo <= hi, false for NaN) and a finite centroid (|c| < inf).
  struct Classified {
    __m128 lo, hi, c;
    bool valid;
  };
  static Classified classify(const BBox& b) {
    // Two loads inside the 24-byte box: lo.x lo.y lo.z hi.x and lo.z hi.x hi.y hi.z.
    const __m128 lo = _mm_and_ps(_mm_loadu_ps(&b.lo.x), xyz_mask());
    const __m128 upper = _mm_loadu_ps(&b.lo.z);
    const __m128 hi = _mm_and_ps(_mm_shuffle_ps(upper, upper, _MM_SHUFFLE(0, 3, 2, 1)), xyz_mask());
    const __m128 c = center4(lo, hi);  // BBox::center()
    const __m128 ok =
        _mm_and_ps(_mm_cmple_ps(lo, hi), _mm_cmplt_ps(_mm_andnot_ps(_mm_set1_ps(-0.0f), c), _mm_set1_ps(kInf)));
    return {lo, hi, c, (_mm_movemask_ps(ok) & 7) == 7};
  }

  const BvhBuildOptions opt_;
  const std::uint32_t n_;
  LargeArray<Item> items_;  // uninitialised: every slot is written above
  std::uint32_t n_valid_ = 0;
  BBox valid_box_, valid_cbox_, invalid_box_;
};

}  // namespace

Bvh build_bvh(std::span<const BBox> prim_boxes, const BvhBuildOptions& options) {
  check_build_options(options, "build_bvh");
  if (prim_boxes.size() >= std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("build_bvh: more than 2^32 - 2 primitives");
  if (prim_boxes.empty()) return Bvh{};
  return Builder(prim_boxes, options).run();
}
}  // namespace volley::core
