// volley::load (volley/packet.h) for whole packets, per ISA: K consecutive rays turned into
// a packet's lanes by whole-ray loads and the transposes of ray_transpose.h, instead of
// 8 K scalar copies, whose narrow stores the packet walks' first vector loads of the same
// lines cannot forward from (perf/rays.md, session 20). Bodies templated on Arch,
// instantiated only in the per-ISA files isa_sse42.cpp, isa_avx2.cpp and isa_avx512.cpp;
// src/accel/packet_load.cpp picks the widest the CPU runs.
#pragma once
#include <immintrin.h>

#include <cstdint>

#include "simd/arch.h"
#include "simd/ray_transpose.h"
#include "volley/packet.h"

namespace volley::simd {

/// rays[0 .. K) into lanes 0 .. K of a packet, all active: what volley::load gives for
/// count = K, bit for bit.
template <class Arch>
struct PacketLoad {
  static void whole(RayPacket<16>& packet, const Ray* rays);
  static void whole(RayPacket<8>& packet, const Ray* rays);
  static void whole(RayPacket<4>& packet, const Ray* rays);

 private:
  template <int K>
  static void transpose(RayPacket<K>& packet, const Ray* rays);
};

template <class Arch>
template <int K>
void PacketLoad<Arch>::transpose(RayPacket<K>& packet, const Ray* rays) {
  // A ray is eight floats (org, tmin, dir, tmax: volley/ray.h); float f of every ray goes
  // to its packet array.
  const float* const data = reinterpret_cast<const float*>(rays);
  float* const column[8] = {packet.ox, packet.oy, packet.oz, packet.tmin, packet.dx, packet.dy, packet.dz, packet.tmax};
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
void PacketLoad<Arch>::whole(RayPacket<16>& packet, const Ray* rays) {
  transpose(packet, rays);
}
template <class Arch>
void PacketLoad<Arch>::whole(RayPacket<8>& packet, const Ray* rays) {
  transpose(packet, rays);
}
template <class Arch>
void PacketLoad<Arch>::whole(RayPacket<4>& packet, const Ray* rays) {
  transpose(packet, rays);
}

// Explicit instantiation declarations: the definitions live in the per-ISA files only.
extern template struct PacketLoad<Sse42>;
extern template struct PacketLoad<Avx2>;
extern template struct PacketLoad<Avx512>;

}  // namespace volley::simd
