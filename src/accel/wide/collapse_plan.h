// The collapse plan of the wide BVH build (wide_build.cpp): which binary nodes become the
// children of each wide node.
#pragma once
#include <tbb/parallel_invoke.h>

#include <array>
#include <cstdint>
#include <limits>

#include "core/bvh.h"
#include "core/large_alloc.h"
#include "simd/wide/wide_bvh.h"

namespace volley::accel {

// Binary-tree levels whose two subtrees the collapse plan solves in parallel (2^8 tasks at
// most; below, one task solves its subtree alone).
constexpr int kParallelDepth = 8;

// The binary nodes that become one wide node's children (at most kWideN).
struct Kids {
  std::uint32_t id[simd::kWideN];
  int size = 0;
};

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
  static constexpr int N = simd::kWideN;

 public:
  explicit CollapsePlan(const core::Bvh& bvh)
      : bvh_(bvh),
        cost_(bvh.nodes.size()),
        choice_(bvh.nodes.size()),
        split_(bvh.nodes.size()) {
    solve_subtree(0, 0);
  }

  /// The binary nodes that become the children of the wide node for interior node n, in
  /// binary-tree order (left subtree first). Empty boxes left out.
  void children(std::uint32_t n, Kids& out) const { collect_split(n, N, out); }

 private:
  // Children before parents: n's subtree, post order, the two halves of the top levels in
  // parallel (recursion depth <= the tree's, < kBvhMaxDepth for build_bvh's trees).
  void solve_subtree(std::uint32_t n, int depth) {
    const core::BvhNode& node = bvh_.nodes[n];
    if (!node.is_leaf()) {
      const std::uint32_t l = node.first_or_child;
      if (depth < kParallelDepth) {
        tbb::parallel_invoke([&] { solve_subtree(l, depth + 1); }, [&] { solve_subtree(l + 1, depth + 1); });
      } else {
        solve_subtree(l, depth + 1);
        solve_subtree(l + 1, depth + 1);
      }
    }
    solve(n);
  }

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
  void collect(std::uint32_t n, int i, Kids& out) const {
    if (bvh_.nodes[n].box.empty()) return;
    if (bvh_.nodes[n].is_leaf() || i == 1 || choice_[n][i - 1] == 0) {
      out.id[out.size++] = n;
      return;
    }
    collect_split(n, i, out);
  }

  // n's two children as at most i slots.
  void collect_split(std::uint32_t n, int i, Kids& out) const {
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

}  // namespace volley::accel
