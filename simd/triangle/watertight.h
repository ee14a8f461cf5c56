// Watertight ray/triangle test (Woop, Benthin & Wald 2013, "Watertight Ray/Triangle
// Intersection", JCGT 2(1)) on float lanes. The SIMD twin of
// src/core/triangle_watertight.h: the same float operations in the same order, so every
// lane gives the hit/miss and t, u, v of the oracle's variant for its ISA bit for bit
// (core::watertight_fused_for: the shear and the depth sum fuse where the ISA has FMA).
//
// Watertightness needs the edge functions a*b - c*d with both products rounded: the
// per-ISA files are compiled with -ffp-contract=off and xsimd's operators map to plain
// multiply and subtract instructions, so the edge functions never fuse; the only fused
// operations are the explicit ones (kFused), per vertex, which cannot open a crack
// (tests/simd/test_watertight.cpp checks it on closed meshes with the shipped flags).
// A lane whose float edge function is exactly 0 is recomputed in double (exact products),
// one lane at a time; watertight_fallback_lanes counts them.
//
// Division-free decision (as moller.h): test() passes the lanes whose scaled distance
// t det lies in [tmin, upper] |det| (a conservative prefilter, the oracle's); the kernel
// forms divide only those candidates and confirm tmin <= t < upper on the quotient, which
// is what decides, as in the oracle. u and v are divided once, for the final winner.
// Any hit needs no division at all for lanes that sure_hit() proves in range (all but
// those within ~16 ulps of either end); the rest go through the quotient as above.
#pragma once
#include <immintrin.h>

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "core/kernel_constants.h"
#include "core/triangle_watertight.h"
#include "simd/triangle/kernel_common.h"
#include "simd/rays/prepared_packet.h"
#include "simd/rays/prepared_ray.h"
#include "simd/triangle/triangle_blocks.h"
#include "simd/triangle/triangle_test.h"
#include "simd/triangle/watertight_stats.h"

namespace volley::simd::detail {

/// Watertight test on kLanes<Arch> (ray, triangle) pairs. Reads WatertightBlock<kLanes<Arch>>.
/// Zero-area triangles are made NaN lanes when the block is built (the oracle's first
/// check), so the kernel never sees one.
/// Crossing: the exactly-once rule of the crossing queries (core::intersect_watertight's
/// Crossing): lanes with an exactly-zero edge function are decided in the cold fallback by
/// core::crossing_inside; the hot path is the same.
template <class Arch, bool Crossing = false>
struct WatertightTest {
  /// The candidates' quotients decide (the kernel forms call confirm() on them).
  static constexpr Decision kDecision = Decision::quotient;
  static constexpr int W = kLanes<Arch>;
  using Block = WatertightBlock<W>;
  using B = FloatB<Arch>;
  using M = MaskB<Arch>;

  /// Ray lanes with their Woop shear. The axis permutation is either the same for all
  /// lanes (`uniform`, always so for a single ray; then kx, ky, kz apply) or per lane
  /// (masks x0: kx == 0, x1: kx == 1, likewise y0, y1 for ky and z0, z1 for kz).
  struct Rays {
    B o[3];                    // origin x y z (per-lane permutation)
    B okx, oky, okz;           // origin along kx, ky, kz (per lane when not uniform)
    IntB<Arch> ikx, iky, ikz;  // kx, ky, kz per lane (not uniform; AVX2, AVX-512)
    B tmin;
    B tmin_lo;     // lower end of the prefilter, tmin - |tmin| core::kScaledPad<float> (then times
                   // |det|); NaN where |sz| > 0 fails: an infinite dir[kz] (sz = 0)
                   // or a NaN one never hits
    B sx, sy, sz;  // shear dir[kx]/dir[kz], dir[ky]/dir[kz], 1/dir[kz]
    bool uniform;
    int kx, ky, kz;
    M x0, x1, y0, y1, z0, z1;
  };
  /// Triangle lanes: the vertices relative to the ray origin, permuted: a = p0 - org
  /// taken along axes kx, ky, kz; likewise b (p1) and c (p2).
  struct Tris {
    B akx, aky, akz, bkx, bky, bkz, ckx, cky, ckz;
  };
  /// Candidate hits, det-scaled: `valid` lanes pass the scaled range prefilter; the hits
  /// among them are the lanes where confirm() holds for the quotient t / den. t, u, v are
  /// t det, u det, v det and den = det (t = t / den ...), meaningful in valid lanes only.
  struct Cand {
    M valid;
    B t, u, v, den;
  };
  /// The edge functions U, V, W of the lanes.
  struct Edges {
    B u, v, w;
  };

  [[gnu::always_inline]] inline static Rays broadcast(const PreparedRay& r);
  /// The oracle's make_woop_ray for every lane, and whether the active lanes share axes.
  template <int K>
  static void prepare(const RayPacket<K>& rays, PreparedPacket<K>& out);
  template <int K>
  [[gnu::always_inline]] inline static Rays load(const PreparedPacket<K>& p, int offset);
  /// Ray lanes from their origins, tmin and shear, the axes `uk` shared by every lane...
  [[gnu::always_inline]] inline static Rays lanes(const B o[3], B tmin, const B s[3], const std::int32_t uk[3]);
  /// ... or per lane (kx, ky, kz), as load() builds them from a prepared packet.
  [[gnu::always_inline]] inline static Rays lanes(const B o[3], B tmin, const B s[3], const IntB<Arch> k[3]);
  [[gnu::always_inline]] inline static Tris load_block(const Block& b, const Rays& r);
  /// What both lanes() forms share.
  [[gnu::always_inline]] inline static Rays lanes(const B o[3], B tmin, const B s[3]);
  /// Triangle j of a block of any width BW (packets of 16 lanes read blocks of 8 on AVX-512).
  template <int BW>
  [[gnu::always_inline]] inline static Tris broadcast_tri(const WatertightBlock<BW>& b, int j, const Rays& r);
  /// broadcast_tri() for rays known to be uniform.
  template <int BW>
  [[gnu::always_inline]] inline static Tris broadcast_uniform(const WatertightBlock<BW>& b, int j, const Rays& r);

  /// The any-hit forms' triangle lanes: broadcast_uniform() negated, origin minus vertex,
  /// for rays from negated() (the z scale negated too). AVX-512 folds a broadcast from
  /// memory into an instruction only as its second operand, so this is one instruction
  /// per coordinate where vertex minus origin takes two (perf/reports/rays.md, "fewer instructions per triangle test").
  /// Every decision is the same bit for bit: each nonzero value of the test is the
  /// original's, negated or not (rounding is symmetric; the edge functions and the
  /// depth terms are products of two negated factors), and an exact zero may differ
  /// only in its sign, which no comparison sees. A reported t, u or v could show such a
  /// zero's sign, so the closest-hit and crossing forms keep broadcast_uniform().
  template <int BW>
  [[gnu::always_inline]] inline static Tris broadcast_negated(const WatertightBlock<BW>& b, int j, const Rays& r) {
    const int kx = r.kx, ky = r.ky, kz = r.kz;
    return {r.okx - B(b.p[0][kx][j]), r.oky - B(b.p[0][ky][j]), r.okz - B(b.p[0][kz][j]),
            r.okx - B(b.p[1][kx][j]), r.oky - B(b.p[1][ky][j]), r.okz - B(b.p[1][kz][j]),
            r.okx - B(b.p[2][kx][j]), r.oky - B(b.p[2][ky][j]), r.okz - B(b.p[2][kz][j])};
  }
  /// The rays for broadcast_negated(): the z scale negated.
  [[gnu::always_inline]] inline static Rays negated(Rays r) {
    r.sz = -r.sz;
    return r;
  }
  /// The any-hit forms' pair for uniform rays: negated where the broadcast folds (AVX-512,
  /// 16 lanes), broadcast_uniform() elsewhere (AVX2 has no broadcast operand to gain).
  static constexpr bool kNegatedAnyHit = W == 16;
  [[gnu::always_inline]] inline static decltype(auto) any_hit_rays(const Rays& r) {
    if constexpr (kNegatedAnyHit)
      return negated(r);
    else
      return (r);  // (a reference: a copy of the lanes measured 0.7% more instructions)
  }
  template <int BW>
  [[gnu::always_inline]] inline static Tris any_hit_uniform(const WatertightBlock<BW>& b, int j, const Rays& r) {
    if constexpr (kNegatedAnyHit)
      return broadcast_negated(b, j, r);
    else
      return broadcast_uniform(b, j, r);
  }
  /// The per-lane steps are always inlined into the kernel forms (one block or one triangle
  /// per call, so call overhead and batches passed through memory would dominate).
  /// EarlyExit: return as soon as no lane passes the edge and det tests (RayBlockKernels::intersect_inline).
  template <bool EarlyExit = true>
  [[gnu::always_inline]] inline static Cand test(const Rays& r, const Tris& tri, B upper);

  /// The sheared vertices' edge functions U, V, W and the lanes whose signs do not mix
  /// (`inside`): the first steps of test() and depth().
  [[gnu::always_inline]] inline static Edges edges(const Rays& r, const Tris& tri, M& inside);
  /// Lanes past the edge and det tests (`inside`; the rest is meaningful there only, and
  /// unset when no lane is) with their scaled distance: t det, with det's sign folded in (ts_s).
  struct Depth {
    M inside;
    B ts, ts_s, det, ad, u, v;
  };
  /// test()'s steps up to t det, for the any-hit forms. Both share edges(); the rest is
  /// written out twice on purpose: test() built on depth() ran more instructions
  /// (perf/reports/traversal.md).
  /// EarlyExit: return as soon as no lane is inside (the rest unset).
  template <bool EarlyExit = true>
  [[gnu::always_inline]] inline static Depth depth(const Rays& r, const Tris& tri);
  /// test()'s prefilter on the inside lanes of `d`.
  [[gnu::always_inline]] inline static M prefilter(const Rays& r, const Depth& d, B upper) {
    return and_cmp<Cmp::le, Arch>(and_cmp<Cmp::ge, Arch>(d.inside, d.ts_s, r.tmin_lo * d.ad), d.ts_s, upper * d.ad);
  }

  /// Per-lane factors of sure_hit(): lo for tmin, hi for the upper end.
  struct SureRange {
    B lo, hi;
  };
  [[gnu::always_inline]] inline static SureRange sure_range(B tmin, B upper);
  /// The same for one ray, from its prepared factors (core::sure_quotient_range).
  [[gnu::always_inline]] inline static SureRange sure_range(const PreparedRay& r) {
    return {B(r.sure[0]), B(r.sure[1])};
  }
  /// Inside lanes that the oracle's quotient test certainly accepts (tmin <= t < upper),
  /// decided on det-scaled values with no division: fl(lo |det|) < t det < fl(hi |det|)
  /// (strict). Lanes near either end (about 16 ulps) are left to the quotient.
  [[gnu::always_inline]] inline static M sure_hit(const Depth& d, const SureRange& s) {
    return and_cmp<Cmp::lt, Arch>(and_cmp<Cmp::gt, Arch>(d.inside, d.ts_s, s.lo * d.ad), d.ts_s, s.hi * d.ad);
  }
  /// The lanes of `c` hit, given their quotient t = c.t / c.den: tmin <= t < upper, the
  /// oracle's final test.
  [[gnu::always_inline]] inline static M confirm(const Rays& r, const Cand& c, B t, B upper) {
    return and_cmp<Cmp::lt, Arch>(and_cmp<Cmp::le, Arch>(c.valid, r.tmin, t), t, upper);
  }
  /// Whether this ISA's lanes fuse the shear and the depth sum (core::watertight_fused_for:
  /// where the ISA has FMA); the edge functions never fuse.
  static constexpr bool kFused = kHasFma<Arch>;
  /// A sheared coordinate, p - s z.
  [[gnu::always_inline]] inline static B shear(B p, B s, B z) {
    if constexpr (kFused)
      return fused_neg_mul_add<Arch>(s, z, p);
    else
      return p - s * z;
  }
  /// The scaled distance U az + V bz + W cz.
  [[gnu::always_inline]] inline static B depth_sum(const Edges& e, B az, B bz, B cz) {
    if constexpr (kFused)
      return fused_mul_add<Arch>(e.w, cz, fused_mul_add<Arch>(e.v, bz, e.u * az));
    else
      return e.u * az + e.v * bz + e.w * cz;
  }
  /// The sheared x and y of the three vertices.
  struct Sheared {
    B ax, ay, bx, by, cx, cy;
  };
  /// Shears the vertices (so the ray runs along +z; the z scaling is deferred to the depth
  /// test) and returns their 2D edge functions at the origin, both products rounded: the
  /// first steps of edges() and of the AVX-512VL block test (watertight_vl.h).
  [[gnu::always_inline]] inline static Edges edge_functions(const Rays& r, const Tris& tri, Sheared& s) {
    s = {shear(tri.akx, r.sx, tri.akz), shear(tri.aky, r.sy, tri.akz), shear(tri.bkx, r.sx, tri.bkz),
         shear(tri.bky, r.sy, tri.bkz), shear(tri.ckx, r.sx, tri.ckz), shear(tri.cky, r.sy, tri.ckz)};
    return {s.cx * s.by - s.cy * s.bx, s.ax * s.cy - s.ay * s.cx, s.bx * s.ay - s.by * s.ax};
  }
  /// Recomputes the edge functions of the lanes with a zero one in double (exact
  /// products) and returns all three. Out of line and cold: the test stays small enough
  /// to inline, and its hot path keeps the edge functions in registers.
  /// Crossing: `crossing_in` gets the lanes inside by core::crossing_inside (every lane:
  /// those with no zero edge function by their signs).
  [[gnu::noinline, gnu::cold]] static Edges fallback(B ax, B ay, B bx, B by, B cx, B cy, B eu, B ev, B ew,
                                                     std::uint32_t* crossing_in = nullptr);
};

template <class Arch, bool Crossing>
auto WatertightTest<Arch, Crossing>::edges(const Rays& r, const Tris& tri, M& inside) -> Edges {
  const B zero(0.0f);
  Sheared s;
  Edges e = edge_functions(r, tri, s);
  // Mixed signs: the origin is outside (both facings accepted). With no edge function
  // exactly 0 the signs are the sign bits (a NaN lane fails on det below). An exact 0 may
  // hide a nonzero one: those lanes are redone in double, and signs are then compared as
  // the oracle does, where 0 goes with either sign.
  if (all_nonzero<Arch>(e.u, e.v, e.w)) [[likely]] {
    inside = same_sign_bit<Arch>(e.u, e.v, e.w);
  } else {
    if constexpr (Crossing) {
      std::uint32_t in = 0;
      e = fallback(s.ax, s.ay, s.bx, s.by, s.cx, s.cy, e.u, e.v, e.w, &in);
      inside = mask_from_bits<Arch>(in);
    } else {
      e = fallback(s.ax, s.ay, s.bx, s.by, s.cx, s.cy, e.u, e.v, e.w);
      inside = ~(((e.u < zero) | (e.v < zero) | (e.w < zero)) & ((e.u > zero) | (e.v > zero) | (e.w > zero)));
    }
  }
  return e;
}

template <class Arch, bool Crossing>
template <bool EarlyExit>
auto WatertightTest<Arch, Crossing>::depth(const Rays& r, const Tris& tri) -> Depth {
  M inside;
  Edges e = edges(r, tri, inside);
  // det NaN or Inf fails here; det = 0 (the ray lies in the plane) fails on its quotient
  // t = 0 / 0 (the prefilter passes it only with t det = 0), so no test of its own.
  Depth d;
  d.det = e.u + e.v + e.w;
  d.ad = xsimd::abs(d.det);
  d.inside = and_cmp<Cmp::le, Arch>(inside, d.ad, B(std::numeric_limits<float>::max()));
  d.u = e.v, d.v = e.w;
  if (EarlyExit && xsimd::none(d.inside)) return d;
  const B az = r.sz * tri.akz, bz = r.sz * tri.bkz, cz = r.sz * tri.ckz;
  d.ts = depth_sum(e, az, bz, cz);
  d.ts_s = d.ts ^ (d.det & B(-0.0f));
  return d;
}

template <class Arch, bool Crossing>
template <bool EarlyExit>
auto WatertightTest<Arch, Crossing>::test(const Rays& r, const Tris& tri, B upper) -> Cand {
  M inside;
  Edges e = edges(r, tri, inside);
  // det NaN or Inf fails here; det = 0 (the ray lies in the plane) fails on its quotient
  // t = 0 / 0 (the prefilter passes it only with t det = 0), so no test of its own.
  const B det = e.u + e.v + e.w;
  const B ad = xsimd::abs(det);
  M valid = and_cmp<Cmp::le, Arch>(inside, ad, B(std::numeric_limits<float>::max()));
  if (EarlyExit && xsimd::none(valid)) return {valid, det, det, det, det};
  // Scaled distance t det against [tmin, upper] |det| with det's sign folded in: the
  // oracle's prefilter, which never rejects a lane the quotient would accept.
  const B az = r.sz * tri.akz, bz = r.sz * tri.bkz, cz = r.sz * tri.ckz;
  const B ts = depth_sum(e, az, bz, cz);
  const B ts_s = ts ^ (det & B(-0.0f));
  valid = and_cmp<Cmp::le, Arch>(and_cmp<Cmp::ge, Arch>(valid, ts_s, r.tmin_lo * ad), ts_s, upper * ad);
  return {valid, ts, e.v, e.w, det};
}

template <class Arch, bool Crossing>
auto WatertightTest<Arch, Crossing>::sure_range(B tmin, B upper) -> SureRange {
  // Why these are sure (q = t det / |det| exactly, t = fl(q); rounding is monotonic):
  //  - upper end, hi = fl(min(upper, FLT_MAX) (1 - 8 eps)) for upper >= FLT_MIN (else
  //    -inf: nothing sure). t det < fl(hi |det|) gives q < hi / (1 - eps/2) (normal
  //    product) or q < hi (subnormal one: floats there are 2^-149 apart, twice the
  //    product's rounding error; an overflowed one: t det <= FLT_MAX). Either way
  //    q <= pred(upper), so t < upper.
  //  - lower end, lo = 0 for tmin <= 0 (t det > 0: q > 0); for tmin > 0,
  //    lo = fl(max(tmin, FLT_MIN) (1 + 8 eps)), and q > tmin likewise; NaN tmin: +inf.
  //  - det = 0 lanes: both bounds are 0 or NaN, so the strict tests fail.
  const B fmin(std::numeric_limits<float>::min()), fmax(std::numeric_limits<float>::max()), zero(0.0f);
  const B inf(std::numeric_limits<float>::infinity());
  constexpr float kEps = std::numeric_limits<float>::epsilon();
  // (selects, not xsimd::max / min: GCC 12 warns in their AVX-512 forms)
  const B lo_pos = xsimd::select(tmin > fmin, tmin, fmin) * B(1.0f + 8 * kEps);
  const B lo = xsimd::select(tmin > zero, lo_pos, xsimd::select(tmin <= zero, zero, inf));
  const B hi = xsimd::select(upper >= fmin, xsimd::select(upper < fmax, upper, fmax) * B(1.0f - 8 * kEps), -inf);
  return {lo, hi};
}

template <class Arch, bool Crossing>
auto WatertightTest<Arch, Crossing>::fallback(B ax, B ay, B bx, B by, B cx, B cy, B eu, B ev, B ew,
                                              std::uint32_t* crossing_in) -> Edges {
  const B zero(0.0f);
  std::uint32_t lanes = bits_from_mask<Arch>((eu == zero) | (ev == zero) | (ew == zero));
  if (crossing_in) *crossing_in = bits_from_mask<Arch>(same_sign_bit<Arch>(eu, ev, ew)) & ~lanes;
  alignas(64) float fax[W], fay[W], fbx[W], fby[W], fcx[W], fcy[W], feu[W], fev[W], few[W];
  ax.store_aligned(fax), ay.store_aligned(fay), bx.store_aligned(fbx), by.store_aligned(fby);
  cx.store_aligned(fcx), cy.store_aligned(fcy);
  eu.store_aligned(feu), ev.store_aligned(fev), ew.store_aligned(few);
  watertight_fallback_lanes += static_cast<std::uint64_t>(std::popcount(lanes));
  for (; lanes != 0; lanes &= lanes - 1) {
    // Float products are exact in double, so only the subtraction rounds (and fusing it
    // would change nothing).
    const int i = std::countr_zero(lanes);
    const double du = double(fcx[i]) * double(fby[i]) - double(fcy[i]) * double(fbx[i]);
    const double dv = double(fax[i]) * double(fcy[i]) - double(fay[i]) * double(fcx[i]);
    const double dw = double(fbx[i]) * double(fay[i]) - double(fby[i]) * double(fax[i]);
    feu[i] = float(du), fev[i] = float(dv), few[i] = float(dw);
    if (crossing_in && core::crossing_inside(du, dv, dw, fax[i], fay[i], fbx[i], fby[i], fcx[i], fcy[i]))
      *crossing_in |= 1u << i;
  }
  return {B::load_aligned(feu), B::load_aligned(fev), B::load_aligned(few)};
}

}  // namespace volley::simd::detail

#include "simd/triangle/watertight_lanes.h"  // (the ray and triangle lanes: the rest of WatertightTest)
#include "simd/triangle/watertight_vl.h"     // (its block test in AVX-512VL mask registers)
