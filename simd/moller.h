// Möller–Trumbore (1997) ray/triangle test on float lanes: the 3x3 barycentric system
// solved by Cramer's rule. The SIMD twin of src/core/triangle_moller.h: the same float
// operations in the same order (no FMA, true divisions), so every lane gives the
// oracle's hit/miss and t, u, v bit for bit.
#pragma once
#include <limits>

#include "simd/kernel_common.h"
#include "simd/prepared_packet.h"
#include "simd/prepared_ray.h"
#include "simd/triangle_blocks.h"

namespace volley::simd::detail {

/// Möller–Trumbore on kLanes<Arch> (ray, triangle) pairs: one ray against a block, or
/// one triangle against a packet's lanes. Reads MollerBlock<kLanes<Arch>>.
template <class Arch>
struct MollerTest {
  static constexpr int W = kLanes<Arch>;
  using Block = MollerBlock<W>;
  using B = FloatB<Arch>;
  using M = MaskB<Arch>;

  using Rays = RayLanes<Arch>;
  /// Triangle lanes: p0, e1 = p1 - p0, ne2 = -(p2 - p0), n = e1 x (p2 - p0).
  struct Tris {
    B v0x, v0y, v0z, e1x, e1y, e1z, ne2x, ne2y, ne2z, nx, ny, nz;
  };
  /// Candidate hits: `valid` lanes are hit with tmin <= t < upper; t, u, v are
  /// meaningful in those lanes only.
  struct Cand {
    M valid;
    B t, u, v;
  };

  [[gnu::always_inline]] inline static Rays broadcast(const PreparedRay& r);
  /// Nothing to precompute per lane: copies the rays.
  template <int K>
  static void prepare(const RayPacket<K>& rays, PreparedPacket<K>& out);
  template <int K>
  [[gnu::always_inline]] inline static Rays load(const PreparedPacket<K>& p, int offset);
  [[gnu::always_inline]] inline static Tris load_block(const Block& b, const Rays& r);
  [[gnu::always_inline]] inline static Tris broadcast_tri(const Block& b, int j, const Rays& r);
  /// The per-lane steps are always inlined into the kernel forms (one block or one triangle
  /// per call, so call overhead and batches passed through memory would dominate).
  [[gnu::always_inline]] inline static Cand test(const Rays& r, const Tris& tri, B upper);
  /// The lanes of `c` still hit when the upper end shrinks to `upper` (<= the one test()
  /// saw): exactly what test() would have answered for it.
  [[gnu::always_inline]] inline static M accept(const Cand& c, B upper);
};

template <class Arch>
auto MollerTest<Arch>::broadcast(const PreparedRay& r) -> Rays {
  return broadcast_ray_lanes<Arch>(r.ray);
}

template <class Arch>
template <int K>
void MollerTest<Arch>::prepare(const RayPacket<K>& rays, PreparedPacket<K>& out) {
  out.rays = rays;
}

template <class Arch>
template <int K>
auto MollerTest<Arch>::load(const PreparedPacket<K>& p, int offset) -> Rays {
  return load_ray_lanes<Arch, K>(p.rays, offset);
}

template <class Arch>
auto MollerTest<Arch>::load_block(const Block& b, const Rays&) -> Tris {
  return {B::load_aligned(b.v0[0]), B::load_aligned(b.v0[1]), B::load_aligned(b.v0[2]),
          B::load_aligned(b.e1[0]), B::load_aligned(b.e1[1]), B::load_aligned(b.e1[2]),
          B::load_aligned(b.ne2[0]), B::load_aligned(b.ne2[1]), B::load_aligned(b.ne2[2]),
          B::load_aligned(b.n[0]),  B::load_aligned(b.n[1]),  B::load_aligned(b.n[2])};
}

template <class Arch>
auto MollerTest<Arch>::broadcast_tri(const Block& b, int j, const Rays&) -> Tris {
  return {B(b.v0[0][j]), B(b.v0[1][j]), B(b.v0[2][j]), B(b.e1[0][j]), B(b.e1[1][j]), B(b.e1[2][j]),
          B(b.ne2[0][j]), B(b.ne2[1][j]), B(b.ne2[2][j]), B(b.n[0][j]),  B(b.n[1][j]),  B(b.n[2][j])};
}

template <class Arch>
auto MollerTest<Arch>::test(const Rays& r, const Tris& tri, B upper) -> Cand {
  const B zero(0.0f), one(1.0f);
  // c = p0 - org, the right-hand side of the system.
  const B cx = tri.v0x - r.ox, cy = tri.v0y - r.oy, cz = tri.v0z - r.oz;
  // det = dir . n; fails for 0, Inf and NaN (parallel ray, degenerate triangle, padding).
  const B det = r.dx * tri.nx + r.dy * tri.ny + r.dz * tri.nz;
  M valid = finite_nonzero<Arch>(det);
  // Cramer's rule with rr = dir x c: u det = -(e2 . rr), v det = e1 . rr, t det = c . n.
  // -(e2 . rr) = (-e2) . rr exactly (negation is exact), so the block stores -e2.
  const B rx = r.dy * cz - cy * r.dz;
  const B ry = r.dz * cx - cz * r.dx;
  const B rz = r.dx * cy - cx * r.dy;
  const B nu = tri.ne2x * rx + tri.ne2y * ry + tri.ne2z * rz;
  const B nv = tri.e1x * rx + tri.e1y * ry + tri.e1z * rz;
  const B nt = cx * tri.nx + cy * tri.ny + cz * tri.nz;
  if (xsimd::none(valid)) return {valid, nt, nu, nv};
  // The oracle's true divisions and its comparisons, written so NaN fails.
  const B u = nu / det;
  const B v = nv / det;
  valid = valid & (u >= zero) & (v >= zero) & (u + v <= one);
  const B t = nt / det;
  valid = valid & (r.tmin <= t) & (t < upper);
  return {valid, t, u, v};
}

template <class Arch>
auto MollerTest<Arch>::accept(const Cand& c, B upper) -> M {
  return c.valid & (c.t < upper);
}

}  // namespace volley::simd::detail
