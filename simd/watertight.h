// Watertight ray/triangle test (Woop, Benthin & Wald 2013, "Watertight Ray/Triangle
// Intersection", JCGT 2(1)) on float lanes. The SIMD twin of
// src/core/triangle_watertight.h: the same float operations in the same order, so every
// lane gives the oracle's hit/miss and t, u, v bit for bit.
//
// Watertightness needs the edge functions a*b - c*d with both products rounded: the
// per-ISA files are compiled with -ffp-contract=off and xsimd's operators map to plain
// multiply and subtract instructions, so nothing is fused even where FMA is enabled
// (tests/simd/test_watertight.cpp checks it on closed meshes with the shipped flags).
// A lane whose float edge function is exactly 0 is recomputed in double (exact products),
// one lane at a time; watertight_fallback_lanes counts them.
#pragma once
#include <bit>
#include <cstdint>
#include <limits>

#include "simd/kernel_common.h"
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
    B o[3];             // origin x y z
    B tmin;
    B sx, sy, sz;       // shear dir[kx]/dir[kz], dir[ky]/dir[kz], 1/dir[kz]
    M ok;               // |sz| > 0: an infinite dir[kz] (sz = 0) or NaN never hits
    bool uniform;
    int kx, ky, kz;
    M x0, x1, y0, y1, z0, z1;
  };
  /// Triangle lanes: the vertices relative to the ray origin, permuted: a = p0 - org
  /// taken along axes kx, ky, kz; likewise b (p1) and c (p2).
  struct Tris {
    B akx, aky, akz, bkx, bky, bkz, ckx, cky, ckz;
  };
  /// Candidate hits: `valid` lanes are hit with tmin <= t < upper. ts_s and ad (the
  /// scaled distance with det's sign folded in, and |det|) let accept() redo the
  /// oracle's scaled range test for a smaller upper.
  struct Cand {
    M valid;
    B t, u, v, ts_s, ad;
  };

  static Rays broadcast(const PreparedRay& r);
  template <int K>
  static Rays load(const RayPacket<K>& p, int offset);
  static Tris load_block(const Block& b, const Rays& r);
  static Tris broadcast_tri(const Block& b, int j, const Rays& r);
  static Cand test(const Rays& r, const Tris& tri, B upper);
  /// The lanes of `c` still hit when the upper end shrinks to `upper`.
  static M accept(const Cand& c, B upper);
  /// Recomputes the edge functions of the lanes in `lanes` in double (exact products).
  static void fallback(std::uint32_t lanes, B ax, B ay, B bx, B by, B cx, B cy, B& eu, B& ev, B& ew);
};

template <class Arch>
auto WatertightTest<Arch>::broadcast(const PreparedRay& r) -> Rays {
  Rays out;
  for (int i = 0; i < 3; ++i) out.o[i] = B(r.ray.org[i]);
  out.tmin = B(r.ray.tmin);
  out.sx = B(r.s[0]);
  out.sy = B(r.s[1]);
  out.sz = B(r.s[2]);
  out.ok = xsimd::abs(out.sz) > B(0.0f);
  out.uniform = true;
  out.kx = r.k[0];
  out.ky = r.k[1];
  out.kz = r.k[2];
  return out;
}

template <class Arch>
template <int K>
auto WatertightTest<Arch>::load(const RayPacket<K>& p, int offset) -> Rays {
  Rays out;
  out.o[0] = B::load_aligned(p.ox + offset);
  out.o[1] = B::load_aligned(p.oy + offset);
  out.o[2] = B::load_aligned(p.oz + offset);
  out.tmin = B::load_aligned(p.tmin + offset);
  const B dx = B::load_aligned(p.dx + offset), dy = B::load_aligned(p.dy + offset),
          dz = B::load_aligned(p.dz + offset);
  // make_woop_ray per lane: kz = axis of the largest |dir| (ties: lowest axis), kx and ky
  // the next two cyclically, swapped when dir[kz] < 0 (keeps the winding).
  const B ax = xsimd::abs(dx), ay = xsimd::abs(dy), az = xsimd::abs(dz);
  const M x_ge_y = ax >= ay;
  const M z0 = x_ge_y & (ax >= az);
  const M z1 = ~x_ge_y & (ay >= az);
  const B dkz = xsimd::select(z0, dx, xsimd::select(z1, dy, dz));
  const M neg = dkz < B(0.0f);
  const M z2 = ~(z0 | z1);
  // Unswapped: kx = kz + 1, ky = kz + 2 (mod 3); swapped: exchanged.
  out.x0 = (neg & z1) | (~neg & z2);
  out.x1 = (neg & z2) | (~neg & z0);
  out.y0 = (neg & z2) | (~neg & z1);
  out.y1 = (neg & z0) | (~neg & z2);
  out.z0 = z0;
  out.z1 = z1;
  const B dkx = xsimd::select(out.x0, dx, xsimd::select(out.x1, dy, dz));
  const B dky = xsimd::select(out.y0, dx, xsimd::select(out.y1, dy, dz));
  out.sx = dkx / dkz;
  out.sy = dky / dkz;
  out.sz = B(1.0f) / dkz;
  out.ok = xsimd::abs(out.sz) > B(0.0f);
  // One permutation for all active lanes (the common case of a coherent packet): the
  // triangle's coordinates are then picked by index instead of per-lane selects.
  const std::uint32_t act = (p.active >> offset) & ((2u << (W - 1)) - 1u);
  const std::uint32_t b0 = bits_from_mask<Arch>(z0) & act, b1 = bits_from_mask<Arch>(z1) & act,
                      bn = bits_from_mask<Arch>(neg) & act;
  out.uniform = (b0 == 0 || b0 == act) && (b1 == 0 || b1 == act) && (bn == 0 || bn == act);
  if (out.uniform) {
    out.kz = b0 ? 0 : b1 ? 1 : 2;
    out.kx = out.kz == 2 ? 0 : out.kz + 1;
    out.ky = out.kx == 2 ? 0 : out.kx + 1;
    if (bn != 0) {
      const int k = out.kx;
      out.kx = out.ky;
      out.ky = k;
    }
  }
  return out;
}

template <class Arch>
auto WatertightTest<Arch>::load_block(const Block& b, const Rays& r) -> Tris {
  // Single ray: always uniform, so the permutation is an index into the block.
  const int kx = r.kx, ky = r.ky, kz = r.kz;
  return {B::load_aligned(b.p[0][kx]) - r.o[kx], B::load_aligned(b.p[0][ky]) - r.o[ky],
          B::load_aligned(b.p[0][kz]) - r.o[kz], B::load_aligned(b.p[1][kx]) - r.o[kx],
          B::load_aligned(b.p[1][ky]) - r.o[ky], B::load_aligned(b.p[1][kz]) - r.o[kz],
          B::load_aligned(b.p[2][kx]) - r.o[kx], B::load_aligned(b.p[2][ky]) - r.o[ky],
          B::load_aligned(b.p[2][kz]) - r.o[kz]};
}

template <class Arch>
auto WatertightTest<Arch>::broadcast_tri(const Block& b, int j, const Rays& r) -> Tris {
  if (r.uniform) {
    const int kx = r.kx, ky = r.ky, kz = r.kz;
    return {B(b.p[0][kx][j]) - r.o[kx], B(b.p[0][ky][j]) - r.o[ky], B(b.p[0][kz][j]) - r.o[kz],
            B(b.p[1][kx][j]) - r.o[kx], B(b.p[1][ky][j]) - r.o[ky], B(b.p[1][kz][j]) - r.o[kz],
            B(b.p[2][kx][j]) - r.o[kx], B(b.p[2][ky][j]) - r.o[ky], B(b.p[2][kz][j]) - r.o[kz]};
  }
  // Per-lane permutation: relative coordinates along x y z, then picked per lane.
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
auto WatertightTest<Arch>::test(const Rays& r, const Tris& tri, B upper) -> Cand {
  const B zero(0.0f), max(std::numeric_limits<float>::max());
  // Shear so the ray runs along +z; the z scaling is deferred to the depth test.
  const B ax = tri.akx - r.sx * tri.akz;
  const B ay = tri.aky - r.sy * tri.akz;
  const B bx = tri.bkx - r.sx * tri.bkz;
  const B by = tri.bky - r.sy * tri.bkz;
  const B cx = tri.ckx - r.sx * tri.ckz;
  const B cy = tri.cky - r.sy * tri.ckz;
  // Scaled barycentrics: 2D edge functions at the origin, both products rounded.
  B eu = cx * by - cy * bx;
  B ev = ax * cy - ay * cx;
  B ew = bx * ay - by * ax;
  // An edge function of exactly 0 may hide a nonzero one: redo those lanes in double.
  const M any_zero = (eu == zero) | (ev == zero) | (ew == zero);
  if (xsimd::any(any_zero)) fallback(bits_from_mask<Arch>(any_zero), ax, ay, bx, by, cx, cy, eu, ev, ew);
  // Mixed signs: the origin is outside (both facings accepted). An infinite dir[kz]
  // (sz = 0, every hit at t = 0) or a NaN direction fails.
  M valid = r.ok & ~(((eu < zero) | (ev < zero) | (ew < zero)) & ((eu > zero) | (ev > zero) | (ew > zero)));
  // det = 0: the ray lies in the plane; NaN and Inf fail.
  const B det = eu + ev + ew;
  const B ad = xsimd::abs(det);
  valid = valid & (ad > zero) & (ad <= max);
  if (xsimd::none(valid)) return {valid, det, det, det, det, ad};
  // Scaled distance t det against [tmin, upper) |det| with det's sign folded in.
  const B az = r.sz * tri.akz, bz = r.sz * tri.bkz, cz = r.sz * tri.ckz;
  const B ts = eu * az + ev * bz + ew * cz;
  const B ts_s = ts ^ (det & B(-0.0f));
  valid = valid & (ts_s >= r.tmin * ad) & (ts_s < upper * ad);
  if (xsimd::none(valid)) return {valid, det, det, det, ts_s, ad};
  // Normalize the survivors and recheck the range on the quotient (as the oracle does).
  const B t = ts / det;
  valid = valid & (r.tmin <= t) & (t < upper);
  return {valid, t, ev / det, ew / det, ts_s, ad};
}

template <class Arch>
auto WatertightTest<Arch>::accept(const Cand& c, B upper) -> M {
  return c.valid & (c.ts_s < upper * c.ad) & (c.t < upper);
}

template <class Arch>
void WatertightTest<Arch>::fallback(std::uint32_t lanes, B ax, B ay, B bx, B by, B cx, B cy, B& eu, B& ev,
                                    B& ew) {
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
  eu = B::load_aligned(feu);
  ev = B::load_aligned(fev);
  ew = B::load_aligned(few);
}

}  // namespace volley::simd::detail
