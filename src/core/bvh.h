// Scalar oracle: the binary BVH, its binned-SAH builder and its statistics. The BVH
// never knows the primitive type: it is built over primitive boxes and traversed with
// a leaf callback (bvh_traverse.h), as in madmann91/bvh.
#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "core/bbox.h"
#include "core/kernel_constants.h"

namespace volley::core {

/// One BVH node. count == 0: interior node whose children are
/// nodes[first_or_child] and nodes[first_or_child + 1] (always allocated as a pair);
/// count > 0: leaf over prim_index[first_or_child .. first_or_child + count).
struct BvhNode {
  BBox box;                      // 24 bytes: bounds of every primitive below the node
  std::uint32_t first_or_child;  //  4 bytes: first child (interior) or first prim slot (leaf)
  std::uint32_t count;           //  4 bytes: 0 for interior, primitive count for a leaf
  bool is_leaf() const { return count != 0; }
};
static_assert(sizeof(BvhNode) == 32, "BvhNode is 32 bytes (two per cache line)");

/// A binary BVH over primitives numbered 0 .. n-1. nodes[0] is the root; `nodes` is
/// empty when the BVH was built over zero primitives. prim_index lists every primitive
/// exactly once, grouped by leaf. Immutable after build: any number of threads may
/// traverse it concurrently.
struct Bvh {
  std::vector<BvhNode> nodes;             // 32 bytes per node, 2n-1 nodes at most
  std::vector<std::uint32_t> prim_index;  //  4 bytes per primitive
};

/// Parameters of the binned SAH build (Wald 2007). Costs are relative: the SAH cost of
/// a node is traversal_cost + intersection_cost * (A_left N_left + A_right N_right) / A.
struct BvhBuildOptions {
  int bins = 16;                   ///< centroid bins per axis, in [2, 256]
  int max_leaf_size = 8;           ///< a node with more primitives is always split, >= 1
  int min_leaf_size = 1;           ///< a node with this many or fewer is never split, in [1, max_leaf_size]
  float traversal_cost = 1.0f;     ///< cost of visiting one interior node, > 0
  float intersection_cost = 1.0f;  ///< cost of one primitive test, > 0
  /// Primitives are stored in blocks of this many (the wide BVH's triangle blocks), in [1, 64].
  /// The SAH prices a leaf of N primitives as N tests plus padding_cost per empty slot of its
  /// last block (ceil(N / w) * w - N), so that leaves fill their blocks.
  int leaf_block_width = 1;
  float padding_cost = 1.0f;  ///< cost of an empty block slot, in primitive tests, in [0, 1]

  /// Test cost of n primitives in leaf blocks of leaf_block_width, in primitive tests: n plus
  /// padding_cost per empty slot of the last block.
  float leaf_slots(std::size_t n) const {
    const auto w = static_cast<std::size_t>(leaf_block_width);
    const std::size_t padded = (n + w - 1) / w * w;
    return static_cast<float>(n) + padding_cost * static_cast<float>(padded - n);
  }
};

/// Whether a node of `count` primitives at `depth` must take median splits from now on so
/// that every leaf stays above kBvhMaxDepth (they need ceil(log2(count)) more levels at most).
inline bool near_depth_limit(std::uint32_t depth, std::size_t count) {
  int levels = 0;
  while ((std::size_t{1} << levels) < count) ++levels;
  return static_cast<int>(depth) + levels + 1 >= kBvhMaxDepth;
}

/// Builds a binary BVH over the given primitive boxes with the binned SAH of Wald,
/// "On fast construction of SAH-based bounding volume hierarchies" (RT 2007): centroids
/// binned on all three axes, best plane by SAH, a leaf when the SAH says splitting does
/// not pay and the node holds at most max_leaf_size primitives. Above max_leaf_size a
/// split is forced; when the centroids coincide (or binning finds no plane) the node is
/// split at the object median. Reentrant; O(n log n). Parallel on oneTBB (big nodes binned in
/// parallel, subtrees built as tasks); the result is the same for any number of threads.
///
/// Robustness: a primitive whose box is empty (lo > hi, a NaN bound) or has a
/// non-finite bound is kept in a separate subtree under the root, split by index into
/// leaves of at most max_leaf_size; it never influences the SAH of the valid ones, and
/// with an empty box it is never visited by traversal. The depth is bounded by
/// kBvhMaxDepth whatever the input (near the bound the builder switches to median
/// splits); only the top levels (nodes of thousands of primitives) recurse, at most
/// kBvhMaxDepth deep, so no input can overflow a stack.
///
/// Throws std::invalid_argument for options outside the ranges above and
/// std::length_error for more than 2^32 - 1 primitives.
Bvh build_bvh(std::span<const BBox> prim_boxes, const BvhBuildOptions& options = {});

/// Throws std::invalid_argument, naming `builder`, for options outside the ranges above.
void check_build_options(const BvhBuildOptions& options, const char* builder);

/// Builds a binary BVH with spatial splits (Stich, Friedrich, Dietrich, "Spatial splits in
/// bounding volume hierarchies", HPG 2009) over triangles: primitive i is the triangle
/// vertices[3i .. 3i + 3), prim_boxes[i] its box (an empty box leaves it out of the tree).
/// Each node takes the cheapest by SAH of a leaf, the binned object split, and (where the
/// object split's children overlap) a binned spatial split, which cuts the triangles that
/// straddle its plane into references with clipped boxes; the splits add at most
/// max_growth * n references. prim_index may then name a triangle in several leaves, and
/// its size is that of the references. Clipping rounds outwards: the boxes of a
/// triangle's references cover it. Parallel on oneTBB; the same tree for any number of
/// threads. Throws std::invalid_argument for options outside build_bvh's ranges or
/// max_growth outside [0, 16].
Bvh build_bvh_spatial(std::span<const BBox> prim_boxes, const glm::vec3* vertices,
                      const BvhBuildOptions& options = {}, double max_growth = 1.0);

/// Size and quality of a BVH (for `volley info`, tests and benchmarks).
struct BvhStats {
  std::size_t nodes = 0;        ///< interior nodes + leaves
  std::size_t leaves = 0;       ///< leaves
  std::size_t depth = 0;        ///< depth of the deepest leaf (root = 0)
  double sah_cost = 0.0;        ///< SAH cost normalised by the root's area (see below)
  double mean_leaf_size = 0.0;  ///< primitives per leaf
  std::size_t bytes = 0;        ///< memory of nodes and prim_index
};

/// Statistics of a BVH. sah_cost = (traversal_cost * sum over interior nodes of A(node)
/// + intersection_cost * sum over leaves of A(leaf) * count) / A(root), A = half area;
/// NaN when the root's area is 0 or infinite. Depth counts edges (a lone root leaf: 0).
BvhStats bvh_stats(const Bvh& bvh, const BvhBuildOptions& options = {});

}  // namespace volley::core
