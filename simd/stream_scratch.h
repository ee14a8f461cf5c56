// The stream walk's working memory (simd/wide/stream_walk.h), one per calling thread and
// kept between calls. Baseline code with out-of-line members: a per-ISA object must not
// define the containers' functions (docs/style.md rule 2).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "simd/prepared_ray.h"

namespace volley::simd {

/// The stream walk takes a stream this many rays at a time (its lists and ray data then
/// stay within the L2 cache), and hands a subtree whose list holds fewer than
/// kStreamSwitchRays rays to the single-ray walk, ray by ray (perf/rays.md: 4096 and 16
/// against 1024 to 8192 and 8 to 32).
inline constexpr std::size_t kStreamBatch = 4096;
inline constexpr std::uint32_t kStreamSwitchRays = 16;

class StreamScratch {
 public:
  StreamScratch();
  ~StreamScratch();
  StreamScratch(const StreamScratch&) = delete;
  StreamScratch& operator=(const StreamScratch&) = delete;

  /// 8 floats per ray for n rays, 64-byte aligned (contents not kept when it grows).
  float* ray_lanes(std::size_t n);
  /// n prepared rays (contents not kept when it grows).
  PreparedRay* prepared(std::size_t n);
  /// The lists of ray ids, at least n entries; what it held is kept when it grows.
  std::uint32_t* lists(std::size_t n);
  /// A node's children's lists while it is split: at least n entries.
  std::uint32_t* split(std::size_t n);

 private:
  struct Buffers;
  std::unique_ptr<Buffers> buffers_;
};

/// For compressing the set lanes of an 8-bit mask to the front with one permute (AVX2 has
/// no compress instruction): entry m packs, 3 bits each from the lowest, the lanes of m's
/// set bits in order.
inline constexpr std::array<std::uint32_t, 256> kCompressLanes8 = [] {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t m = 0; m < 256; ++m) {
    int n = 0;
    for (std::uint32_t lane = 0; lane < 8; ++lane)
      if ((m >> lane) & 1u) table[m] |= lane << (3 * n++);
  }
  return table;
}();

/// For compressing the set lanes of a 4-bit mask to the front with one byte shuffle (SSE4.2:
/// pshufb): entry m is the 16 shuffle bytes at [16 m, 16 m + 16), the 32-bit lanes of m's set
/// bits in order, then zeros (0x80).
inline constexpr std::array<std::uint8_t, 256> kCompressBytes4 = [] {
  std::array<std::uint8_t, 256> table{};
  for (std::uint32_t m = 0; m < 16; ++m) {
    for (std::uint32_t b = 0; b < 16; ++b) table[16 * m + b] = 0x80;
    std::uint32_t n = 0;
    for (std::uint32_t lane = 0; lane < 4; ++lane)
      if ((m >> lane) & 1u) {
        for (std::uint32_t k = 0; k < 4; ++k) table[16 * m + 4 * n + k] = static_cast<std::uint8_t>(4 * lane + k);
        ++n;
      }
  }
  return table;
}();

/// The calling thread's scratch.
StreamScratch& stream_scratch();

}  // namespace volley::simd
