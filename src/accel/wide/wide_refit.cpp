// Refit of a built wide BVH to moved triangles (wide_build.h): the same tree, every leaf's
// blocks repacked from the new vertices and every box recomputed bottom-up.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <immintrin.h>

#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

#include "accel/wide/wide_build.h"
#include "core/bbox.h"
#include "simd/triangle/block_build.h"
#include "volley/ray.h"

namespace volley::accel {
namespace {

constexpr int N = simd::kWideN;

using simd::slot_box;

void set_slot_box(simd::WideNode<N>& node, int j, const core::BBox& b) {
  for (int a = 0; a < 3; ++a) node.bounds[2 * a][j] = b.lo[a], node.bounds[2 * a + 1][j] = b.hi[a];
}

/// The box of all used slots of a node (inert slots are empty boxes: they add nothing).
core::BBox node_box(const simd::WideNode<N>& node) {
  core::BBox b;
  for (int j = 0; j < N; ++j)
    if (node.child[j] != simd::wide_ref::kEmptyRef) b.extend(slot_box(node, j));
  return b;
}

/// The blocks' triangle ids in block order, in one pass that the hardware prefetcher
/// streams (read node by node, each block's id line was a cache miss).
template <class Block, int W>
std::vector<std::uint32_t> block_ids(const simd::AlignedVector<Block>& blocks) {
  std::vector<std::uint32_t> ids(blocks.size() * W);
  using Range = tbb::blocked_range<std::size_t>;
  tbb::parallel_for(Range(0, blocks.size(), 4096), [&](const Range& r) {
    for (std::size_t b = r.begin(); b < r.end(); ++b) std::memcpy(&ids[b * W], blocks[b].prim, sizeof(blocks[b].prim));
  });
  return ids;
}

/// A node's leaves' triangles: their ids (a leaf's are its blocks' used lanes, in order;
/// slot j's are [leaf_end[j - 1], leaf_end[j])) and their moved vertices, copied together.
/// They lie anywhere in xyz: all are requested (dozens of lines in flight) before the first copy.
template <int W>
struct LeafTriangles {
  std::vector<float> xyz;
  std::vector<std::uint32_t> ids;
  std::uint32_t leaf_end[N];

  void gather(const simd::WideNode<N>& node, const std::vector<std::uint32_t>& block_ids, const float* all_xyz,
              const std::uint32_t* index_of) {
    namespace ref = simd::wide_ref;
    ids.clear();
    for (int j = 0; j < N; ++j) {
      const std::uint32_t child = node.child[j];
      if (child != ref::kEmptyRef && (child & ref::kLeafBit))
        for (std::uint32_t b = ref::leaf_first(child); b < ref::leaf_first(child) + ref::leaf_count(child); ++b)
          for (int lane = 0; lane < W; ++lane) {
            const std::uint32_t id = block_ids[b * W + lane];
            if (id == volley::kInvalidPrim) continue;
            ids.push_back(id);
            const float* p = all_xyz + 9 * std::size_t{index_of ? index_of[id] : id};
            __builtin_prefetch(p);
            __builtin_prefetch(p + 8);
          }
      leaf_end[j] = static_cast<std::uint32_t>(ids.size());
    }
    xyz.resize(9 * ids.size() + 1);  // + 1: the box loop's last load reads one float past
    for (std::size_t t = 0; t < ids.size(); ++t)
      std::memcpy(xyz.data() + 9 * t, all_xyz + 9 * std::size_t{index_of ? index_of[ids[t]] : ids[t]},
                  9 * sizeof(float));
  }

  /// The box of triangles [begin, end), a vertex per SSE min and max (lane 3, the next
  /// float, dropped); operands in BBox::extend's order, so NaN coordinates are ignored as there.
  core::BBox box(std::uint32_t begin, std::uint32_t end) const {
    constexpr float kInf = std::numeric_limits<float>::infinity();
    __m128 lo = _mm_set1_ps(kInf), hi = _mm_set1_ps(-kInf);
    for (std::uint32_t f = 9 * begin; f < 9 * end; f += 3) {
      const __m128 v = _mm_loadu_ps(xyz.data() + f);
      lo = _mm_min_ps(v, lo), hi = _mm_max_ps(v, hi);
    }
    alignas(16) float l4[4], h4[4];
    _mm_store_ps(l4, lo), _mm_store_ps(h4, hi);
    return {{l4[0], l4[1], l4[2]}, {h4[0], h4[1], h4[2]}};
  }
};

/// The SAH terms of a node's leaves (area x triangles, area x blocks).
struct LeafCost {
  double triangles = 0.0, blocks = 0.0;
};

/// Interior boxes bottom-up (a node's interior children come after it in the array) and
/// the tree's SAH costs, the leaves' terms summed in node order so that the result does not
/// depend on the threads.
void refit_interiors(simd::AlignedVector<simd::WideNode<N>>& nodes, const std::vector<LeafCost>& leaf_cost,
                     simd::WideStats& stats) {
  namespace ref = simd::wide_ref;
  double node_area = 0.0, leaf_area_tris = 0.0, leaf_area_blocks = 0.0;
  for (std::size_t i = nodes.size(); i-- > 0;) {
    simd::WideNode<N>& node = nodes[i];
    for (int j = 0; j < N; ++j) {
      const std::uint32_t child = node.child[j];
      if (child != ref::kEmptyRef && !(child & ref::kLeafBit))
        set_slot_box(node, j, node_box(ref::node_at(nodes.data(), child)));
    }
    node_area += node_box(node).half_area();
    leaf_area_tris += leaf_cost[i].triangles;
    leaf_area_blocks += leaf_cost[i].blocks;
  }
  const double root_area = node_box(nodes[0]).half_area();
  if (root_area > 0.0) {
    stats.sah_cost = (node_area + leaf_area_tris) / root_area;
    stats.block_sah_cost = (node_area + leaf_area_blocks) / root_area;
  } else {
    stats.sah_cost = stats.block_sah_cost = std::numeric_limits<double>::quiet_NaN();
  }
}

}  // namespace

template <TriangleTest Test, int W>
simd::WideStats refit_wide(const float* xyz, const std::uint32_t* index_of, simd::AlignedVector<simd::WideNode<N>>& nodes,
                           simd::AlignedVector<simd::BlockFor<Test, W>>& blocks, simd::WideStats stats) {
  namespace ref = simd::wide_ref;
  if (nodes.empty()) return stats;
  std::vector<LeafCost> leaf_cost(nodes.size());
  const std::vector<std::uint32_t> ids = block_ids<simd::BlockFor<Test, W>, W>(blocks);
  // Leaves, nodes in parallel: each leaf's blocks repacked from its moved triangles.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nodes.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
    LeafTriangles<W> tris;
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      simd::WideNode<N>& node = nodes[i];
      tris.gather(node, ids, xyz, index_of);
      for (int j = 0; j < N; ++j) {
        const std::uint32_t child = node.child[j];
        if (child == ref::kEmptyRef || !(child & ref::kLeafBit)) continue;
        const std::uint32_t begin = j == 0 ? 0 : tris.leaf_end[j - 1], end = tris.leaf_end[j];
        const core::BBox box = tris.box(begin, end);
        simd::pack_blocks<Test, W>(tris.xyz.data() + 9 * std::size_t{begin}, tris.ids.data() + begin, end - begin,
                                   blocks.data() + ref::leaf_first(child));
        set_slot_box(node, j, box);
        const double area = box.half_area();
        leaf_cost[i].triangles += area * double(end - begin);
        leaf_cost[i].blocks += area * double(ref::leaf_count(child));
      }
    }
  });
  refit_interiors(nodes, leaf_cost, stats);
  return stats;
}

#define VOLLEY_REFIT(test, w)                                                                       \
  template simd::WideStats refit_wide<TriangleTest::test, w>(                                        \
      const float*, const std::uint32_t*, simd::AlignedVector<simd::WideNode<N>>&,                  \
      simd::AlignedVector<simd::BlockFor<TriangleTest::test, w>>&, simd::WideStats);
VOLLEY_WIDE_BLOCK_FORMS(VOLLEY_REFIT)
#undef VOLLEY_REFIT

}  // namespace volley::accel
