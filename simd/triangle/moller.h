// Möller–Trumbore (1997) ray/triangle test on float lanes: the 3x3 barycentric system
// solved by Cramer's rule, division-free. The SIMD twin of src/core/triangle_moller.h:
// the same float operations in the same order, fused where the ISA has FMA (kMollerFused),
// so every lane gives the hit/miss and t, u, v of the oracle's variant for its ISA
// (intersect_moller<T, core::moller_fused_for(isa)>) bit for bit.
//
// The hit decision uses the determinants themselves, with det's sign folded in:
// u det >= 0, v det >= 0, (u + v) det <= |det|, tmin |det| <= t det < upper |det|. The
// quotients are true divisions done only for hits (block_kernels.h): t of each accepted
// lane, which must also lie in [tmin, upper) (confirm), u and v of the final winner.
#pragma once
#include <limits>

#include "simd/triangle/kernel_common.h"
#include "simd/rays/prepared_packet.h"
#include "simd/rays/prepared_ray.h"
#include "simd/triangle/triangle_blocks.h"
#include "simd/triangle/triangle_test.h"

namespace volley::simd::detail {

/// Whether the Möller–Trumbore kernels fuse their products: where the ISA has an FMA
/// instruction (AVX2, AVX-512). SSE4.2 computes unfused: emulating FMA there costs 15x.
/// The oracle's side of this rule is core::moller_fused_for (not included here: the per-ISA
/// files must not include core headers); tests/simd/test_kernels_oracle.cpp asserts that
/// the two agree for every ISA.
template <class Arch>
inline constexpr bool kMollerFused = kHasFma<Arch>;

/// Möller–Trumbore on kLanes<Arch> (ray, triangle) pairs: one ray against a block, or
/// one triangle against a packet's lanes. Reads MollerBlock<kLanes<Arch>>.
template <class Arch>
struct MollerTest : PlainRays<Arch> {
  static constexpr Decision kDecision = Decision::scaled_checked;
  static constexpr int W = kLanes<Arch>;
  using Block = MollerBlock<W>;
  using B = FloatB<Arch>;
  using M = MaskB<Arch>;

  using Rays = RayLanes<Arch>;
  /// Triangle lanes: p0, e1 = p1 - p0, ne2 = -(p2 - p0), n = e1 x (p2 - p0).
  struct Tris {
    B v0x, v0y, v0z, e1x, e1y, e1z, ne2x, ne2y, ne2z, nx, ny, nz;
  };
  /// Candidate hits, det-scaled: `valid` lanes are hit with tmin <= t < upper; t, u, v
  /// are t det, u det, v det with det's sign folded in and den = |det| (t = t / den ...),
  /// meaningful in valid lanes only.
  struct Cand {
    M valid;
    B t, u, v, den;
  };

  [[gnu::always_inline]] inline static Tris load_block(const Block& b, const Rays& r);
  /// Triangle j of a block of any width BW (packets of 16 lanes read blocks of 8 on AVX-512).
  template <int BW>
  [[gnu::always_inline]] inline static Tris broadcast_tri(const MollerBlock<BW>& b, int j, const Rays& r);
  /// The per-lane steps are always inlined into the kernel forms (one block or one triangle
  /// per call, so call overhead and batches passed through memory would dominate).
  /// EarlyExit: none here either way (the test has no branch).
  template <bool EarlyExit = true>
  [[gnu::always_inline]] inline static Cand test(const Rays& r, const Tris& tri, B upper);
  /// The lanes of `c` still hit when the upper end shrinks to `upper` (<= the one test()
  /// saw): exactly what test() would have answered for it.
  [[gnu::always_inline]] inline static M accept(const Cand& c, B upper);
  /// The valid lanes of `c` whose quotient t (= c.t / c.den) lies in [tmin, upper): the
  /// scaled range test rounds its products, the quotient once more, so t alone could land
  /// an ulp outside the range the API promises (the oracle checks the same).
  [[gnu::always_inline]] inline static M confirm(const Rays& r, const Cand& c, B t, B upper) {
    return c.valid & (r.tmin <= t) & (t < upper);
  }

 private:
  /// a b + c: one rounding when fused (the oracle's std::fma), two otherwise (Fused = false).
  [[gnu::always_inline]] inline static B mul_add(B a, B b, B c) {
    if constexpr (kMollerFused<Arch>)
      return fused_mul_add<Arch>(a, b, c);
    else
      return a * b + c;
  }
  /// a b - c d: the oracle's diff_of_products (fused: fma(a, b, -(c d))).
  [[gnu::always_inline]] inline static B diff_of_products(B a, B b, B c, B d) {
    if constexpr (kMollerFused<Arch>)
      return fused_mul_sub<Arch>(a, b, c * d);
    else
      return a * b - c * d;
  }
  /// ax bx + ay by + az bz, left to right: the oracle's dot3.
  [[gnu::always_inline]] inline static B dot3(B ax, B ay, B az, B bx, B by, B bz) {
    return mul_add(az, bz, mul_add(ay, by, ax * bx));
  }
};

template <class Arch>
auto MollerTest<Arch>::load_block(const Block& b, const Rays&) -> Tris {
  return {B::load_aligned(b.v0[0]), B::load_aligned(b.v0[1]), B::load_aligned(b.v0[2]),
          B::load_aligned(b.e1[0]), B::load_aligned(b.e1[1]), B::load_aligned(b.e1[2]),
          B::load_aligned(b.ne2[0]), B::load_aligned(b.ne2[1]), B::load_aligned(b.ne2[2]),
          B::load_aligned(b.n[0]),  B::load_aligned(b.n[1]),  B::load_aligned(b.n[2])};
}

template <class Arch>
template <int BW>
auto MollerTest<Arch>::broadcast_tri(const MollerBlock<BW>& b, int j, const Rays&) -> Tris {
  return {B(b.v0[0][j]), B(b.v0[1][j]), B(b.v0[2][j]), B(b.e1[0][j]), B(b.e1[1][j]), B(b.e1[2][j]),
          B(b.ne2[0][j]), B(b.ne2[1][j]), B(b.ne2[2][j]), B(b.n[0][j]),  B(b.n[1][j]),  B(b.n[2][j])};
}

template <class Arch>
template <bool EarlyExit>
auto MollerTest<Arch>::test(const Rays& r, const Tris& tri, B upper) -> Cand {
  const B zero(0.0f);
  // c = p0 - org, the right-hand side of the system.
  const B cx = tri.v0x - r.ox, cy = tri.v0y - r.oy, cz = tri.v0z - r.oz;
  // det = dir . n; rr = dir x c; Cramer: u det = (-e2) . rr, v det = e1 . rr, t det = c . n.
  const B det = dot3(r.dx, r.dy, r.dz, tri.nx, tri.ny, tri.nz);
  const B rx = diff_of_products(r.dy, cz, cy, r.dz);
  const B ry = diff_of_products(r.dz, cx, cz, r.dx);
  const B rz = diff_of_products(r.dx, cy, cx, r.dy);
  const B un = dot3(tri.ne2x, tri.ne2y, tri.ne2z, rx, ry, rz);
  const B vn = dot3(tri.e1x, tri.e1y, tri.e1z, rx, ry, rz);
  const B tn = dot3(cx, cy, cz, tri.nx, tri.ny, tri.nz);
  // Fold det's sign in (negation is exact): the tests below are those of u, v, t >= ...
  const B sign = det & B(-0.0f);
  const B den = det ^ sign;
  const B u = un ^ sign, v = vn ^ sign, t = tn ^ sign;
  // det finite and nonzero (parallel ray, degenerate triangle, padding and NaN fail);
  // every comparison is false for NaN. Without mask registers the test reuses den
  // (finite_nonzero would take abs(det) again).
  M valid;
  if constexpr (kHasMaskRegisters<Arch>)
    valid = finite_nonzero<Arch>(det);
  else
    valid = (den > zero) & (den <= B(std::numeric_limits<float>::max()));
  valid = valid & (u >= zero) & (v >= zero) & (u + v <= den);
  valid = valid & (r.tmin * den <= t) & (t < upper * den);
  return {valid, t, u, v, den};
}

template <class Arch>
auto MollerTest<Arch>::accept(const Cand& c, B upper) -> M {
  return c.valid & (c.t < upper * c.den);
}

}  // namespace volley::simd::detail
