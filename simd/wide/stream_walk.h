// The stream walk: a batch of rays walks the tree together, breadth by node (after
// Barringer and Akenine-Möller, "Dynamic ray stream traversal", SIGGRAPH 2014). A node
// takes the list of rays that entered it and splits it by its children's boxes, L rays
// at a time with the oracle's per-lane test; each child's list is walked in turn, a short
// one ray by ray by the single-ray walk. For incoherent rays handed to the stream API
// (bounce and ambient-occlusion rays), where packets of neighbours share little.
#pragma once
#include <immintrin.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <limits>

#include "simd/stream_scratch.h"
#include "simd/wide/queries.h"
#include "simd/wide/stack.h"

namespace volley::simd {

namespace detail {

/// A subtree and its list in the stream walk: the rays whose ids are entries
/// [begin, begin + count) of the lists (StreamScratch::lists) enter subtree `ref`.
struct StreamItem {
  std::uint32_t ref;
  std::uint32_t begin;
  std::uint32_t count;
};

/// The eight floats of 16 rays (data + 8 ids[l], 32 bytes each) as eight 16-lane registers,
/// out[f] lane l = data[8 ids[l] + f]: two rays per 512-bit load, then a 16 x 8 transpose in
/// three rounds of two-source permutes (24 permutes and 8 inserts against eight gathers).
template <class Arch>
[[gnu::always_inline]] inline void transpose_rays16(const float* data, const std::uint32_t* ids, __m512 out[8]) {
  static_assert(kLanes<Arch> == 16, "AVX-512 only");
  __m512 rows[8];  // rays 2k and 2k + 1
  for (int k = 0; k < 8; ++k)
    rows[k] = _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_load_ps(data + 8 * std::size_t{ids[2 * k]})),
                                 _mm256_load_ps(data + 8 * std::size_t{ids[2 * k + 1]}), 1);
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

/// transpose_rays16 for 8 rays (AVX2): one 256-bit load per ray and the 8 x 8 transpose of
/// unpacks, shuffles and lane permutes (24 shuffles against eight gathers).
template <class Arch>
[[gnu::always_inline]] inline void transpose_rays8(const float* data, const std::uint32_t* ids, __m256 out[8]) {
  static_assert(kLanes<Arch> == 8, "AVX2 only");
  __m256 r[8];
  for (int k = 0; k < 8; ++k) r[k] = _mm256_load_ps(data + 8 * std::size_t{ids[k]});
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

/// The eight floats of the rays ids[0 .. L) as eight L-lane registers (out[f] lane l =
/// data[8 ids[l] + f]): transposed from whole-ray loads, which on AVX-512 and AVX2 is 1.2x
/// faster on bounce-ray streams than eight gathers (perf/rays.md).
template <class Arch>
[[gnu::always_inline]] inline void load_rays(const float* data, const std::uint32_t* ids, FloatB<Arch> out[8]) {
  if constexpr (kLanes<Arch> == 16) {
    __m512 cols[8];
    transpose_rays16<Arch>(data, ids, cols);
    for (int f = 0; f < 8; ++f) out[f] = cols[f];
  } else if constexpr (kLanes<Arch> == 8) {
    __m256 cols[8];
    transpose_rays8<Arch>(data, ids, cols);
    for (int f = 0; f < 8; ++f) out[f] = cols[f];
  } else {
    // SSE4.2: two 4 x 4 transposes, of the rays' first and second halves.
    __m128 lo[4], hi[4];
    for (int k = 0; k < 4; ++k) {
      lo[k] = _mm_load_ps(data + 8 * std::size_t{ids[k]});
      hi[k] = _mm_load_ps(data + 8 * std::size_t{ids[k]} + 4);
    }
    _MM_TRANSPOSE4_PS(lo[0], lo[1], lo[2], lo[3]);
    _MM_TRANSPOSE4_PS(hi[0], hi[1], hi[2], hi[3]);
    for (int f = 0; f < 4; ++f) out[f] = lo[f], out[4 + f] = hi[f];
  }
}

/// Stores the ids of `bits` (lane order) at dst; returns how many.
template <class Arch>
[[gnu::always_inline]] inline int compress_ids(std::uint32_t* dst, IntB<Arch> v, std::uint32_t bits) {
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

// The walk. Every ray of a list is tested against each child of its node with its own
// current upper end (the oracle's padded slab test, as the per-lane packet walk), so a ray
// visits what its single walk would and its answer is the oracle's; the order of the
// visits differs (the closest hit keeps the oracle's rule by its bound and tie rule).
// Children's lists are walked nearest first by their rays' mean entry distance for a
// query that asks (kNearFirst), in slot order otherwise.
template <class Arch, TriangleTest Test, bool Robust>
template <class Query>
void WideKernels<Arch, Test, Robust>::trace_stream(const View& bvh, const Ray* rays, std::size_t n, Query& query) {
  using B = detail::FloatB<Arch>;
  using I = detail::IntB<Arch>;
  using M = detail::MaskB<Arch>;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  if (n == 0 || bvh.root == wide_ref::kEmptyRef) return;
  StreamScratch& scratch = stream_scratch();
  // Per ray, eight floats in one aligned half line (one load per ray: load_rays): origin,
  // tmin, reciprocal direction, and the current upper end tfar.
  float* const data = scratch.ray_lanes(n);
  const auto tfar = [data](std::size_t i) -> float& { return data[8 * i + 7]; };
  PreparedRay* const prepared = scratch.prepared(n);

  // The rays the oracle does not reject form the root's list.
  std::uint32_t* lists = scratch.lists(n + L);
  std::uint32_t count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    __m128 inv;
    if (prepare_single<Query::Single::kSureRange>(rays[i], prepared[i], inv) == detail::RayScreen::rejected) {
      continue;
    }
    _mm_store_ps(data + 8 * i, _mm_loadu_ps(&rays[i].org[0]));  // org, tmin
    _mm_store_ps(data + 8 * i + 4, inv);
    tfar(i) = query.bound(i, rays[i]);
    lists[count++] = static_cast<std::uint32_t>(i);
  }
  if (count == 0) return;

  const B pad(Robust ? core::kSlabExitPad : 1.0f);
  detail::StreamItem stack[detail::kWideStack];
  int size = 0;
  detail::StreamItem cur{bvh.root, 0, count};
  std::size_t top = count;
  for (;;) {
    if (cur.count < kStreamSwitchRays && !(cur.ref & wide_ref::kLeafBit)) {
      // Few rays: each on by itself from here, by the single-ray walk of its prepared ray
      // (a leaf's list, however short, is tested at once: the walk would only add its entry).
      for (std::uint32_t k = 0; k < cur.count; ++k) {
        const std::uint32_t i = lists[cur.begin + k];
        if (tfar(i) == -kInf) continue;
        const __m128 inv = _mm_load_ps(data + 8 * i + 4);
        typename Query::Single q = query.single(i);
        if (_mm_movemask_ps(_mm_cmpeq_ps(_mm_loadu_ps(rays[i].dir), _mm_setzero_ps())) & 7)
          walk<typename Query::Single, false>(bvh, prepared[i], inv, cur.ref, q);
        else
          walk<typename Query::Single, true>(bvh, prepared[i], inv, cur.ref, q);
        query.done(i, q, tfar(i));
      }
    } else if (cur.ref & wide_ref::kLeafBit) {
      const std::uint32_t blocks = wide_ref::leaf_count(cur.ref);
      if (blocks != 0) {
        const Block* first = bvh.blocks + wide_ref::leaf_first(cur.ref);
        for (std::uint32_t k = 0; k < cur.count; ++k) {
          const std::uint32_t i = lists[cur.begin + k];
          if (tfar(i) == -kInf) continue;
          typename Query::Single q = query.single(i);
          q.leaf(prepared[i], first, blocks, tfar(i));
          query.done(i, q, tfar(i));
        }
      }
    } else {
      // Split the list by the children's boxes into `split` (child j's list at j * cap).
      const WideNode<N>& node = wide_ref::node_at(bvh.nodes, cur.ref);
      const std::size_t cap = cur.count + L;
      std::uint32_t* const split = scratch.split(N * cap);
      int used = 0;
      while (used < N && node.child[used] != wide_ref::kEmptyRef) ++used;
      std::uint32_t child_count[N] = {};
      B entry_sum[N];
      for (int j = 0; j < N; ++j) entry_sum[j] = B(0.0f);
      const std::uint32_t* list = lists + cur.begin;
      for (std::uint32_t g = 0; g < cur.count; g += L) {
        const std::uint32_t m = cur.count - g < L ? cur.count - g : static_cast<std::uint32_t>(L);
        alignas(64) std::uint32_t ids[L];
        for (int l = 0; l < L; ++l) ids[l] = l < static_cast<int>(m) ? list[g + l] : list[g];
        const I idx = I::load_aligned(reinterpret_cast<const std::int32_t*>(ids));
        B ray[8];  // org, tmin, reciprocal direction, tfar
        detail::load_rays<Arch>(data, ids, ray);
        const B gx = ray[0], gy = ray[1], gz = ray[2], gtmin = ray[3];
        const B gix = ray[4], giy = ray[5], giz = ray[6], gtfar = ray[7];
        const M valid = detail::mask_from_bits<Arch>(m == L ? kChunkBits : (1u << m) - 1u);
        const M negx = gix < B(0.0f), negy = giy < B(0.0f), negz = giz < B(0.0f);
        for (int j = 0; j < used; ++j) {
          const B lx = (B(node.bounds[0][j]) - gx) * gix, hx = (B(node.bounds[1][j]) - gx) * gix;
          const B ly = (B(node.bounds[2][j]) - gy) * giy, hy = (B(node.bounds[3][j]) - gy) * giy;
          const B lz = (B(node.bounds[4][j]) - gz) * giz, hz = (B(node.bounds[5][j]) - gz) * giz;
          const B tnx = xsimd::select(negx, hx, lx), tfx = xsimd::select(negx, lx, hx);
          const B tny = xsimd::select(negy, hy, ly), tfy = xsimd::select(negy, ly, hy);
          const B tnz = xsimd::select(negz, hz, lz), tfz = xsimd::select(negz, lz, hz);
          // NaN-safe order, as PacketLanes::slabs.
          const B entry = xsimd::max(tnz, xsimd::max(tny, xsimd::max(tnx, gtmin)));
          const B exit = xsimd::min(tfz, xsimd::min(tfy, xsimd::min(tfx, gtfar))) * pad;
          const M hit = valid & (entry <= exit);
          const std::uint32_t bits = detail::bits_from_mask<Arch>(hit);
          if constexpr (Query::kNearFirst) entry_sum[j] = entry_sum[j] + xsimd::select(hit, entry, B(0.0f));
          child_count[j] += detail::compress_ids<Arch>(split + j * cap + child_count[j], idx, bits);
        }
      }
      // Push order: the child walked first goes last (farthest mean entry first).
      int order[N];
      int pushed = 0;
      for (int j = 0; j < used; ++j)
        if (child_count[j] != 0) order[pushed++] = j;
      if constexpr (Query::kNearFirst) {
        // Insertion sort of at most N, farthest first (entries of entered lanes are finite;
        // a NaN mean, were one possible, would only stay in place).
        float mean[N];
        for (int k = 0; k < pushed; ++k)
          mean[order[k]] = xsimd::hadd(entry_sum[order[k]]) / static_cast<float>(child_count[order[k]]);
        for (int k = 1; k < pushed; ++k) {
          const int j = order[k];
          int at = k;
          for (; at > 0 && mean[order[at - 1]] < mean[j]; --at) order[at] = order[at - 1];
          order[at] = j;
        }
      } else {
        // (Reversed by hand: a per-ISA object must not emit a standard function, which a
        // sanitizer build leaves out of line; docs/style.md rule 2.)
        for (int k = 0; k < pushed / 2; ++k) {
          const int j = order[k];
          order[k] = order[pushed - 1 - k];
          order[pushed - 1 - k] = j;
        }
      }
      std::size_t need = top;
      for (int k = 0; k < pushed; ++k) need += child_count[order[k]];
      lists = scratch.lists(need);
      for (int k = 0; k < pushed; ++k) {
        const int j = order[k];
        std::memcpy(lists + top, split + j * cap, child_count[j] * sizeof(std::uint32_t));
        stack[size++] = {node.child[j], static_cast<std::uint32_t>(top), child_count[j]};
        top += child_count[j];
      }
    }
    if (size == 0) return;
    cur = stack[--size];
    top = cur.begin + cur.count;
  }
}

template <class Arch, TriangleTest Test, bool Robust>
void WideKernels<Arch, Test, Robust>::occluded(const View& bvh, const Ray* rays, std::size_t count,
                                               std::uint8_t* blocked) {
  std::memset(blocked, 0, count);
  detail::AnyHitStream<WideKernels> query{blocked};
  for (std::size_t first = 0; first < count; first += kStreamBatch) {
    query.blocked = blocked + first;
    trace_stream(bvh, rays + first, count - first < kStreamBatch ? count - first : kStreamBatch, query);
  }
}

template <class Arch, TriangleTest Test, bool Robust>
void WideKernels<Arch, Test, Robust>::intersect(const View& bvh, const Ray* rays, std::size_t count, Hit* hits) {
  detail::ClosestHitStream<WideKernels> query{hits};
  for (std::size_t first = 0; first < count; first += kStreamBatch) {
    query.hits = hits + first;
    trace_stream(bvh, rays + first, count - first < kStreamBatch ? count - first : kStreamBatch, query);
  }
}

}  // namespace volley::simd
