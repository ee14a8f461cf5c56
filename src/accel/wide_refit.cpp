// Refit of a built wide BVH to moved triangles (wide_build.h): the same tree, every leaf's
// blocks repacked from the new vertices and every box recomputed bottom-up.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

#include "accel/wide_build.h"
#include "core/bbox.h"
#include "simd/block_build.h"
#include "volley/ray.h"

namespace volley::accel {
namespace {

constexpr int N = simd::kWideN;

/// The box of slot j of `node`.
core::BBox slot_box(const simd::WideNode<N>& node, int j) {
  core::BBox b;
  for (int a = 0; a < 3; ++a) b.lo[a] = node.bounds[2 * a][j], b.hi[a] = node.bounds[2 * a + 1][j];
  return b;
}

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

}  // namespace

template <TriangleTest Test, int W>
simd::WideStats refit_wide(const float* xyz, const std::uint32_t* index_of, simd::AlignedVector<simd::WideNode<N>>& nodes,
                           simd::AlignedVector<simd::BlockFor<Test, W>>& blocks, simd::WideStats stats) {
  namespace ref = simd::wide_ref;
  if (nodes.empty()) return stats;
  // Leaves, nodes in parallel: each leaf's triangles are its blocks' used lanes, in order.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nodes.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<float> tri_xyz;
    std::vector<std::uint32_t> tri_ids;
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      simd::WideNode<N>& node = nodes[i];
      for (int j = 0; j < N; ++j) {
        const std::uint32_t child = node.child[j];
        if (child == ref::kEmptyRef || !(child & ref::kLeafBit)) continue;
        const std::uint32_t first = ref::leaf_first(child), count = ref::leaf_count(child);
        tri_ids.clear();
        for (std::uint32_t b = first; b < first + count; ++b)
          for (int lane = 0; lane < W; ++lane)
            if (blocks[b].prim[lane] != volley::kInvalidPrim) tri_ids.push_back(blocks[b].prim[lane]);
        tri_xyz.resize(9 * tri_ids.size());
        core::BBox box;
        for (std::size_t t = 0; t < tri_ids.size(); ++t) {
          const float* p = xyz + 9 * std::size_t{index_of[tri_ids[t]]};
          std::memcpy(tri_xyz.data() + 9 * t, p, 9 * sizeof(float));
          for (int k = 0; k < 3; ++k) box.extend({p[3 * k], p[3 * k + 1], p[3 * k + 2]});
        }
        simd::pack_blocks<Test, W>(tri_xyz.data(), tri_ids.data(), tri_ids.size(), blocks.data() + first);
        set_slot_box(node, j, box);
      }
    }
  });
  // Interior boxes bottom-up: a node's interior children come after it in the array.
  double node_area = 0.0, leaf_area_tris = 0.0, leaf_area_blocks = 0.0;
  for (std::size_t i = nodes.size(); i-- > 0;) {
    simd::WideNode<N>& node = nodes[i];
    for (int j = 0; j < N; ++j) {
      const std::uint32_t child = node.child[j];
      if (child == ref::kEmptyRef) continue;
      if (child & ref::kLeafBit) {
        const double area = slot_box(node, j).half_area();
        std::size_t used = 0;
        for (std::uint32_t b = ref::leaf_first(child); b < ref::leaf_first(child) + ref::leaf_count(child); ++b)
          for (int lane = 0; lane < W; ++lane) used += blocks[b].prim[lane] != volley::kInvalidPrim;
        leaf_area_tris += area * double(used);
        leaf_area_blocks += area * double(ref::leaf_count(child));
      } else {
        set_slot_box(node, j, node_box(ref::node_at(nodes.data(), child)));
      }
    }
    node_area += node_box(node).half_area();
  }
  const double root_area = node_box(nodes[0]).half_area();
  if (root_area > 0.0) {
    stats.sah_cost = (node_area + leaf_area_tris) / root_area;
    stats.block_sah_cost = (node_area + leaf_area_blocks) / root_area;
  } else {
    stats.sah_cost = stats.block_sah_cost = std::numeric_limits<double>::quiet_NaN();
  }
  return stats;
}

#define VOLLEY_REFIT(test, w)                                                                       \
  template simd::WideStats refit_wide<TriangleTest::test, w>(                                        \
      const float*, const std::uint32_t*, simd::AlignedVector<simd::WideNode<N>>&,                  \
      simd::AlignedVector<simd::BlockFor<TriangleTest::test, w>>&, simd::WideStats);
VOLLEY_REFIT(moller, 4)
VOLLEY_REFIT(moller, 8)
VOLLEY_REFIT(moller, 16)
VOLLEY_REFIT(plane, 4)
VOLLEY_REFIT(plane, 8)
VOLLEY_REFIT(plane, 16)
VOLLEY_REFIT(watertight, 4)
VOLLEY_REFIT(watertight, 8)
VOLLEY_REFIT(watertight, 16)
#undef VOLLEY_REFIT

}  // namespace volley::accel
