// Triangle blocks: W triangles in SoA form, one layout per triangle test, each built only
// for the test in use (block_build.h fills them). Plain data, no xsimd: W is the lane
// count of the ISA that reads them (kLanes<Arch>), and every array is read with one
// aligned load. Padding lanes are inert: NaN geometry (every comparison false, so never a
// hit) and prim = kInvalidPrim.
#pragma once
#include <cstdint>

#include "simd/aligned.h"

namespace volley::simd {

/// Möller–Trumbore block: first vertex, the two edges from it and their cross product,
/// read by moller.h. The oracle computes n = e1 x e2 per test; storing it (computed by the
/// same float operations, so bit-identical) saves 9 operations per test (the test is ~35).
/// The second edge is stored negated: the oracle's u det = -(e2 . r) is (-e2) . r exactly,
/// one negation less per test.
template <int W>
struct alignas(64) MollerBlock {
  float v0[3][W];          // 12W bytes: p0, x y z lane arrays
  float e1[3][W];          // 12W bytes: p1 - p0
  float ne2[3][W];         // 12W bytes: -(p2 - p0)
  float n[3][W];           // 12W bytes: e1 x (p2 - p0) (not normalized)
  std::uint32_t prim[W];   //  4W bytes: prim ids, kInvalidPrim in padding lanes
};                         // 52 bytes per triangle (W = 4: 208 B padded to 256, W = 8: 416 to 448)
static_assert(sizeof(MollerBlock<4>) == 256 && sizeof(MollerBlock<8>) == 448 &&
              sizeof(MollerBlock<16>) == 832, "MollerBlock: 52 B per triangle, 64 B aligned");

/// Plane block (the notes' algorithm 1): the reference vertex v0, the supporting plane
/// n.(x - v0) = 0 and the two edge planes giving u = n1.(q - v0), v = n2.(q - v0) for q in the
/// plane; read by plane.h. Relative to v0, the planes' offsets are zero: v0's 12 bytes
/// replace the three absolute offsets, which cancelled far from the origin (issue 5).
template <int W>
struct alignas(64) PlaneBlock {
  float v0[3][W];          // 12W bytes: reference vertex p0
  float n[3][W];           // 12W bytes: plane normal
  float n1[3][W];          // 12W bytes: edge plane of u
  float n2[3][W];          // 12W bytes: edge plane of v
  std::uint32_t prim[W];   //  4W bytes
};                         // 52 bytes per triangle (W = 4: 208 B padded to 256, W = 8: 416 to 448)
static_assert(sizeof(PlaneBlock<4>) == 256 && sizeof(PlaneBlock<8>) == 448 &&
              sizeof(PlaneBlock<16>) == 832, "PlaneBlock: 52 B per triangle, 64 B aligned");

/// Watertight block (Woop, Benthin, Wald 2013): the raw vertices, sheared per ray by the
/// kernel; read by watertight.h. p[k][c] is coordinate c of vertex k.
template <int W>
struct alignas(64) WatertightBlock {
  float p[3][3][W];        // 36W bytes: p0, p1, p2, x y z lane arrays
  std::uint32_t prim[W];   //  4W bytes
};                         // 40 bytes per triangle (W = 4: 160 B padded to 192)
static_assert(sizeof(WatertightBlock<4>) == 192 && sizeof(WatertightBlock<8>) == 320 &&
              sizeof(WatertightBlock<16>) == 640, "WatertightBlock: 40 B per triangle, 64 B aligned");

template <int W>
inline constexpr bool kWalkedByRays<MollerBlock<W>> = true;
template <int W>
inline constexpr bool kWalkedByRays<PlaneBlock<W>> = true;
template <int W>
inline constexpr bool kWalkedByRays<WatertightBlock<W>> = true;

}  // namespace volley::simd

#include "volley/options.h"

namespace volley::simd {

/// The block layout a triangle test reads.
template <TriangleTest Test, int W>
struct BlockForT;
template <int W>
struct BlockForT<TriangleTest::moller, W> {
  using type = MollerBlock<W>;
};
template <int W>
struct BlockForT<TriangleTest::plane, W> {
  using type = PlaneBlock<W>;
};
template <int W>
struct BlockForT<TriangleTest::watertight, W> {
  using type = WatertightBlock<W>;
};
template <TriangleTest Test, int W>
using BlockFor = typename BlockForT<Test, W>::type;

}  // namespace volley::simd
