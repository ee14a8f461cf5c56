// Packing triangles into the per-test blocks (block_build.h).
#include "simd/triangle/block_build.h"

#include <cstddef>
#include <cstring>
#include <limits>

#include "core/geometry.h"
#include "core/triangle_plane.h"
#include "volley/ray.h"

namespace volley::simd {
namespace {

using V3 = core::Vec3<float>;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

V3 vertex(const float* xyz, std::size_t t, int k) {
  const float* p = xyz + 9 * t + 3 * k;
  return V3(p[0], p[1], p[2]);
}

template <int W>
void put(float (&lanes)[3][W], int i, const V3& v) {
  lanes[0][i] = v.x, lanes[1][i] = v.y, lanes[2][i] = v.z;
}

template <int W>
void fill_lane(MollerBlock<W>& b, int i, const V3& p0, const V3& p1, const V3& p2) {
  // The oracle's operations: e1 = p1 - p0, e2 = p2 - p0, n = e1 x e2.
  const V3 e1 = p1 - p0, e2 = p2 - p0;
  put<W>(b.v0, i, p0);
  put<W>(b.e1, i, e1);
  put<W>(b.ne2, i, -e2);
  put<W>(b.n, i, glm::cross(e1, e2));
}

template <int W>
void fill_lane(PlaneBlock<W>& b, int i, const V3& p0, const V3& p1, const V3& p2) {
  const core::PlaneTriangle<float> pt = core::PlaneTriangle<float>::from(p0, p1, p2);
  put<W>(b.v0, i, pt.p0);
  put<W>(b.n, i, pt.n);
  put<W>(b.n1, i, pt.n1);
  put<W>(b.n2, i, pt.n2);
}

template <int W>
void fill_lane(WatertightBlock<W>& b, int i, const V3& p0, const V3& p1, const V3& p2) {
  // The oracle rejects a triangle whose cross product is exactly zero before anything
  // else; a NaN lane fails the kernel's det test the same way.
  const bool zero_area = glm::cross(p1 - p0, p2 - p0) == V3(0);
  const V3 nan(kNaN);
  put<W>(b.p[0], i, zero_area ? nan : p0);
  put<W>(b.p[1], i, zero_area ? nan : p1);
  put<W>(b.p[2], i, zero_area ? nan : p2);
}

template <class Block>
void fill_padding(Block& b, int i) {
  // Every float of the lane NaN: no comparison in any test passes.
  float* f = reinterpret_cast<float*>(&b);
  constexpr int kW = sizeof(b.prim) / sizeof(b.prim[0]);
  constexpr int kArrays = static_cast<int>(offsetof(Block, prim) / sizeof(float)) / kW;
  for (int a = 0; a < kArrays; ++a) f[a * kW + i] = kNaN;
  b.prim[i] = kInvalidPrim;
}

}  // namespace

template <TriangleTest Test, int W>
void pack_blocks(const float* xyz, const std::uint32_t* prim_ids, std::size_t n, BlockFor<Test, W>* out) {
  for (std::size_t b = 0; b < blocks_for<W>(n); ++b) {
    // Every byte written, the struct's tail padding included: `out` may be uninitialised.
    // (A block without tail padding gets every byte from the lanes below.)
    using Block = BlockFor<Test, W>;
    if constexpr (sizeof(Block) != offsetof(Block, prim) + sizeof(Block::prim))
      std::memset(static_cast<void*>(&out[b]), 0, sizeof(out[b]));
    for (int i = 0; i < W; ++i) {
      const std::size_t t = b * W + static_cast<std::size_t>(i);
      if (t >= n) {
        fill_padding(out[b], i);
        continue;
      }
      fill_lane<W>(out[b], i, vertex(xyz, t, 0), vertex(xyz, t, 1), vertex(xyz, t, 2));
      out[b].prim[i] = prim_ids[t];
    }
  }
}

template void pack_blocks<TriangleTest::moller, 4>(const float*, const std::uint32_t*, std::size_t, MollerBlock<4>*);
template void pack_blocks<TriangleTest::moller, 8>(const float*, const std::uint32_t*, std::size_t, MollerBlock<8>*);
template void pack_blocks<TriangleTest::moller, 16>(const float*, const std::uint32_t*, std::size_t, MollerBlock<16>*);
template void pack_blocks<TriangleTest::plane, 4>(const float*, const std::uint32_t*, std::size_t, PlaneBlock<4>*);
template void pack_blocks<TriangleTest::plane, 8>(const float*, const std::uint32_t*, std::size_t, PlaneBlock<8>*);
template void pack_blocks<TriangleTest::plane, 16>(const float*, const std::uint32_t*, std::size_t, PlaneBlock<16>*);
template void pack_blocks<TriangleTest::watertight, 4>(const float*, const std::uint32_t*, std::size_t,
                                                       WatertightBlock<4>*);
template void pack_blocks<TriangleTest::watertight, 8>(const float*, const std::uint32_t*, std::size_t,
                                                       WatertightBlock<8>*);
template void pack_blocks<TriangleTest::watertight, 16>(const float*, const std::uint32_t*, std::size_t,
                                                        WatertightBlock<16>*);

}  // namespace volley::simd
