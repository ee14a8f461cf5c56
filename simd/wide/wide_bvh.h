// The wide BVH: N-wide nodes (N = 8) with their children's boxes in SoA, collapsed from
// the scalar oracle's binary binned-SAH BVH (core/bvh.h), leaves pointing at runs of
// triangle blocks (triangle_blocks.h). Plain data, no xsimd: the traversal kernels
// (wide_traverse.h) read it, baseline code builds it (wide_build.cpp).
#pragma once
#include <cstddef>
#include <cstdint>

#include "core/bvh.h"
#include "simd/aligned.h"

namespace volley::simd {

/// BVH width: children per node. 8 children are one AVX register per box plane; SSE tests
/// them as two halves (N = 4 for SSE was not measured).
inline constexpr int kWideN = 8;

/// One N-wide node: the boxes of its children in SoA (a plane per array, the slab test of
/// all N children is one vector operation per plane), and a reference per child.
/// bounds[2a] = lower bounds on axis a, bounds[2a + 1] = upper bounds, so the near and far
/// planes of a ray are picked by its octant with an offset of N floats.
/// Unused children are inert: lo = +inf, hi = -inf (every slab test fails for every ray,
/// NaN rays and zero direction components included), ref = kEmptyRef.
template <int N>
struct alignas(64) WideNode {
  float bounds[6][N];       // 24N bytes: lo_x hi_x lo_y hi_y lo_z hi_z, one lane per child
  std::uint32_t child[N];   //  4N bytes: child references (see WideRef)
};                          // N = 8: 224 bytes, padded to 256 (4 cache lines); N = 4: 112 -> 128
static_assert(sizeof(WideNode<8>) == 256, "WideNode<8>: 192 B boxes + 32 B refs + 32 B padding");
static_assert(sizeof(WideNode<4>) == 128, "WideNode<4>: 96 B boxes + 16 B refs + 16 B padding");
template <int N>
inline constexpr bool kWalkedByRays<WideNode<N>> = true;

/// Child references, 32 bits:
///   interior: bit 31 clear, bits 0..30 = the node's byte offset in the node array (index
///             times sizeof(WideNode<N>)), so the walk adds it to the array's address
///             without a shift (the shift sat on the walk's longest chain);
///   leaf:     bit 31 set, bits 27..30 = block count (0..15), bits 0..26 = first block.
/// A leaf of 0 blocks is the empty reference (kEmptyRef).
namespace wide_ref {
inline constexpr std::uint32_t kLeafBit = 0x80000000u;
inline constexpr int kCountShift = 27;
inline constexpr std::uint32_t kCountMask = 0xfu;
inline constexpr std::uint32_t kFirstMask = (1u << kCountShift) - 1u;
/// Most blocks one leaf may hold.
inline constexpr std::uint32_t kMaxLeafBlocks = kCountMask;
/// Most blocks a wide BVH may hold (first block index fits 27 bits).
inline constexpr std::size_t kMaxBlocks = std::size_t{1} << kCountShift;
/// The reference of an unused child (a leaf of zero blocks).
inline constexpr std::uint32_t kEmptyRef = kLeafBit;
/// Most interior nodes an N-wide BVH may hold (their byte offsets fit 31 bits).
template <int N>
inline constexpr std::size_t kMaxNodes = std::size_t{kLeafBit} / sizeof(WideNode<N>);
/// The reference of interior node `index` (< kMaxNodes<N>).
template <int N>
constexpr std::uint32_t interior(std::size_t index) {
  return static_cast<std::uint32_t>(index * sizeof(WideNode<N>));
}
/// The node an interior reference names.
template <int N>
inline const WideNode<N>& node_at(const WideNode<N>* nodes, std::uint32_t ref) {
  return *reinterpret_cast<const WideNode<N>*>(reinterpret_cast<const char*>(nodes) + ref);
}
/// The reference of a leaf of `count` blocks from block `first` (count <= kMaxLeafBlocks,
/// first < kMaxBlocks).
constexpr std::uint32_t leaf(std::size_t first, std::uint32_t count) {
  return kLeafBit | (count << kCountShift) | static_cast<std::uint32_t>(first);
}
/// The blocks a leaf reference holds.
constexpr std::uint32_t leaf_count(std::uint32_t ref) { return (ref >> kCountShift) & kCountMask; }
/// The index of a leaf reference's first block.
constexpr std::uint32_t leaf_first(std::uint32_t ref) { return ref & kFirstMask; }
/// Requests the cache lines of [first, first + bytes) for reading.
inline void request_lines(std::uintptr_t first, std::size_t bytes) {
  for (std::size_t offset = 0; offset < bytes; offset += 64)
    __builtin_prefetch(reinterpret_cast<const void*>(first + offset));
}
/// Requests the first block of leaf `ref` into the cache. The closest-hit walks and the
/// frustum walk call it as soon as a node test finds the leaf entered, so that the misses
/// of a node's entered leaves overlap instead of following one another (perf/reports/rays.md,
/// "leaf requests"; the any-hit single-ray and per-lane walks gained nothing from it). The
/// address is formed as an integer: an empty tree's blocks are a null pointer.
template <class Leaves>
inline void request_leaf(const Leaves* blocks, std::uint32_t ref) {
  request_lines(reinterpret_cast<std::uintptr_t>(blocks) + sizeof(Leaves) * std::uintptr_t{leaf_first(ref)},
                sizeof(Leaves));
}
/// Requests interior node `ref` (its boxes and references) into the cache: the frustum walk
/// calls it for every child it pushes (perf/reports/rays.md, "leaf requests").
template <int N>
inline void request_node(const WideNode<N>* nodes, std::uint32_t ref) {
  request_lines(reinterpret_cast<std::uintptr_t>(nodes) + ref, sizeof(WideNode<N>));
}
}  // namespace wide_ref

/// The box of child slot j of `node` (an unused slot's is empty).
template <int N>
inline core::BBox slot_box(const WideNode<N>& node, int j) {
  core::BBox b;
  for (int a = 0; a < 3; ++a) b.lo[a] = node.bounds[2 * a][j], b.hi[a] = node.bounds[2 * a + 1][j];
  return b;
}

/// What the kernels read of a built WideBvh: raw pointers (the owner keeps the storage).
/// A leaf reference names a run of `Block`s (triangle blocks; instance ids for the top
/// level of an instanced scene).
template <class Block>
struct WideView {
  const WideNode<kWideN>* nodes;  ///< 64-byte aligned
  const Block* blocks;            ///< triangle blocks: 64-byte aligned
  std::uint32_t root;             ///< root reference (wide_ref)
  /// The tree outgrows the caches (kDeferHandoffBytes): the per-lane any-hit walk of
  /// one-octant packets defers its hand-offs to single rays and requests their subtrees
  /// first (packet_walk.h).
  bool defer_handoffs = false;
};

/// Trees of at least this many bytes (nodes and blocks) defer the any-hit packet walk's
/// hand-offs (WideView::defer_handoffs): past the last-level cache the hand-off walks wait
/// on memory, which the deferral overlaps; on trees that fit, it only costs (perf/reports/rays.md,
/// "deferred hand-offs on trees past the caches").
inline constexpr std::size_t kDeferHandoffBytes = std::size_t{24} << 20;

/// A built wide BVH over triangle blocks of type Block (BlockFor<Test, W>): nodes, blocks,
/// the root reference and build statistics. Immutable after build; thread-safe to read.
template <int N, class Block>
struct WideBvh {
  AlignedVector<WideNode<N>> nodes;  // 256 bytes per node (N = 8)
  AlignedVector<Block> blocks;       // sizeof(Block) per W triangles, leaves padded to whole blocks
  /// Root reference: an interior node (nodes[0]), a leaf (a scene of one leaf), or
  /// kEmptyRef (no triangle can be hit).
  std::uint32_t root = wide_ref::kEmptyRef;
};

/// Statistics of a wide BVH (for AccelInfo / `volley info`).
struct WideStats {
  std::size_t nodes = 0;         ///< wide interior nodes
  std::size_t leaves = 0;        ///< leaves (runs of blocks)
  std::size_t depth = 0;         ///< deepest leaf in wide levels (root = 0)
  std::size_t blocks = 0;        ///< triangle blocks
  std::size_t triangles = 0;     ///< triangles stored in leaves (degenerate ones left out)
  double mean_children = 0.0;    ///< used children per node (fill of the N lanes)
  double sah_cost = 0.0;         ///< sum A(node) + sum A(leaf) * triangles, over A(root)
  double block_sah_cost = 0.0;   ///< sum A(node) + sum A(leaf) * blocks, over A(root)
  std::size_t bytes = 0;         ///< nodes + blocks
};

}  // namespace volley::simd
