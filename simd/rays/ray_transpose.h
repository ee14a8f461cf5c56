// Rays as eight floats each (volley::Ray's org, tmin, dir, tmax, or the stream walk's
// per-ray lanes) turned into eight registers of one float per lane: the AoS-to-SoA step of
// the stream walk's loads and of volley::load for packets. Shuffles of whole-ray loads,
// which beat gathers (perf/reports/rays.md, "transposed stream loads") and, for packets, leave the SoA arrays
// written by whole-vector stores that the packet walks' vector loads can forward from.
#pragma once
#include <immintrin.h>

#include <cstddef>
#include <cstdint>

#include "simd/isa/arch.h"

namespace volley::simd::detail {

/// 16 rays as eight rows of two (rows[k]: rays 2k and 2k + 1, eight floats each) to eight
/// 16-lane columns (out[f] lane l = float f of ray l): a 16 x 8 transpose in three rounds
/// of two-source permutes (24 permutes).
template <class Arch>
[[gnu::always_inline]] inline void transpose_rows16(const __m512 rows[8], __m512 out[8]) {
  static_assert(kLanes<Arch> == 16, "AVX-512 only");
  // Round 1: rays 4m .. 4m + 3, columns 0-3 (lo) and 4-7 (hi), row by row.
  const __m512i lo = _mm512_setr_epi32(0, 1, 2, 3, 8, 9, 10, 11, 16, 17, 18, 19, 24, 25, 26, 27);
  const __m512i hi = _mm512_setr_epi32(4, 5, 6, 7, 12, 13, 14, 15, 20, 21, 22, 23, 28, 29, 30, 31);
  __m512 quad[4][2];
  for (int m = 0; m < 4; ++m) {
    quad[m][0] = _mm512_permutex2var_ps(rows[2 * m], lo, rows[2 * m + 1]);
    quad[m][1] = _mm512_permutex2var_ps(rows[2 * m], hi, rows[2 * m + 1]);
  }
  // Round 2: rays 0-7 (from quads 0, 1) and 8-15 (quads 2, 3), two columns, row by row.
  const __m512i pair0 = _mm512_setr_epi32(0, 1, 4, 5, 8, 9, 12, 13, 16, 17, 20, 21, 24, 25, 28, 29);
  const __m512i pair2 = _mm512_setr_epi32(2, 3, 6, 7, 10, 11, 14, 15, 18, 19, 22, 23, 26, 27, 30, 31);
  __m512 half[2][4];  // [rays 0-7 / 8-15][columns 0-1, 2-3, 4-5, 6-7]
  for (int h = 0; h < 2; ++h)
    for (int q = 0; q < 2; ++q) {
      half[h][2 * q] = _mm512_permutex2var_ps(quad[2 * h][q], pair0, quad[2 * h + 1][q]);
      half[h][2 * q + 1] = _mm512_permutex2var_ps(quad[2 * h][q], pair2, quad[2 * h + 1][q]);
    }
  // Round 3: one column, rays 0-15.
  const __m512i even = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
  const __m512i odd = _mm512_setr_epi32(1, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31);
  for (int c = 0; c < 4; ++c) {
    out[2 * c] = _mm512_permutex2var_ps(half[0][c], even, half[1][c]);
    out[2 * c + 1] = _mm512_permutex2var_ps(half[0][c], odd, half[1][c]);
  }
}

/// 8 rays (r[k]: ray k) to eight 8-lane columns (AVX2): the 8 x 8 transpose of unpacks,
/// shuffles and lane permutes (24 shuffles).
template <class Arch>
[[gnu::always_inline]] inline void transpose_rows8(const __m256 r[8], __m256 out[8]) {
  static_assert(kLanes<Arch> >= 8, "AVX2 or AVX-512");
  // Pairs of rays interleaved, then quads, then the 128-bit halves exchanged.
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  const __m256 t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
  const __m256 t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
  const __m256 u0 = _mm256_shuffle_ps(t0, t2, 0x44), u1 = _mm256_shuffle_ps(t0, t2, 0xee);
  const __m256 u2 = _mm256_shuffle_ps(t1, t3, 0x44), u3 = _mm256_shuffle_ps(t1, t3, 0xee);
  const __m256 u4 = _mm256_shuffle_ps(t4, t6, 0x44), u5 = _mm256_shuffle_ps(t4, t6, 0xee);
  const __m256 u6 = _mm256_shuffle_ps(t5, t7, 0x44), u7 = _mm256_shuffle_ps(t5, t7, 0xee);
  out[0] = _mm256_permute2f128_ps(u0, u4, 0x20);
  out[1] = _mm256_permute2f128_ps(u1, u5, 0x20);
  out[2] = _mm256_permute2f128_ps(u2, u6, 0x20);
  out[3] = _mm256_permute2f128_ps(u3, u7, 0x20);
  out[4] = _mm256_permute2f128_ps(u0, u4, 0x31);
  out[5] = _mm256_permute2f128_ps(u1, u5, 0x31);
  out[6] = _mm256_permute2f128_ps(u2, u6, 0x31);
  out[7] = _mm256_permute2f128_ps(u3, u7, 0x31);
}

/// 4 rays (lo[k], hi[k]: the first and last four floats of ray k) to eight 4-lane columns,
/// in place (out lo[f] = float f, hi[f] = float 4 + f): two 4 x 4 transposes (SSE).
template <class Arch>
[[gnu::always_inline]] inline void transpose_rows4(__m128 lo[4], __m128 hi[4]) {
  _MM_TRANSPOSE4_PS(lo[0], lo[1], lo[2], lo[3]);
  _MM_TRANSPOSE4_PS(hi[0], hi[1], hi[2], hi[3]);
}

}  // namespace volley::simd::detail
