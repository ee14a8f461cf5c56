// The point query of the wide BVH (closest point, distance, signed distance): children
// visited nearest box first by their squared box distances, eight at once (Lanes8), a
// stacked subtree dropped once its box lies beyond the nearest triangle found, and each
// leaf's blocks answered by core::nearest_on_triangle on the block's lanes.
#pragma once
#include <bit>
#include <cmath>
#include <cstdint>
#include <stdexcept>

#include "core/kernel_constants.h"
#include "core/bvh_nearest.h"
#include "core/point_triangle.h"
#include "simd/wide/node_lanes.h"

namespace volley::simd {

namespace detail {

/// core::nearest_on_triangle's lane operations on xsimd batches.
template <class Arch>
struct BatchLaneOps {
  using B = FloatB<Arch>;
  using Mask = MaskB<Arch>;
  static B select(Mask m, B a, B b) { return xsimd::select(m, a, b); }
  static B clamp01(B x) {
    const B zero(0.0f), one(1.0f);
    const B lo = xsimd::select(x > zero, x, zero);
    return xsimd::select(lo < one, lo, one);
  }
  static Mask and_(Mask a, Mask b) { return a & b; }
};

/// A block's triangles as a vertex and two edges per lane (e1 = b - a, e2 = c - a, rounded
/// as core::offer_triangle_vertices rounds them), for the tests that keep the vertices.
template <class Arch, class Block>
struct BlockEdges {
  static constexpr bool kHasVertices = false;
};
template <class Arch, int W>
struct BlockEdges<Arch, WatertightBlock<W>> {
  static constexpr bool kHasVertices = true;
  using B = FloatB<Arch>;
  static void lanes(const WatertightBlock<W>& b, B* a, B* e1, B* e2) {
    for (int k = 0; k < 3; ++k) {
      a[k] = B::load_aligned(b.p[0][k]);
      e1[k] = B::load_aligned(b.p[1][k]) - a[k];
      e2[k] = B::load_aligned(b.p[2][k]) - a[k];
    }
  }
  static void lane(const WatertightBlock<W>& b, int i, float* a, float* e1, float* e2) {
    for (int k = 0; k < 3; ++k) a[k] = b.p[0][k][i], e1[k] = b.p[1][k][i] - a[k], e2[k] = b.p[2][k][i] - a[k];
  }
};
template <class Arch, int W>
struct BlockEdges<Arch, MollerBlock<W>> {
  static constexpr bool kHasVertices = true;
  using B = FloatB<Arch>;
  static void lanes(const MollerBlock<W>& b, B* a, B* e1, B* e2) {
    for (int k = 0; k < 3; ++k) {
      a[k] = B::load_aligned(b.v0[k]);
      e1[k] = B::load_aligned(b.e1[k]);
      e2[k] = -B::load_aligned(b.ne2[k]);
    }
  }
  static void lane(const MollerBlock<W>& b, int i, float* a, float* e1, float* e2) {
    for (int k = 0; k < 3; ++k) a[k] = b.v0[k][i], e1[k] = b.e1[k][i], e2[k] = -b.ne2[k][i];
  }
};

/// A stacked subtree of the point walk and its squared box distance.
struct PointItem {
  std::uint32_t ref;
  float d2;
};

/// The children of `node` whose box lies within `bound` (squared) of the point p (each
/// coordinate in all lanes), pushed farthest first so that the nearest is popped next.
template <class Arch>
[[gnu::always_inline]] inline void push_near_children(const WideNode<kWideN>& node, const typename Lanes8<Arch>::V* p,
                                                      float bound, PointItem* stack, int& size) {
  using V8 = Lanes8<Arch>;
  const typename V8::V zero = V8::set1(0.0f);
  auto axis = [&](int a) {
    const auto d = V8::max(V8::max(V8::sub(V8::load(node.bounds[2 * a]), p[a]), V8::sub(p[a], V8::load(node.bounds[2 * a + 1]))), zero);
    return V8::mul(d, d);
  };
  const auto d2 = V8::add(V8::add(axis(0), axis(1)), axis(2));
  alignas(32) float dist[8];
  V8::store(dist, d2);
  std::uint32_t mask = V8::le(d2, V8::set1(bound));
  const int base = size;
  for (; mask != 0; mask &= mask - 1) {
    const int c = std::countr_zero(mask);
    int k = size++;
    for (; k > base && stack[k - 1].d2 < dist[c]; --k) stack[k] = stack[k - 1];
    stack[k] = {node.child[c], dist[c]};
  }
}

/// The nearest triangle of one leaf block to the point p (each coordinate in all lanes)
/// offered to `query` when nearer than its bound.
template <class Arch, class Block>
[[gnu::always_inline]] inline void offer_nearest_in_block(const Block& block, const FloatB<Arch>* p, float bound,
                                                          core::PointQuery& query) {
  using B = FloatB<Arch>;
  using Edges = BlockEdges<Arch, Block>;
  B a[3], e1[3], e2[3];
  Edges::lanes(block, a, e1, e2);
  // The triangles' boxes first: a block whose every triangle lies beyond the bound (most,
  // once a near triangle is known) costs no distance computation.
  const B zero(0.0f);
  B box2 = zero;
  for (int k = 0; k < 3; ++k) {
    const B bk = a[k] + e1[k], ck = a[k] + e2[k];
    const B lo = xsimd::min(a[k], xsimd::min(bk, ck)), hi = xsimd::max(a[k], xsimd::max(bk, ck));
    const B d = xsimd::max(xsimd::max(lo - p[k], p[k] - hi), zero);
    box2 = box2 + d * d;
  }
  if (xsimd::none(box2 <= B(bound))) return;
  const auto r = core::nearest_on_triangle<B, BatchLaneOps<Arch>>(p[0] - a[0], p[1] - a[1], p[2] - a[2], e1[0], e1[1],
                                                                  e1[2], e2[0], e2[1], e2[2]);
  // The nearest lane (the first of equals: what offering the lanes in order keeps) through
  // the scalar oracle, which recomputes it with the same operations (the same values) and
  // fills in the point and barycentrics.
  const B nearer = xsimd::select(r.d2 < B(query.d2), r.d2, B(INFINITY));  // NaN (padding) out
  const std::uint32_t bits = bits_from_mask<Arch>(nearer == B(reduce_min<Arch>(nearer))) &
                             bits_from_mask<Arch>(nearer < B(query.d2));
  if (bits == 0) return;
  const int i = std::countr_zero(bits);
  float la[3], le1[3], le2[3];
  Edges::lane(block, i, la, le1, le2);
  core::offer_triangle(query, la, le1, le2, block.prim[i]);
}

}  // namespace detail

template <class Arch, TriangleTest Test, bool Robust, int PK>
void WideKernels<Arch, Test, Robust, PK>::closest_point(const View& bvh, core::PointQuery& query) {
  if constexpr (!detail::BlockEdges<SingleArch, Block>::kHasVertices) {
    throw std::invalid_argument("point queries need the watertight or Moller triangle test (the plane test's blocks keep no vertices)");
  } else {
    using V8 = detail::Lanes8<Arch>;
    using B = detail::FloatB<SingleArch>;
    const float* p = query.p;
    if (bvh.root == wide_ref::kEmptyRef || !std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) return;
    // A box may be skipped only when it lies surely beyond the nearest triangle: its
    // squared distance against the bound padded for the rounding of both (a relative
    // 2^-10, far above the few ulps of either), and never +inf (an unused child).
    auto bound = [&] { return core::nearest_bound(query.d2); };
    const typename V8::V node_p[3] = {V8::set1(p[0]), V8::set1(p[1]), V8::set1(p[2])};
    const B block_p[3] = {B(p[0]), B(p[1]), B(p[2])};
    detail::PointItem stack[(kWideN - 1) * core::kBvhMaxDepth + 1];
    int size = 0;
    std::uint32_t ref = bvh.root;
    for (;;) {
      if (!(ref & wide_ref::kLeafBit)) {
        const auto& node = *reinterpret_cast<const WideNode<kWideN>*>(reinterpret_cast<const char*>(bvh.nodes) + ref);
        detail::push_near_children<Arch>(node, node_p, bound(), stack, size);
      } else {
        const std::uint32_t first = ref & wide_ref::kFirstMask;
        const std::uint32_t count = (ref >> wide_ref::kCountShift) & wide_ref::kCountMask;
        for (std::uint32_t b = first; b < first + count; ++b)
          detail::offer_nearest_in_block<SingleArch>(bvh.blocks[b], block_p, bound(), query);
      }
      for (;;) {
        if (size == 0) return;
        --size;
        if (stack[size].d2 <= bound()) break;
      }
      ref = stack[size].ref;
    }
  }
}

}  // namespace volley::simd
