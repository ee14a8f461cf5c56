// Compressing the selected lanes of a vector of 32-bit values to the front of memory, the
// stores of the lists and stacks that grow by the children a node test selects (the stream
// walk's lists, the any-hit packet walk's stack): one instruction on AVX-512, one permute
// from a table on AVX2, one byte shuffle per four lanes on SSE4.2.
#pragma once
#include <immintrin.h>

#include <array>
#include <bit>
#include <cstdint>

#include "simd/wide/kernels.h"

namespace volley::simd {

namespace detail {

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

/// Stores the lanes of v that `bits` selects at dst, in lane order (dst has room for all
/// lanes); returns how many.
template <class Arch>
[[gnu::always_inline]] inline int compress_lanes(std::uint32_t* dst, IntB<Arch> v, std::uint32_t bits) {
  if constexpr (kLanes<Arch> == 16) {
    _mm512_storeu_si512(dst, _mm512_maskz_compress_epi32(static_cast<__mmask16>(bits), v));
    return std::popcount(bits);
  } else if constexpr (kLanes<Arch> == 8) {
    // vpermd reads the low 3 bits of each index. (data()[]: with _GLIBCXX_ASSERTIONS
    // std::array's operator[] is an out-of-line weak function, which a per-ISA object must
    // not define.)
    const __m256i lanes = _mm256_srlv_epi32(_mm256_set1_epi32(static_cast<int>(kCompressLanes8.data()[bits])),
                                            _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst), _mm256_permutevar8x32_epi32(v, lanes));
    return std::popcount(bits);
  } else {
    // (data(): see above.)
    const __m128i control = _mm_loadu_si128(reinterpret_cast<const __m128i*>(kCompressBytes4.data() + 16 * bits));
    _mm_storeu_si128(reinterpret_cast<__m128i*>(dst), _mm_shuffle_epi8(v, control));
    return std::popcount(bits);
  }
}

}  // namespace detail

}  // namespace volley::simd
