// Möller–Trumbore (1997) ray/triangle test on float lanes: the 3x3 barycentric system
// solved by Cramer's rule. The SIMD twin of src/core/triangle_moller.h: the same float
// operations in the same order (no FMA, true divisions), so every lane gives the
// oracle's hit/miss and t, u, v bit for bit.
#pragma once
#include <limits>

#include "simd/kernel_common.h"
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
  /// Triangle lanes: p0, e1 = p1 - p0, e2 = p2 - p0, n = e1 x e2.
  struct Tris {
    B v0x, v0y, v0z, e1x, e1y, e1z, e2x, e2y, e2z, nx, ny, nz;
  };
  /// Candidate hits: `valid` lanes are hit with tmin <= t < upper; t, u, v are
  /// meaningful in those lanes only.
  struct Cand {
    M valid;
    B t, u, v;
  };

  static Rays broadcast(const PreparedRay& r);
  template <int K>
  static Rays load(const RayPacket<K>& p, int offset);
  static Tris load_block(const Block& b, const Rays& r);
  static Tris broadcast_tri(const Block& b, int j, const Rays& r);
  static Cand test(const Rays& r, const Tris& tri, B upper);
  /// The lanes of `c` still hit when the upper end shrinks to `upper` (<= the one test()
  /// saw): exactly what test() would have answered for it.
  static M accept(const Cand& c, B upper);
};

template <class Arch>
auto MollerTest<Arch>::broadcast(const PreparedRay& r) -> Rays {
  return broadcast_ray_lanes<Arch>(r.ray);
}

template <class Arch>
template <int K>
auto MollerTest<Arch>::load(const RayPacket<K>& p, int offset) -> Rays {
  return load_ray_lanes<Arch, K>(p, offset);
}

template <class Arch>
auto MollerTest<Arch>::load_block(const Block& b, const Rays&) -> Tris {
  return {B::load_aligned(b.v0[0]), B::load_aligned(b.v0[1]), B::load_aligned(b.v0[2]),
          B::load_aligned(b.e1[0]), B::load_aligned(b.e1[1]), B::load_aligned(b.e1[2]),
          B::load_aligned(b.e2[0]), B::load_aligned(b.e2[1]), B::load_aligned(b.e2[2]),
          B::load_aligned(b.n[0]),  B::load_aligned(b.n[1]),  B::load_aligned(b.n[2])};
}

template <class Arch>
auto MollerTest<Arch>::broadcast_tri(const Block& b, int j, const Rays&) -> Tris {
  return {B(b.v0[0][j]), B(b.v0[1][j]), B(b.v0[2][j]), B(b.e1[0][j]), B(b.e1[1][j]), B(b.e1[2][j]),
          B(b.e2[0][j]), B(b.e2[1][j]), B(b.e2[2][j]), B(b.n[0][j]),  B(b.n[1][j]),  B(b.n[2][j])};
}

template <class Arch>
auto MollerTest<Arch>::test(const Rays& r, const Tris& tri, B upper) -> Cand {
  const B zero(0.0f), one(1.0f), max(std::numeric_limits<float>::max());
  // c = p0 - org, the right-hand side of the system.
  const B cx = tri.v0x - r.ox, cy = tri.v0y - r.oy, cz = tri.v0z - r.oz;
  // det = dir . n; fails for 0, Inf and NaN (parallel ray, degenerate triangle, padding).
  const B det = r.dx * tri.nx + r.dy * tri.ny + r.dz * tri.nz;
  const B ad = xsimd::abs(det);
  M valid = (ad > zero) & (ad <= max);
  // Cramer's rule with rr = dir x c: u det = -(e2 . rr), v det = e1 . rr, t det = c . n.
  const B rx = r.dy * cz - cy * r.dz;
  const B ry = r.dz * cx - cz * r.dx;
  const B rz = r.dx * cy - cx * r.dy;
  const B nu = -(tri.e2x * rx + tri.e2y * ry + tri.e2z * rz);
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
