// The notes' algorithm 1 on float lanes: ray/plane distance, then the two half-plane
// (edge plane) tests on the hit point, with the planes precomputed per triangle (Havel &
// Herout 2010), relative to the triangle's first vertex v0 (accurate far from the origin).
// The SIMD twin of src/core/triangle_plane.h: the same float operations in the same order
// (no FMA, a true division), so every lane gives the oracle's hit/miss and t, u, v bit for
// bit.
#pragma once
#include <limits>

#include "simd/triangle/kernel_common.h"
#include "simd/rays/prepared_packet.h"
#include "simd/rays/prepared_ray.h"
#include "simd/triangle/triangle_blocks.h"
#include "simd/triangle/triangle_test.h"

namespace volley::simd::detail {

/// Plane test on kLanes<Arch> (ray, triangle) pairs. Reads PlaneBlock<kLanes<Arch>>.
template <class Arch>
struct PlaneTest : PlainRays<Arch> {
  static constexpr Decision kDecision = Decision::direct;
  static constexpr int W = kLanes<Arch>;
  using Block = PlaneBlock<W>;
  using B = FloatB<Arch>;
  using M = MaskB<Arch>;

  using Rays = RayLanes<Arch>;
  /// Triangle lanes: reference vertex v0, plane n.(x - v0) = 0, edge plane gradients n1, n2.
  struct Tris {
    B v0x, v0y, v0z, nx, ny, nz, n1x, n1y, n1z, n2x, n2y, n2z;
  };
  /// Candidate hits: `valid` lanes are hit with tmin <= t < upper.
  struct Cand {
    M valid;
    B t, u, v;
  };

  [[gnu::always_inline]] inline static Tris load_block(const Block& b, const Rays& r);
  /// Triangle j of a block of any width BW (packets of 16 lanes read blocks of 8 on AVX-512).
  template <int BW>
  [[gnu::always_inline]] inline static Tris broadcast_tri(const PlaneBlock<BW>& b, int j, const Rays& r);
  /// The per-lane steps are always inlined into the kernel forms (one block or one triangle
  /// per call, so call overhead and batches passed through memory would dominate).
  /// EarlyExit: return as soon as no lane passes the den test (RayBlockKernels::intersect_inline).
  template <bool EarlyExit = true>
  [[gnu::always_inline]] inline static Cand test(const Rays& r, const Tris& tri, B upper);
  /// The lanes of `c` still hit when the upper end shrinks to `upper`.
  [[gnu::always_inline]] inline static M accept(const Cand& c, B upper);
};

template <class Arch>
auto PlaneTest<Arch>::load_block(const Block& b, const Rays&) -> Tris {
  return {B::load_aligned(b.v0[0]), B::load_aligned(b.v0[1]), B::load_aligned(b.v0[2]), B::load_aligned(b.n[0]),
          B::load_aligned(b.n[1]),  B::load_aligned(b.n[2]),  B::load_aligned(b.n1[0]), B::load_aligned(b.n1[1]),
          B::load_aligned(b.n1[2]), B::load_aligned(b.n2[0]), B::load_aligned(b.n2[1]), B::load_aligned(b.n2[2])};
}

template <class Arch>
template <int BW>
auto PlaneTest<Arch>::broadcast_tri(const PlaneBlock<BW>& b, int j, const Rays&) -> Tris {
  return {B(b.v0[0][j]), B(b.v0[1][j]), B(b.v0[2][j]), B(b.n[0][j]),  B(b.n[1][j]),  B(b.n[2][j]),
          B(b.n1[0][j]), B(b.n1[1][j]), B(b.n1[2][j]), B(b.n2[0][j]), B(b.n2[1][j]), B(b.n2[2][j])};
}

template <class Arch>
template <bool EarlyExit>
auto PlaneTest<Arch>::test(const Rays& r, const Tris& tri, B upper) -> Cand {
  const B zero(0.0f), one(1.0f);
  // den = n . dir; fails for 0 (parallel ray, degenerate triangle), Inf and NaN (padding).
  const B den = tri.nx * r.dx + tri.ny * r.dy + tri.nz * r.dz;
  M valid = finite_nonzero<Arch>(den);
  if (EarlyExit && xsimd::none(valid)) return {valid, den, den, den};
  // Ray/plane distance t = n . a / den with a = v0 - org (nearby numbers subtracted
  // first), in [tmin, upper).
  const B ax = tri.v0x - r.ox, ay = tri.v0y - r.oy, az = tri.v0z - r.oz;
  const B t = (tri.nx * ax + tri.ny * ay + tri.nz * az) / den;
  valid = valid & (r.tmin <= t) & (t < upper);
  // Half-plane tests on the hit point relative to v0, q = t dir - a: u = n1 . q, v = n2 . q.
  const B qx = t * r.dx - ax, qy = t * r.dy - ay, qz = t * r.dz - az;
  const B u = tri.n1x * qx + tri.n1y * qy + tri.n1z * qz;
  const B v = tri.n2x * qx + tri.n2y * qy + tri.n2z * qz;
  valid = valid & (u >= zero) & (v >= zero) & (u + v <= one);
  return {valid, t, u, v};
}

template <class Arch>
auto PlaneTest<Arch>::accept(const Cand& c, B upper) -> M {
  return c.valid & (c.t < upper);
}

}  // namespace volley::simd::detail
