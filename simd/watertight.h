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
#include "simd/kernel_common.h"
#include "simd/prepared_packet.h"
#include "simd/prepared_ray.h"
#include "simd/triangle_blocks.h"
#include "simd/watertight_stats.h"

namespace volley::simd::detail {

/// Watertight test on kLanes<Arch> (ray, triangle) pairs. Reads WatertightBlock<kLanes<Arch>>.
/// Zero-area triangles are made NaN lanes when the block is built (the oracle's first
/// check), so the kernel never sees one.
template <class Arch>
struct WatertightTest {
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
  /// The candidates' quotients decide (the kernel forms call confirm() on them).
  static constexpr bool kQuotientDecides = true;

  [[gnu::always_inline]] inline static Rays broadcast(const PreparedRay& r);
  /// The oracle's make_woop_ray for every lane, and whether the active lanes share axes.
  template <int K>
  static void prepare(const RayPacket<K>& rays, PreparedPacket<K>& out);
  template <int K>
  [[gnu::always_inline]] inline static Rays load(const PreparedPacket<K>& p, int offset);
  [[gnu::always_inline]] inline static Tris load_block(const Block& b, const Rays& r);
  /// Triangle j of a block of any width BW (packets of 16 lanes read blocks of 8 on AVX-512).
  template <int BW>
  [[gnu::always_inline]] inline static Tris broadcast_tri(const WatertightBlock<BW>& b, int j, const Rays& r);
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
  /// written out twice on purpose: with test() built on depth(), the closest-hit forms ran
  /// 4-9% more instructions (AVX2, callgrind).
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
  /// test<false>() for one ray against an 8-wide block on AVX-512 (Avx512Ymm), written with
  /// AVX-512VL intrinsics: compares into mask registers (the xsimd AVX2 code it stands for
  /// uses VEX compares on ymm0-15 and vector masks). The same operations in the same order,
  /// so the same lanes and values. Returns false, computing nothing, when some lane has an
  /// edge function exactly 0 (test() redoes those in double).
  [[gnu::always_inline]] inline static bool test_vl(const Rays& r, const Tris& tri, B upper, Cand& out,
                                                    std::uint32_t& bits);
  /// The sheared x and y of the three vertices.
  struct Sheared {
    B ax, ay, bx, by, cx, cy;
  };
  /// Shears the vertices (so the ray runs along +z; the z scaling is deferred to the depth
  /// test) and returns their 2D edge functions at the origin, both products rounded: the
  /// first steps of edges() and test_vl().
  [[gnu::always_inline]] inline static Edges edge_functions(const Rays& r, const Tris& tri, Sheared& s) {
    s = {shear(tri.akx, r.sx, tri.akz), shear(tri.aky, r.sy, tri.akz), shear(tri.bkx, r.sx, tri.bkz),
         shear(tri.bky, r.sy, tri.bkz), shear(tri.ckx, r.sx, tri.ckz), shear(tri.cky, r.sy, tri.ckz)};
    return {s.cx * s.by - s.cy * s.bx, s.ax * s.cy - s.ay * s.cx, s.bx * s.ay - s.by * s.ax};
  }
  /// Recomputes the edge functions of the lanes with a zero one in double (exact
  /// products) and returns all three. Out of line and cold: the test stays small enough
  /// to inline, and its hot path keeps the edge functions in registers.
  [[gnu::noinline, gnu::cold]] static Edges fallback(B ax, B ay, B bx, B by, B cx, B cy, B eu, B ev, B ew);
};

template <class Arch>
auto WatertightTest<Arch>::broadcast(const PreparedRay& r) -> Rays {
  Rays out;
  for (int i = 0; i < 3; ++i) out.o[i] = B(r.ray.org[i]);
  out.okx = B(r.ray.org[r.k[0]]);
  out.oky = B(r.ray.org[r.k[1]]);
  out.okz = B(r.ray.org[r.k[2]]);
  out.tmin = B(r.ray.tmin);
  out.sx = B(r.s[0]);
  out.sy = B(r.s[1]);
  out.sz = B(r.s[2]);
  const float tmin = r.ray.tmin;
  out.tmin_lo = B(std::abs(r.s[2]) > 0.0f ? tmin - std::abs(tmin) * core::kScaledPad<float>
                                          : std::numeric_limits<float>::quiet_NaN());
  out.uniform = true;
  out.kx = r.k[0];
  out.ky = r.k[1];
  out.kz = r.k[2];
  return out;
}

template <class Arch>
template <int K>
void WatertightTest<Arch>::prepare(const RayPacket<K>& rays, PreparedPacket<K>& out) {
  using I = IntB<Arch>;
  out.rays = rays;
  std::uint32_t axes_seen = 0;  // bit (kz * 2 + swapped) of every active lane
  for (int c = 0; c < K; c += W) {
    const B dx = B::load_aligned(rays.dx + c), dy = B::load_aligned(rays.dy + c), dz = B::load_aligned(rays.dz + c);
    // make_woop_ray per lane: kz = axis of the largest |dir| (ties: lowest axis), kx and
    // ky the next two cyclically, swapped when dir[kz] < 0 (keeps the winding).
    const B ax = xsimd::abs(dx), ay = xsimd::abs(dy), az = xsimd::abs(dz);
    const M x_ge_y = ax >= ay;
    const M z0 = x_ge_y & (ax >= az);
    const M z1 = ~x_ge_y & (ay >= az);
    const M z2 = ~(z0 | z1);
    const B dkz = xsimd::select(z0, dx, xsimd::select(z1, dy, dz));
    const M neg = dkz < B(0.0f);
    // Unswapped: kx = kz + 1, ky = kz + 2 (mod 3); swapped: exchanged.
    const M x0 = (neg & z1) | (~neg & z2), x1 = (neg & z2) | (~neg & z0);
    const M y0 = (neg & z2) | (~neg & z1), y1 = (neg & z0) | (~neg & z2);
    const B dkx = xsimd::select(x0, dx, xsimd::select(x1, dy, dz));
    const B dky = xsimd::select(y0, dx, xsimd::select(y1, dy, dz));
    (dkx / dkz).store_aligned(out.s[0] + c);
    (dky / dkz).store_aligned(out.s[1] + c);
    (B(1.0f) / dkz).store_aligned(out.s[2] + c);
    const auto axis = [](M is0, M is1) {
      return xsimd::select(xsimd::bool_cast(is0), I(0), xsimd::select(xsimd::bool_cast(is1), I(1), I(2)));
    };
    axis(x0, x1).store_aligned(out.k[0] + c);
    axis(y0, y1).store_aligned(out.k[1] + c);
    axis(z0, z1).store_aligned(out.k[2] + c);
    const std::uint32_t act = (rays.active >> c) & ((2u << (W - 1)) - 1u);
    const std::uint32_t b0 = bits_from_mask<Arch>(z0) & act, b1 = bits_from_mask<Arch>(z1) & act,
                        b2 = bits_from_mask<Arch>(z2) & act, bn = bits_from_mask<Arch>(neg) & act;
    axes_seen |= (b0 & ~bn ? 1u : 0u) | (b0 & bn ? 2u : 0u) | (b1 & ~bn ? 4u : 0u) | (b1 & bn ? 8u : 0u) |
                 (b2 & ~bn ? 16u : 0u) | (b2 & bn ? 32u : 0u);
  }
  // One permutation for all active lanes (the common case of a coherent packet): the
  // triangle's coordinates are then picked by index instead of per-lane selects.
  out.uniform = std::popcount(axes_seen) <= 1;
  if (out.uniform) {
    const int kz = axes_seen & 3u ? 0 : axes_seen & 12u ? 1 : 2;
    const bool swapped = (axes_seen & 42u) != 0;
    out.uk[2] = kz;
    out.uk[0] = kz == 2 ? 0 : kz + 1;
    out.uk[1] = out.uk[0] == 2 ? 0 : out.uk[0] + 1;
    if (swapped) {
      const int k = out.uk[0];
      out.uk[0] = out.uk[1];
      out.uk[1] = k;
    }
  }
}

template <class Arch>
template <int K>
auto WatertightTest<Arch>::load(const PreparedPacket<K>& p, int offset) -> Rays {
  using I = IntB<Arch>;
  Rays out;
  out.o[0] = B::load_aligned(p.rays.ox + offset);
  out.o[1] = B::load_aligned(p.rays.oy + offset);
  out.o[2] = B::load_aligned(p.rays.oz + offset);
  out.tmin = B::load_aligned(p.rays.tmin + offset);
  out.sx = B::load_aligned(p.s[0] + offset);
  out.sy = B::load_aligned(p.s[1] + offset);
  out.sz = B::load_aligned(p.s[2] + offset);
  out.tmin_lo =
      xsimd::select(xsimd::abs(out.sz) > B(0.0f), out.tmin - xsimd::abs(out.tmin) * B(core::kScaledPad<float>),
                    B(std::numeric_limits<float>::quiet_NaN()));
  out.uniform = p.uniform != 0;
  if (out.uniform) {
    out.kx = p.uk[0];
    out.ky = p.uk[1];
    out.kz = p.uk[2];
    out.okx = out.o[out.kx];
    out.oky = out.o[out.ky];
    out.okz = out.o[out.kz];
  } else {
    const I kx = I::load_aligned(p.k[0] + offset), ky = I::load_aligned(p.k[1] + offset),
            kz = I::load_aligned(p.k[2] + offset);
    out.x0 = xsimd::bool_cast(kx == I(0)), out.x1 = xsimd::bool_cast(kx == I(1));
    out.y0 = xsimd::bool_cast(ky == I(0)), out.y1 = xsimd::bool_cast(ky == I(1));
    out.z0 = xsimd::bool_cast(kz == I(0)), out.z1 = xsimd::bool_cast(kz == I(1));
    out.ikx = kx, out.iky = ky, out.ikz = kz;
    out.okx = xsimd::select(out.x0, out.o[0], xsimd::select(out.x1, out.o[1], out.o[2]));
    out.oky = xsimd::select(out.y0, out.o[0], xsimd::select(out.y1, out.o[1], out.o[2]));
    out.okz = xsimd::select(out.z0, out.o[0], xsimd::select(out.z1, out.o[1], out.o[2]));
  }
  return out;
}

template <class Arch>
auto WatertightTest<Arch>::load_block(const Block& b, const Rays& r) -> Tris {
  // Single ray: always uniform, so the permutation is an index into the block. Addressed
  // as bytes of the block (vertex k's arrays at a fixed offset from p0's), so that three
  // offsets serve all nine loads instead of nine addresses kept in registers.
  const auto* bytes = reinterpret_cast<const unsigned char*>(b.p);
  const std::size_t x = r.kx * sizeof(b.p[0][0]), y = r.ky * sizeof(b.p[0][0]), z = r.kz * sizeof(b.p[0][0]);
  const auto at = [bytes](int k, std::size_t axis) {
    return B::load_aligned(reinterpret_cast<const float*>(bytes + k * sizeof(b.p[0]) + axis));
  };
  return {at(0, x) - r.okx, at(0, y) - r.oky, at(0, z) - r.okz, at(1, x) - r.okx, at(1, y) - r.oky,
          at(1, z) - r.okz, at(2, x) - r.okx, at(2, y) - r.oky, at(2, z) - r.okz};
}

template <class Arch>
template <int BW>
auto WatertightTest<Arch>::broadcast_tri(const WatertightBlock<BW>& b, int j, const Rays& r) -> Tris {
  if (r.uniform) {
    const int kx = r.kx, ky = r.ky, kz = r.kz;
    return {B(b.p[0][kx][j]) - r.okx, B(b.p[0][ky][j]) - r.oky, B(b.p[0][kz][j]) - r.okz,
            B(b.p[1][kx][j]) - r.okx, B(b.p[1][ky][j]) - r.oky, B(b.p[1][kz][j]) - r.okz,
            B(b.p[2][kx][j]) - r.okx, B(b.p[2][ky][j]) - r.oky, B(b.p[2][kz][j]) - r.okz};
  }
  if constexpr (kLanes<Arch> >= 8) {
    // Per-lane permutation, AVX2 and AVX-512: the vertex's x y z in one register, each lane
    // picking its axis with one permute, minus the origin permuted once per packet (the same
    // subtraction p[k] - o[k] per lane as below, three permutes instead of six selects).
    const auto pick = [&](int k, const IntB<Arch>& axis) {
      const __m128 v = _mm_setr_ps(b.p[k][0][j], b.p[k][1][j], b.p[k][2][j], 0.0f);
      if constexpr (kLanes<Arch> == 16)
        // (maskz: GCC 12's header makes the unmasked form warn, -Wmaybe-uninitialized)
        return B(_mm512_maskz_permutexvar_ps(0xffff, axis, _mm512_zextps128_ps512(v)));
      else
        return B(_mm256_permutevar8x32_ps(_mm256_zextps128_ps256(v), axis));
    };
    return {pick(0, r.ikx) - r.okx, pick(0, r.iky) - r.oky, pick(0, r.ikz) - r.okz,
            pick(1, r.ikx) - r.okx, pick(1, r.iky) - r.oky, pick(1, r.ikz) - r.okz,
            pick(2, r.ikx) - r.okx, pick(2, r.iky) - r.oky, pick(2, r.ikz) - r.okz};
  }
  // Per-lane permutation (SSE4.2): relative coordinates along x y z, then picked per lane.
  Tris out;
  B* dst[3][3] = {{&out.akx, &out.aky, &out.akz}, {&out.bkx, &out.bky, &out.bkz}, {&out.ckx, &out.cky, &out.ckz}};
  for (int k = 0; k < 3; ++k) {
    const B q0 = B(b.p[k][0][j]) - r.o[0], q1 = B(b.p[k][1][j]) - r.o[1], q2 = B(b.p[k][2][j]) - r.o[2];
    *dst[k][0] = xsimd::select(r.x0, q0, xsimd::select(r.x1, q1, q2));
    *dst[k][1] = xsimd::select(r.y0, q0, xsimd::select(r.y1, q1, q2));
    *dst[k][2] = xsimd::select(r.z0, q0, xsimd::select(r.z1, q1, q2));
  }
  return out;
}

template <class Arch>
auto WatertightTest<Arch>::edges(const Rays& r, const Tris& tri, M& inside) -> Edges {
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
    e = fallback(s.ax, s.ay, s.bx, s.by, s.cx, s.cy, e.u, e.v, e.w);
    inside = ~(((e.u < zero) | (e.v < zero) | (e.w < zero)) & ((e.u > zero) | (e.v > zero) | (e.w > zero)));
  }
  return e;
}

template <class Arch>
auto WatertightTest<Arch>::depth(const Rays& r, const Tris& tri) -> Depth {
  M inside;
  Edges e = edges(r, tri, inside);
  // det NaN or Inf fails here; det = 0 (the ray lies in the plane) fails on its quotient
  // t = 0 / 0 (the prefilter passes it only with t det = 0), so no test of its own.
  Depth d;
  d.det = e.u + e.v + e.w;
  d.ad = xsimd::abs(d.det);
  d.inside = and_cmp<Cmp::le, Arch>(inside, d.ad, B(std::numeric_limits<float>::max()));
  d.u = e.v, d.v = e.w;
  if (xsimd::none(d.inside)) return d;
  const B az = r.sz * tri.akz, bz = r.sz * tri.bkz, cz = r.sz * tri.ckz;
  d.ts = depth_sum(e, az, bz, cz);
  d.ts_s = d.ts ^ (d.det & B(-0.0f));
  return d;
}

template <class Arch>
template <bool EarlyExit>
auto WatertightTest<Arch>::test(const Rays& r, const Tris& tri, B upper) -> Cand {
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

template <class Arch>
bool WatertightTest<Arch>::test_vl(const Rays& r, const Tris& tri, B upper, Cand& out, std::uint32_t& bits) {
  static_assert(W == 8 && kFused, "the AVX-512 8-lane leaf of the single-ray walk");
  Sheared s;
  const Edges e = edge_functions(r, tri, s);
  const __m256 eu = e.u, ev = e.v, ew = e.w, zero = _mm256_setzero_ps();
  constexpr int kNeqUnordered = 0x04, kLe = 0x12, kGe = 0x1d;
  // all_nonzero(), same_sign_bit() and test()'s and_cmp chain, in mask registers.
  __mmask8 nz = _mm256_cmp_ps_mask(eu, zero, kNeqUnordered);
  nz = _mm256_mask_cmp_ps_mask(nz, ev, zero, kNeqUnordered);
  nz = _mm256_mask_cmp_ps_mask(nz, ew, zero, kNeqUnordered);
  if (nz != 0xff) [[unlikely]]
    return false;
  const __m256i signs = _mm256_castps_si256(_mm256_or_ps(_mm256_xor_ps(eu, ev), _mm256_xor_ps(eu, ew)));
  const __mmask8 inside = _mm256_cmpgt_epi32_mask(signs, _mm256_set1_epi32(-1));
  const B det = e.u + e.v + e.w;
  const B ad = xsimd::abs(det);
  __mmask8 valid = _mm256_mask_cmp_ps_mask(inside, ad, _mm256_set1_ps(std::numeric_limits<float>::max()), kLe);
  const B ts = depth_sum(e, r.sz * tri.akz, r.sz * tri.bkz, r.sz * tri.ckz);
  const B ts_s = ts ^ (det & B(-0.0f));
  valid = _mm256_mask_cmp_ps_mask(valid, ts_s, r.tmin_lo * ad, kGe);
  valid = _mm256_mask_cmp_ps_mask(valid, ts_s, upper * ad, kLe);
  bits = valid;
  out.t = ts, out.u = e.v, out.v = e.w, out.den = det;
  return true;
}

template <class Arch>
auto WatertightTest<Arch>::sure_range(B tmin, B upper) -> SureRange {
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

template <class Arch>
auto WatertightTest<Arch>::fallback(B ax, B ay, B bx, B by, B cx, B cy, B eu, B ev, B ew) -> Edges {
  const B zero(0.0f);
  std::uint32_t lanes = bits_from_mask<Arch>((eu == zero) | (ev == zero) | (ew == zero));
  alignas(64) float fax[W], fay[W], fbx[W], fby[W], fcx[W], fcy[W], feu[W], fev[W], few[W];
  ax.store_aligned(fax), ay.store_aligned(fay), bx.store_aligned(fbx), by.store_aligned(fby);
  cx.store_aligned(fcx), cy.store_aligned(fcy);
  eu.store_aligned(feu), ev.store_aligned(fev), ew.store_aligned(few);
  watertight_fallback_lanes += static_cast<std::uint64_t>(std::popcount(lanes));
  for (; lanes != 0; lanes &= lanes - 1) {
    // Float products are exact in double, so only the subtraction rounds (and fusing it
    // would change nothing).
    const int i = std::countr_zero(lanes);
    feu[i] = float(double(fcx[i]) * double(fby[i]) - double(fcy[i]) * double(fbx[i]));
    fev[i] = float(double(fax[i]) * double(fcy[i]) - double(fay[i]) * double(fcx[i]));
    few[i] = float(double(fbx[i]) * double(fay[i]) - double(fby[i]) * double(fax[i]));
  }
  return {B::load_aligned(feu), B::load_aligned(fev), B::load_aligned(few)};
}

}  // namespace volley::simd::detail
