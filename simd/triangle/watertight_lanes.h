// The watertight test's ray and triangle lanes (simd/triangle/watertight.h): the oracle's Woop shear
// per ray, once per packet or broadcast for one ray, and the triangle lanes of a block,
// or one triangle broadcast to a packet, sheared into ray space. Out-of-class members of
// WatertightTest, included by watertight.h.
#pragma once
#include <bit>
#include <cmath>
#include <limits>

#include "simd/triangle/watertight.h"

namespace volley::simd::detail {

template <class Arch, bool Crossing>
auto WatertightTest<Arch, Crossing>::broadcast(const PreparedRay& r) -> Rays {
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

template <class Arch, bool Crossing>
template <int K>
void WatertightTest<Arch, Crossing>::prepare(const RayPacket<K>& rays, PreparedPacket<K>& out) {
  using I = IntB<Arch>;
  if (&out.rays != &rays) out.rays = rays;  // (the packet walk prepares its packet in place)
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

template <class Arch, bool Crossing>
template <int K>
auto WatertightTest<Arch, Crossing>::load(const PreparedPacket<K>& p, int offset) -> Rays {
  using I = IntB<Arch>;
  const B o[3] = {B::load_aligned(p.rays.ox + offset), B::load_aligned(p.rays.oy + offset),
                  B::load_aligned(p.rays.oz + offset)};
  const B s[3] = {B::load_aligned(p.s[0] + offset), B::load_aligned(p.s[1] + offset),
                  B::load_aligned(p.s[2] + offset)};
  const B tmin = B::load_aligned(p.rays.tmin + offset);
  if (p.uniform != 0) return lanes(o, tmin, s, p.uk);
  const I k[3] = {I::load_aligned(p.k[0] + offset), I::load_aligned(p.k[1] + offset),
                  I::load_aligned(p.k[2] + offset)};
  // A chunk whose active lanes share one permutation where the packet's do not (more often
  // in double packets of 32): the uniform form for the chunk (kx and ky fix kz).
  const std::uint32_t act = (p.rays.active >> offset) & ((2u << (W - 1)) - 1u);
  if (act != 0) {
    const int f = offset + std::countr_zero(act);
    const std::int32_t uk[3] = {p.k[0][f], p.k[1][f], p.k[2][f]};
    if ((bits_from_mask<Arch>(xsimd::bool_cast((k[0] == I(uk[0])) & (k[1] == I(uk[1])))) & act) == act)
      return lanes(o, tmin, s, uk);
  }
  return lanes(o, tmin, s, k);
}

template <class Arch, bool Crossing>
auto WatertightTest<Arch, Crossing>::lanes(const B o[3], B tmin, const B s[3]) -> Rays {
  Rays out;
  for (int a = 0; a < 3; ++a) out.o[a] = o[a];
  out.tmin = tmin;
  out.sx = s[0];
  out.sy = s[1];
  out.sz = s[2];
  out.tmin_lo =
      xsimd::select(xsimd::abs(out.sz) > B(0.0f), out.tmin - xsimd::abs(out.tmin) * B(core::kScaledPad<float>),
                    B(std::numeric_limits<float>::quiet_NaN()));
  return out;
}

template <class Arch, bool Crossing>
auto WatertightTest<Arch, Crossing>::lanes(const B o[3], B tmin, const B s[3], const std::int32_t uk[3]) -> Rays {
  Rays out = lanes(o, tmin, s);
  out.uniform = true;
  out.kx = uk[0];
  out.ky = uk[1];
  out.kz = uk[2];
  out.okx = out.o[out.kx];
  out.oky = out.o[out.ky];
  out.okz = out.o[out.kz];
  return out;
}

template <class Arch, bool Crossing>
auto WatertightTest<Arch, Crossing>::lanes(const B o[3], B tmin, const B s[3], const IntB<Arch> k[3]) -> Rays {
  using I = IntB<Arch>;
  Rays out = lanes(o, tmin, s);
  out.uniform = false;
  out.x0 = xsimd::bool_cast(k[0] == I(0)), out.x1 = xsimd::bool_cast(k[0] == I(1));
  out.y0 = xsimd::bool_cast(k[1] == I(0)), out.y1 = xsimd::bool_cast(k[1] == I(1));
  out.z0 = xsimd::bool_cast(k[2] == I(0)), out.z1 = xsimd::bool_cast(k[2] == I(1));
  out.ikx = k[0], out.iky = k[1], out.ikz = k[2];
  out.okx = xsimd::select(out.x0, out.o[0], xsimd::select(out.x1, out.o[1], out.o[2]));
  out.oky = xsimd::select(out.y0, out.o[0], xsimd::select(out.y1, out.o[1], out.o[2]));
  out.okz = xsimd::select(out.z0, out.o[0], xsimd::select(out.z1, out.o[1], out.o[2]));
  return out;
}

template <class Arch, bool Crossing>
auto WatertightTest<Arch, Crossing>::load_block(const Block& b, const Rays& r) -> Tris {
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

template <class Arch, bool Crossing>
template <int BW>
auto WatertightTest<Arch, Crossing>::broadcast_uniform(const WatertightBlock<BW>& b, int j, const Rays& r) -> Tris {
  const int kx = r.kx, ky = r.ky, kz = r.kz;
  return {B(b.p[0][kx][j]) - r.okx, B(b.p[0][ky][j]) - r.oky, B(b.p[0][kz][j]) - r.okz,
          B(b.p[1][kx][j]) - r.okx, B(b.p[1][ky][j]) - r.oky, B(b.p[1][kz][j]) - r.okz,
          B(b.p[2][kx][j]) - r.okx, B(b.p[2][ky][j]) - r.oky, B(b.p[2][kz][j]) - r.okz};
}

template <class Arch, bool Crossing>
template <int BW>
auto WatertightTest<Arch, Crossing>::broadcast_tri(const WatertightBlock<BW>& b, int j, const Rays& r) -> Tris {
  if (r.uniform) return broadcast_uniform(b, j, r);
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

}  // namespace volley::simd::detail
