// A ray packet with its per-lane precomputation hoisted out of the triangle loop (the
// Woop shear of the watertight test), the packet counterpart of PreparedRay. Plain data,
// no xsimd: built by PacketKernels<Arch, Test, K>::prepare (or TriangleKernels::prepare).
#pragma once
#include <cstdint>

#include "volley/packet.h"

namespace volley::simd {

/// K rays plus what the packet kernels would otherwise recompute per call: for the
/// watertight test, the shear constants and axes of every lane (exactly the oracle's
/// make_woop_ray, lane by lane) and whether all active lanes share the axes. For moller
/// and plane only `rays` is filled. Immutable once prepared: reuse it for every leaf the
/// packet visits. 64-byte aligned.
template <int K>
struct alignas(64) PreparedPacket {
  RayPacket<K> rays;       // 32K + 64 bytes: the packet as given
  float s[3][K];           // 12K bytes: Sx, Sy, Sz per lane (watertight)
  std::int32_t k[3][K];    // 12K bytes: kx, ky, kz per lane (watertight)
  std::int32_t uniform;    //  4 bytes: 1 when every active lane has the same kx, ky, kz
  std::int32_t uk[3];      // 12 bytes: those axes (when uniform)
};                         // 56K + 80 bytes, padded to 64 (K = 4: 320 B, 8: 576 B, 16: 1024 B)
static_assert(sizeof(PreparedPacket<4>) == 320 && sizeof(PreparedPacket<8>) == 576 &&
              sizeof(PreparedPacket<16>) == 1024, "PreparedPacket: 56 B per lane + 80 B, 64 B aligned");

}  // namespace volley::simd
