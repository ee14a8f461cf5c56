// Packing triangles into the per-test blocks (triangle_blocks.h). Baseline code: it uses
// the scalar oracle's own precomputation (PlaneTriangle::from, glm::cross) so the blocks
// hold exactly the values the oracle computes.
#pragma once
#include <cstddef>
#include <cstdint>

#include "simd/triangle/triangle_blocks.h"
#include "volley/options.h"

namespace volley::simd {

/// Blocks needed for n triangles: ceil(n / W).
template <int W>
constexpr std::size_t blocks_for(std::size_t n) {
  return (n + W - 1) / W;
}

/// Packs triangles 0 .. n into out[0 .. blocks_for<W>(n)), lane i of block b holding
/// triangle b*W + i: vertices xyz[9*t .. 9*t+9) (p0, p1, p2), id prim_ids[t]. Lanes past n
/// are padding: NaN geometry, prim = kInvalidPrim. A zero-area triangle (the watertight
/// oracle's first check) becomes a NaN lane with its prim id, so it is never hit; moller and
/// plane miss it through their own arithmetic (det = 0, resp. PlaneTriangle's "never").
/// Writes every byte of the blocks (out may be uninitialised). Instantiated for W = 4, 8,
/// 16 and every test.
template <TriangleTest Test, int W>
void pack_blocks(const float* xyz, const std::uint32_t* prim_ids, std::size_t n, BlockFor<Test, W>* out);

}  // namespace volley::simd
