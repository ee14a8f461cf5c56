// A packet's rays as the packet walks hold them, chunk by chunk of L lanes, and the
// oracle's box test of one child for each lane: the per-lane test of the per-lane walk
// (packet_walk.h) and of the frustum walk's leaves (frustum_walk.h).
#pragma once
#include <immintrin.h>

#include <bit>
#include <cstdint>
#include <limits>

#include "simd/wide/kernels.h"
#include "simd/wide/stack.h"

namespace volley::simd {

namespace detail {

template <class Arch, int K>
struct PacketLanes {
  using B = FloatB<Arch>;
  static constexpr int L = kLanes<Arch>;
  static constexpr int C = K / L;  // chunks of L lanes
  static constexpr std::uint32_t kChunkBits = (1u << L) - 1u;
  // Lane i's bit, read by a broadcast from memory (1 << i in a register takes three steps).
  static constexpr std::uint32_t kLaneBit[32] = {
      1u << 0,  1u << 1,  1u << 2,  1u << 3,  1u << 4,  1u << 5,  1u << 6,  1u << 7,  1u << 8,  1u << 9,  1u << 10,
      1u << 11, 1u << 12, 1u << 13, 1u << 14, 1u << 15, 1u << 16, 1u << 17, 1u << 18, 1u << 19, 1u << 20, 1u << 21,
      1u << 22, 1u << 23, 1u << 24, 1u << 25, 1u << 26, 1u << 27, 1u << 28, 1u << 29, 1u << 30, 1u << 31};

  // Origin, reciprocal direction (the oracle's, ±inf for ±0), tmin and the current upper end
  // tfar of every lane (invalid or finished lanes: -inf).
  B ox[C], oy[C], oz[C], ix[C], iy[C], iz[C], tmin[C], tfar[C];

  /// Loads the valid lanes of a screened packet; a lane's tfar is query.bound(tmax).
  template <class Query>
  [[gnu::always_inline]] PacketLanes(const RayPacket<K>& rays, const PacketSetup<K>& setup, const Query& query) {
    const B ninf(-std::numeric_limits<float>::infinity());
    for (int c = 0; c < C; ++c) {
      const int o = c * L;
      ox[c] = B::load_aligned(rays.ox + o);
      oy[c] = B::load_aligned(rays.oy + o);
      oz[c] = B::load_aligned(rays.oz + o);
      ix[c] = B::load_aligned(setup.inv[0] + o);
      iy[c] = B::load_aligned(setup.inv[1] + o);
      iz[c] = B::load_aligned(setup.inv[2] + o);
      tmin[c] = B::load_aligned(rays.tmin + o);
      const auto ok = mask_from_bits<Arch>((setup.valid >> o) & kChunkBits);
      tfar[c] = xsimd::select(ok, query.bound(o, B::load_aligned(rays.tmax + o)), ninf);
    }
  }

  /// Entry and exit distances of chunk c into child j of `node`, one octant for the chunk
  /// (near plane of axis a: node.bounds[np[a]], far: np[a] ^ 1). NaN-safe order:
  /// xsimd::max/min(distance, running) is maxps/minps with the running bound second. The
  /// child is hit where entry <= exit.
  [[gnu::always_inline]] void slabs(const WideNode<kWideN>& node, int j, const int np[3], int c, B pad, B& entry,
                                    B& exit) const {
    const B tnx = (B(node.bounds[np[0]][j]) - ox[c]) * ix[c];
    const B tny = (B(node.bounds[np[1]][j]) - oy[c]) * iy[c];
    const B tnz = (B(node.bounds[np[2]][j]) - oz[c]) * iz[c];
    const B tfx = (B(node.bounds[np[0] ^ 1][j]) - ox[c]) * ix[c];
    const B tfy = (B(node.bounds[np[1] ^ 1][j]) - oy[c]) * iy[c];
    const B tfz = (B(node.bounds[np[2] ^ 1][j]) - oz[c]) * iz[c];
    entry = xsimd::max(tnz, xsimd::max(tny, xsimd::max(tnx, tmin[c])));
    exit = xsimd::min(tfz, xsimd::min(tfy, xsimd::min(tfx, tfar[c]))) * pad;
  }

  /// The fused form of slabs() (PacketLanes::fuse first): each slab distance is one fused
  /// b inv - c with c = org inv rounded outwards once per packet, the single-ray walk's
  /// form (single_walk.h, where the margin is argued), and the exit padding folded into the
  /// far planes' reciprocals. For lanes with no zero direction component (kFusedLanes).
  struct Fused {
    B cn[3][C], cf[3][C], fi[3][C];  // near and far c, reciprocal times the exit padding
  };

  /// The fused form's per-lane constants; `pad` is the exit padding (1 without Robust).
  Fused fuse(float pad, bool robust) const {
    static_assert(kFusedLanes<Arch>, "the fused slab test is for AVX-512");
    Fused f;
    const B rel(robust ? 0x1p-22f : 0.0f), tiny(robust ? 0x1p-149f : 0.0f);
    for (int c = 0; c < C; ++c) {
      const B* org[3] = {&ox[c], &oy[c], &oz[c]};
      const B* inv[3] = {&ix[c], &iy[c], &iz[c]};
      for (int a = 0; a < 3; ++a) {
        f.fi[a][c] = *inv[a] * B(pad);
        const B pn = *org[a] * *inv[a], pf = *org[a] * f.fi[a][c];
        f.cn[a][c] = pn + (xsimd::abs(pn) * rel + tiny);
        f.cf[a][c] = pf - (xsimd::abs(pf) * rel + tiny);
      }
    }
    return f;
  }

  /// fuse() where the walk takes the fused form (Fused), else nothing to set up.
  template <bool UseFused>
  Fused fuse_if(float pad, bool robust) const {
    if constexpr (UseFused)
      return fuse(pad, robust);
    else
      return Fused{};
  }

  /// slabs() in the fused form; `far_pad` is tfar[c] times the exit padding.
  [[gnu::always_inline]] void fused_slabs(const Fused& f, const WideNode<kWideN>& node, int j, const int np[3], int c,
                                          B far_pad, B& entry, B& exit) const {
    const B tnx = fused_mul_sub<Arch>(B(node.bounds[np[0]][j]), ix[c], f.cn[0][c]);
    const B tny = fused_mul_sub<Arch>(B(node.bounds[np[1]][j]), iy[c], f.cn[1][c]);
    const B tnz = fused_mul_sub<Arch>(B(node.bounds[np[2]][j]), iz[c], f.cn[2][c]);
    const B tfx = fused_mul_sub<Arch>(B(node.bounds[np[0] ^ 1][j]), f.fi[0][c], f.cf[0][c]);
    const B tfy = fused_mul_sub<Arch>(B(node.bounds[np[1] ^ 1][j]), f.fi[1][c], f.cf[1][c]);
    const B tfz = fused_mul_sub<Arch>(B(node.bounds[np[2] ^ 1][j]), f.fi[2][c], f.cf[2][c]);
    entry = xsimd::max(tnz, xsimd::max(tny, xsimd::max(tnx, tmin[c])));
    exit = xsimd::min(tfz, xsimd::min(tfy, xsimd::min(tfx, far_pad)));
  }

  /// The lanes whose own test (slabs(), or fused_slabs() with `f` where UseFused) enters
  /// child j of `node`, as lane bits.
  template <bool UseFused>
  [[gnu::always_inline]] std::uint32_t lanes_entering(const Fused& f, const WideNode<kWideN>& node, int j,
                                                      const int np[3], B pad) const {
    std::uint32_t bits = 0;
    for (int c = 0; c < C; ++c) {
      B e, x;
      if constexpr (UseFused)
        fused_slabs(f, node, j, np, c, tfar[c] * pad, e, x);
      else
        slabs(node, j, np, c, pad, e, x);
      bits |= bits_from_mask<Arch>(e <= x) << (c * L);
    }
    return bits;
  }

  /// Lanes `bits` handed to the single-ray walk, where few lanes are left in a subtree:
  /// single(i, far) walks lane i with its far end `far`, which its hits lower, and says
  /// whether the lane is finished. Returns the lanes finished.
  template <class Single>
  [[gnu::always_inline]] std::uint32_t hand_off(std::uint32_t bits, Single&& single) {
    alignas(64) float far_lanes[K];
    for (int c = 0; c < C; ++c) tfar[c].store_aligned(far_lanes + c * L);
    std::uint32_t finished = 0;
    for (std::uint32_t b = bits; b != 0; b &= b - 1) {
      const int i = std::countr_zero(b);
      if (single(i, far_lanes[i])) finished |= 1u << i;
    }
    for (int c = 0; c < C; ++c) tfar[c] = B::load_aligned(far_lanes + c * L);
    return finished;
  }

  /// The children that each lane of `bits` enters, as one lane bit per child lane: the
  /// test of slabs() turned around, one lane against all eight children (the same
  /// operations on the same values, so the same answer bit for bit). Cheaper than a test
  /// per child and chunk where fewer lanes reach a node than it has children times chunks,
  /// which on AVX2 is most nodes of an any-hit walk. Uniform: every lane's near planes are
  /// np; otherwise each lane's own, by the signs of its reciprocal. The lanes' values are
  /// read from the packet (rays, reciprocals, far ends at `far`).
  template <bool Uniform>
  [[gnu::always_inline]] static __m256i lanes_enter(const WideNode<kWideN>& node, const int np[3], std::uint32_t bits,
                                                    const RayPacket<K>& rays, const PacketSetup<K>& setup,
                                                    const float* far, B pad) {
    static_assert(L == kWideN && L == 8, "one lane per child");
    static_assert(K <= 32, "kLaneBit holds 32 lanes");
    B near_plane[3], far_plane[3];
    if constexpr (Uniform)
      for (int a = 0; a < 3; ++a) {
        near_plane[a] = B::load_aligned(node.bounds[np[a]]);
        far_plane[a] = B::load_aligned(node.bounds[np[a] ^ 1]);
      }
    __m256i entered = _mm256_setzero_si256();
    for (; bits != 0; bits &= bits - 1) {
      const int i = std::countr_zero(bits);
      if constexpr (!Uniform)
        for (int a = 0; a < 3; ++a) {
          const int n = 2 * a + (setup.inv[a][i] < 0.0f ? 1 : 0);
          near_plane[a] = B::load_aligned(node.bounds[n]);
          far_plane[a] = B::load_aligned(node.bounds[n ^ 1]);
        }
      const B lx(rays.ox[i]), ly(rays.oy[i]), lz(rays.oz[i]);  // lane i's origin and reciprocal
      const B rx(setup.inv[0][i]), ry(setup.inv[1][i]), rz(setup.inv[2][i]);
      const B tnx = (near_plane[0] - lx) * rx, tny = (near_plane[1] - ly) * ry, tnz = (near_plane[2] - lz) * rz;
      const B tfx = (far_plane[0] - lx) * rx, tfy = (far_plane[1] - ly) * ry, tfz = (far_plane[2] - lz) * rz;
      const B entry = xsimd::max(tnz, xsimd::max(tny, xsimd::max(tnx, B(rays.tmin[i]))));
      const B exit = xsimd::min(tfz, xsimd::min(tfy, xsimd::min(tfx, B(far[i])))) * pad;
      // Lane i's bit in the children it enters (an and of the compare, no select).
      const __m256i hit = _mm256_castps_si256(_mm256_cmp_ps(entry, exit, _CMP_LE_OQ));
      const __m256i bit = _mm256_set1_epi32(static_cast<std::int32_t>(kLaneBit[i]));
      entered = _mm256_or_si256(entered, _mm256_and_si256(hit, bit));
    }
    return entered;
  }

  /// The largest tfar of any lane.
  float far_max() const {
    B hi = tfar[0];
    for (int c = 1; c < C; ++c) hi = xsimd::max(hi, tfar[c]);
    return reduce_max<Arch>(hi);
  }
};

}  // namespace detail

}  // namespace volley::simd
