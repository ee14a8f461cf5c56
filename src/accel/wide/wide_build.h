// Building the wide BVH (simd/wide/wide_bvh.h) from the scalar oracle's binary BVH: the
// collapse into N-wide nodes and the packing of every leaf into triangle blocks.
#pragma once
#include <cstdint>

#include "core/bvh.h"
#include "simd/aligned.h"
#include "simd/triangle/triangle_blocks.h"
#include "simd/wide/wide_bvh.h"
#include "volley/options.h"

namespace volley::accel {

/// Collapses `bvh` (binary, over triangles numbered as its prim_index) into kWideN-wide
/// nodes and packs each of its leaves into blocks of W triangles (simd::pack_blocks).
///
/// Collapse: SAH-optimal over the binary tree's nodes (Ylitie, Karras, Laine 2017, with the
/// binary leaves kept): each wide node gets the forest of at most kWideN subtrees below its
/// binary node that minimises the summed surface area of the wide nodes. Children with an
/// empty box (the builder's subtree of degenerate triangles, which no ray can hit) are left
/// out, the others keep the binary node's box bit for bit (so the slab tests agree with the
/// oracle's). Fewer, fuller nodes than the greedy collapse (open the largest child until N;
/// perf/reports/build.md).
/// Interior children of a node are allocated next to each other, depth first; leaves' blocks
/// in the order the collapse meets them. Unused child slots are inert.
///
/// Triangle i (an index into bvh.prim_index's range) has vertices xyz[9i .. 9i + 9) and id
/// ids[i]. The collapse plan, the layout (below the top three wide levels) and the block
/// packing run in parallel on oneTBB; the result is the same for any number of threads.
/// Throws std::length_error when a leaf needs more than wide_ref::kMaxLeafBlocks blocks, the
/// BVH more than kMaxBlocks blocks or kMaxNodes nodes.
template <TriangleTest Test, int W>
simd::WideStats build_wide(const core::Bvh& bvh, const float* xyz, const std::uint32_t* ids,
                           simd::AlignedVector<simd::WideNode<simd::kWideN>>& nodes,
                           simd::AlignedVector<simd::BlockFor<Test, W>>& blocks, std::uint32_t& root);

/// Refits a BVH build_wide made to moved triangles, in place: the same tree, each leaf's
/// blocks repacked from the new vertices (in the same lanes), every box recomputed
/// bottom-up, and the SAH costs of `stats` recomputed (the rest kept). The triangle with
/// id `id` (as given to build_wide) now has vertices xyz[9 * index_of[id] .. + 9), or
/// xyz[9 * id ..] when index_of is null. Parallel on oneTBB.
template <TriangleTest Test, int W>
simd::WideStats refit_wide(const float* xyz, const std::uint32_t* index_of,
                           simd::AlignedVector<simd::WideNode<simd::kWideN>>& nodes,
                           simd::AlignedVector<simd::BlockFor<Test, W>>& blocks, simd::WideStats stats);

/// Every block form a wide BVH is built for, X(test, W): each triangle test at each block
/// width (4: SSE4.2's single-ray kernels, 8: AVX2's and AVX-512's, 16: 16-wide leaves,
/// which tests build). build_wide's and refit_wide's instantiations are made from it.
#define VOLLEY_WIDE_BLOCK_FORMS(X) \
  X(moller, 4) X(moller, 8) X(moller, 16) X(plane, 4) X(plane, 8) X(plane, 16) X(watertight, 4) X(watertight, 8) X(watertight, 16)

}  // namespace volley::accel
