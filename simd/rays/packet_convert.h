// volley::load and volley::store (volley/packet.h) for whole packets, per ISA: K
// consecutive rays turned into a packet's lanes by whole-ray loads and the transposes of
// ray_transpose.h, and a packet of 16 hits back into Hit records by the inverse transpose,
// instead of scalar copies, whose narrow stores the packet walks' first vector loads of the
// same lines cannot forward from (perf/reports/rays.md, "packets in and out"). Bodies templated on Arch,
// instantiated only in the per-ISA files isa_sse42.cpp, isa_avx2.cpp and isa_avx512.cpp;
// src/accel/packet_convert.cpp picks the widest the CPU runs.
#pragma once
#include <immintrin.h>

#include <cstdint>

#include "simd/isa/arch.h"
#include "simd/rays/ray_transpose.h"
#include "volley/packet.h"

namespace volley::simd {

template <class Arch>
struct PacketConvert {
  /// rays[0 .. K) into lanes 0 .. K of a packet, all active: what volley::load gives for
  /// count = K, bit for bit.
  static void whole(RayPacket<16>& packet, const Ray* rays);
  static void whole(RayPacket<8>& packet, const Ray* rays);
  static void whole(RayPacket<4>& packet, const Ray* rays);
  static void whole(RayPacket<32>& packet, const Ray* rays);
  /// Whether store() is there: AVX-512 only (elsewhere volley::store's lane-by-lane copy).
  static constexpr bool kStore = kLanes<Arch> == 16;
  /// The 16 lanes of `hits` into out[0 .. 16): what volley::store gives for count = 16.
  static void store(const HitPacket<16>& hits, Hit* out);

 private:
  template <int K>
  static void transpose(RayPacket<K>& packet, const Ray* rays);
};

template <class Arch>
template <int K>
void PacketConvert<Arch>::transpose(RayPacket<K>& packet, const Ray* rays) {
  // A ray is eight floats (org, tmin, dir, tmax: volley/ray.h); float f of every ray goes
  // to its packet array.
  const float* const data = reinterpret_cast<const float*>(rays);
  float* const column[8] = {packet.ox, packet.oy, packet.oz, packet.tmin, packet.dx, packet.dy, packet.dz, packet.tmax};
  // The next K rays requested now: callers convert consecutive packets, and the hardware's
  // stream prefetch falls behind at a packet per query (a prefetch past the caller's
  // array is harmless: it never faults; the address is formed as an integer, since a
  // pointer past the array's end would be undefined).
  const std::uintptr_t next = reinterpret_cast<std::uintptr_t>(rays + K);
  for (int k = 0; k < K / 2; ++k) _mm_prefetch(reinterpret_cast<const char*>(next + 64 * k), _MM_HINT_T0);
  if constexpr (K == 16 && kLanes<Arch> == 16) {
    __m512 rows[8], cols[8];  // rows[k]: rays 2k and 2k + 1, one 64-byte load
    for (int k = 0; k < 8; ++k) rows[k] = _mm512_loadu_ps(data + 16 * k);
    detail::transpose_rows16<Arch>(rows, cols);
    for (int f = 0; f < 8; ++f) _mm512_store_ps(column[f], cols[f]);
  } else if constexpr (K >= 8 && kLanes<Arch> >= 8) {
    for (int g = 0; g < K; g += 8) {
      __m256 rows[8], cols[8];
      for (int k = 0; k < 8; ++k) rows[k] = _mm256_loadu_ps(data + 8 * (g + k));
      detail::transpose_rows8<Arch>(rows, cols);
      for (int f = 0; f < 8; ++f) _mm256_store_ps(column[f] + g, cols[f]);
    }
  } else {
    for (int g = 0; g < K; g += 4) {
      __m128 lo[4], hi[4];
      for (int k = 0; k < 4; ++k) {
        lo[k] = _mm_loadu_ps(data + 8 * (g + k));
        hi[k] = _mm_loadu_ps(data + 8 * (g + k) + 4);
      }
      detail::transpose_rows4<Arch>(lo, hi);
      for (int f = 0; f < 4; ++f) {
        _mm_store_ps(column[f] + g, lo[f]);
        _mm_store_ps(column[4 + f] + g, hi[f]);
      }
    }
  }
  packet.active = static_cast<std::uint32_t>((std::uint64_t{1} << K) - 1u);
}

template <class Arch>
void PacketConvert<Arch>::whole(RayPacket<16>& packet, const Ray* rays) {
  transpose(packet, rays);
}
template <class Arch>
void PacketConvert<Arch>::whole(RayPacket<8>& packet, const Ray* rays) {
  transpose(packet, rays);
}
template <class Arch>
void PacketConvert<Arch>::whole(RayPacket<4>& packet, const Ray* rays) {
  transpose(packet, rays);
}
template <class Arch>
void PacketConvert<Arch>::whole(RayPacket<32>& packet, const Ray* rays) {
  transpose(packet, rays);
}

template <class Arch>
void PacketConvert<Arch>::store(const HitPacket<16>& hits, Hit* out) {
  if constexpr (kStore) {
    // The six fields (and two unused rows) as eight rows of 16 lanes, transposed into eight
    // registers of two hits each (hits 2k and 2k + 1: lanes 0-5 and 8-13), each then
    // compressed to its 12 floats and stored: an 8 x 16 transpose in three rounds, each
    // exchanging one bit of the row index with one of the lane index.
    const __m512 zero = _mm512_setzero_ps();
    __m512 a[8] = {_mm512_load_ps(hits.t),
                   _mm512_load_ps(hits.u),
                   _mm512_load_ps(hits.v),
                   _mm512_load_ps(reinterpret_cast<const float*>(hits.prim)),
                   _mm512_load_ps(reinterpret_cast<const float*>(hits.geom)),
                   _mm512_load_ps(reinterpret_cast<const float*>(hits.inst)),
                   zero,
                   zero};
    __m512 b[8];
    const __m512i r1_0 = _mm512_setr_epi32(0, 1, 16, 17, 4, 5, 20, 21, 8, 9, 24, 25, 12, 13, 28, 29);
    const __m512i r1_1 = _mm512_setr_epi32(2, 3, 18, 19, 6, 7, 22, 23, 10, 11, 26, 27, 14, 15, 30, 31);
    for (int r = 0; r < 8; r += 2) {
      b[r] = _mm512_permutex2var_ps(a[r], r1_0, a[r + 1]);
      b[r + 1] = _mm512_permutex2var_ps(a[r], r1_1, a[r + 1]);
    }
    const __m512i r2_0 = _mm512_setr_epi32(0, 1, 2, 3, 16, 17, 18, 19, 8, 9, 10, 11, 24, 25, 26, 27);
    const __m512i r2_1 = _mm512_setr_epi32(4, 5, 6, 7, 20, 21, 22, 23, 12, 13, 14, 15, 28, 29, 30, 31);
    for (int q = 0; q < 4; ++q) {
      const int r = q < 2 ? q : q + 2;  // rows 0, 1, 4, 5 with 2, 3, 6, 7
      a[r] = _mm512_permutex2var_ps(b[r], r2_0, b[r + 2]);
      a[r + 2] = _mm512_permutex2var_ps(b[r], r2_1, b[r + 2]);
    }
    const __m512i r3_0 = _mm512_setr_epi32(0, 2, 4, 6, 16, 18, 20, 22, 1, 3, 5, 7, 17, 19, 21, 23);
    const __m512i r3_1 = _mm512_setr_epi32(8, 10, 12, 14, 24, 26, 28, 30, 9, 11, 13, 15, 25, 27, 29, 31);
    __m512 pairs[8];  // pairs[k]: hits 2k and 2k + 1, compressed to their 12 floats
    for (int r = 0; r < 4; ++r) {
      pairs[r] = _mm512_maskz_compress_ps(0x3f3f, _mm512_permutex2var_ps(a[r], r3_0, a[r + 4]));
      pairs[r + 4] = _mm512_maskz_compress_ps(0x3f3f, _mm512_permutex2var_ps(a[r], r3_1, a[r + 4]));
    }
    // In address order, each whole store's last four floats overwritten by the next; the
    // last store masked, so that nothing past out[15] is written.
    float* const dst = reinterpret_cast<float*>(out);  // a Hit is six 4-byte fields (volley/ray.h)
    // The next 16 records requested for writing, as the next rays in transpose().
    const std::uintptr_t next = reinterpret_cast<std::uintptr_t>(out + 16);
    for (int k = 0; k < 6; ++k) __builtin_prefetch(reinterpret_cast<const void*>(next + 64 * k), 1, 3);
    for (int k = 0; k < 7; ++k) _mm512_storeu_ps(dst + 12 * k, pairs[k]);
    _mm512_mask_storeu_ps(dst + 84, 0x0fff, pairs[7]);
  } else {
    (void)hits, (void)out;  // never called (kStore)
  }
}

// Explicit instantiation declarations: the definitions live in the per-ISA files only.
extern template struct PacketConvert<Sse42>;
extern template struct PacketConvert<Avx2>;
extern template struct PacketConvert<Avx512>;

}  // namespace volley::simd
