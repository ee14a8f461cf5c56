// The stream walk: a batch of rays walks the tree together, breadth by node (after
// Barringer and Akenine-Möller, "Dynamic ray stream traversal", SIGGRAPH 2014). A node
// takes the list of rays that entered it and splits it by its children's boxes, L rays
// at a time with the oracle's per-lane test; each child's list is walked in turn, a short
// one ray by ray by the single-ray walk. For incoherent rays handed to the stream API
// (bounce and ambient-occlusion rays), where packets of neighbours share little.
#pragma once
#include <immintrin.h>

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>

#include "simd/rays/ray_transpose.h"
#include "simd/stream_scratch.h"
#include "simd/wide/compress.h"
#include "simd/wide/stream_queries.h"
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

/// The eight floats of the rays ids[0 .. L) as eight L-lane registers (out[f] lane l =
/// data[8 ids[l] + f]): transposed from whole-ray loads, which on AVX-512 and AVX2 is 1.2x
/// faster on bounce-ray streams than eight gathers (perf/reports/rays.md).
template <class Arch>
[[gnu::always_inline]] inline void load_rays(const float* data, const std::uint32_t* ids, FloatB<Arch> out[8]) {
  if constexpr (kLanes<Arch> == 16) {
    __m512 rows[8], cols[8];
    for (int k = 0; k < 8; ++k)
      rows[k] = _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_load_ps(data + 8 * std::size_t{ids[2 * k]})),
                                   _mm256_load_ps(data + 8 * std::size_t{ids[2 * k + 1]}), 1);
    transpose_rows16<Arch>(rows, cols);
    for (int f = 0; f < 8; ++f) out[f] = cols[f];
  } else if constexpr (kLanes<Arch> == 8) {
    __m256 rows[8], cols[8];
    for (int k = 0; k < 8; ++k) rows[k] = _mm256_load_ps(data + 8 * std::size_t{ids[k]});
    transpose_rows8<Arch>(rows, cols);
    for (int f = 0; f < 8; ++f) out[f] = cols[f];
  } else {
    __m128 lo[4], hi[4];
    for (int k = 0; k < 4; ++k) {
      lo[k] = _mm_load_ps(data + 8 * std::size_t{ids[k]});
      hi[k] = _mm_load_ps(data + 8 * std::size_t{ids[k]} + 4);
    }
    transpose_rows4<Arch>(lo, hi);
    for (int f = 0; f < 4; ++f) out[f] = lo[f], out[4 + f] = hi[f];
  }
}

/// The ids of a group of m <= L rays at `group` in a list, L of them: a whole group's where
/// they lie, a last partial one's copied to `tail`, its empty lanes repeating the first id.
template <int L>
[[gnu::always_inline]] inline const std::uint32_t* group_ids(const std::uint32_t* group, std::uint32_t m,
                                                             std::uint32_t (&tail)[L]) {
  if (m == static_cast<std::uint32_t>(L)) return group;
  for (int l = 0; l < L; ++l) tail[l] = l < static_cast<int>(m) ? group[l] : group[0];
  return tail;
}

}  // namespace detail

// The walk's steps. Every ray of a list is tested against each child of its node with its
// own current upper end (the oracle's padded slab test, as the per-lane packet walk), so a
// ray visits what its single walk would and its answer is the oracle's; the order of the
// visits differs (the closest hit keeps the oracle's rule by its bound and tie rule).
// Every step is forced inline into trace_stream, which keeps the loop's state (the lists,
// the stack) in its own locals.
template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query>
struct WideKernels<Arch, Test, Robust, PK>::StreamWalk {
  using B = detail::FloatB<Arch>;
  using I = detail::IntB<Arch>;
  using M = detail::MaskB<Arch>;
  static constexpr float kInf = std::numeric_limits<float>::infinity();

  const View& bvh;
  const Ray* rays;
  Query& query;
  /// Per ray, eight floats in one aligned half line (one load per ray: load_rays): origin,
  /// tmin, reciprocal direction, and the current upper end tfar.
  float* data;
  PreparedRay* prepared;

  float& tfar(std::size_t i) const { return data[8 * i + 7]; }

  /// The rays of rays[0 .. n) the oracle does not reject, prepared, their ids written to
  /// `list` (the root's list); returns how many.
  [[gnu::always_inline]] std::uint32_t root_list(std::size_t n, std::uint32_t* list) {
    std::uint32_t count = 0;
    for (std::size_t i = 0; i < n; ++i) {
      __m128 inv;
      if (prepare_single<Query::Single::kSureRange>(rays[i], prepared[i], inv) == detail::RayScreen::rejected) {
        continue;
      }
      _mm_store_ps(data + 8 * i, _mm_loadu_ps(&rays[i].org[0]));  // org, tmin
      _mm_store_ps(data + 8 * i + 4, inv);
      tfar(i) = query.bound(i, rays[i]);
      list[count++] = static_cast<std::uint32_t>(i);
    }
    return count;
  }

  /// Few rays: each on by itself from subtree `ref`, by the single-ray walk of its prepared
  /// ray (a leaf's list, however short, is tested at once: the walk would only add its entry).
  [[gnu::always_inline]] void hand_off(const std::uint32_t* list, std::uint32_t count, std::uint32_t ref) {
    for (std::uint32_t k = 0; k < count; ++k) {
      const std::uint32_t i = list[k];
      if (tfar(i) == -kInf) continue;
      const __m128 inv = _mm_load_ps(data + 8 * i + 4);
      typename Query::Single q = query.single(i);
      if (_mm_movemask_ps(_mm_cmpeq_ps(_mm_loadu_ps(rays[i].dir), _mm_setzero_ps())) & 7)
        walk<typename Query::Single, false>(bvh, prepared[i], inv, ref, q);
      else
        walk<typename Query::Single, true>(bvh, prepared[i], inv, ref, q);
      query.done(i, q, tfar(i));
    }
  }

  /// The rays of a list against leaf `ref`'s blocks: a long list L rays at a time in lanes
  /// where the query takes them (leaf_lanes), the rest one by one.
  [[gnu::always_inline]] void leaf(const std::uint32_t* list, std::uint32_t count, std::uint32_t ref) {
    const std::uint32_t blocks = wide_ref::leaf_count(ref);
    if (blocks == 0) return;
    const Block* first = bvh.blocks + wide_ref::leaf_first(ref);
    std::uint32_t k = 0;
    if constexpr (detail::leaf_lanes<Query>() && Test == TriangleTest::watertight)
      if (count >= kStreamLeafList) k = leaf_lanes(list, count, first, blocks);
    for (; k < count; ++k) {
      const std::uint32_t i = list[k];
      if (tfar(i) == -kInf) continue;
      typename Query::Single q = query.single(i);
      q.leaf(prepared[i], first, blocks, tfar(i));
      query.done(i, q, tfar(i));
    }
  }

  /// A long leaf list, L rays at a time in lanes, each triangle broadcast to them; returns
  /// how many of the list it took (whole groups while kStreamLeafLanes rays are left).
  [[gnu::always_inline]] std::uint32_t leaf_lanes(const std::uint32_t* list, std::uint32_t count, const Block* first,
                                                  std::uint32_t blocks) {
    using T = detail::TestOf<Arch, Test>;
    static_assert(offsetof(PreparedRay, k) == 8 * sizeof(float) && offsetof(PreparedRay, s) == 11 * sizeof(float));
    const int last = detail::last_block_triangles<WideKernels>(first, blocks);
    const auto far = [d = data](std::size_t i) -> float& { return d[8 * i + 7]; };
    std::uint32_t k = 0;
    for (; k + kStreamLeafLanes <= count; k += L) {
      const std::uint32_t m = count - k < L ? count - k : static_cast<std::uint32_t>(L);
      alignas(64) std::uint32_t tail[L], halves[L];  // halves: the prepared rays as 32-byte rows
      const std::uint32_t* ids = detail::group_ids<L>(list + k, m, tail);
      const I twice = I::load_unaligned(reinterpret_cast<const std::int32_t*>(ids));
      (twice + twice).store_aligned(reinterpret_cast<std::int32_t*>(halves));
      B ray[8];  // org, tmin, reciprocal direction, tfar
      detail::load_rays<Arch>(data, ids, ray);
      B prep[8];  // the prepared rays' second halves (floats 8 to 15): kx, ky, kz, shear, sure range
      detail::load_rays<Arch>(reinterpret_cast<const float*>(prepared) + 8, halves, prep);
      const B upper = xsimd::select(detail::mask_from_bits<Arch>((2u << (m - 1)) - 1u), ray[7], B(-kInf));
      const B s[3] = {prep[3], prep[4], prep[5]};
      const std::int32_t* uk = prepared[ids[0]].k;
      const I axes[3] = {xsimd::bitwise_cast<I>(prep[0]), xsimd::bitwise_cast<I>(prep[1]),
                         xsimd::bitwise_cast<I>(prep[2])};
      // (kx and ky fix kz; padding lanes repeat lane 0, so they never break uniformity)
      if (xsimd::all((axes[0] == I(uk[0])) & (axes[1] == I(uk[1]))))
        query.template leaf_lanes<T>(T::lanes(ray, ray[3], s, uk), upper, ids, first, blocks, last, far);
      else
        query.template leaf_lanes<T>(T::lanes(ray, ray[3], s, axes), upper, ids, first, blocks, last, far);
    }
    return k;
  }

  /// Splits a list by the boxes of the node's first `used` children, L rays at a time:
  /// child j's rays to split + j * cap, their count to child_count[j], and (kNearFirst) the
  /// sum of their entry distances to entry_sum[j].
  [[gnu::always_inline]] void split(const WideNode<N>& node, int used, const std::uint32_t* list, std::uint32_t count,
                                    std::uint32_t* split, std::size_t cap, std::uint32_t (&child_count)[N],
                                    B (&entry_sum)[N]) {
    const B pad(Robust ? core::kSlabExitPad : 1.0f);
    for (std::uint32_t g = 0; g < count; g += L) {
      const std::uint32_t m = count - g < L ? count - g : static_cast<std::uint32_t>(L);
      alignas(64) std::uint32_t tail[L];
      const std::uint32_t* ids = detail::group_ids<L>(list + g, m, tail);
      const I idx = I::load_unaligned(reinterpret_cast<const std::int32_t*>(ids));
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
        child_count[j] += detail::compress_lanes<Arch>(split + j * cap + child_count[j], idx, bits);
      }
    }
  }

  /// The push order of the children some ray entered: the child walked first goes last
  /// (kNearFirst: farthest mean entry first; else the slots' order, reversed). Returns how
  /// many.
  [[gnu::always_inline]] static int push_order(int used, const std::uint32_t (&child_count)[N],
                                               const B (&entry_sum)[N], int (&order)[N]) {
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
    return pushed;
  }
};

// The walk: a subtree's list is handed to the single-ray walk when short, tested against a
// leaf, or split by a node's children, whose lists go on the stack (the end of the lists
// grows as they are pushed). Children's lists are walked nearest first by their rays' mean
// entry distance for a query that asks (kNearFirst), in slot order otherwise.
template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query>
void WideKernels<Arch, Test, Robust, PK>::trace_stream(const View& bvh, const Ray* rays, std::size_t n, Query& query) {
  static_assert(detail::StreamQuery<Query, WideKernels>, "the stream walk takes a StreamQuery (query_protocol.h)");
  if (n == 0 || bvh.root == wide_ref::kEmptyRef) return;
  StreamScratch& scratch = stream_scratch();
  StreamWalk<Query> w{bvh, rays, query, scratch.ray_lanes(n), scratch.prepared(n)};
  std::uint32_t* lists = scratch.lists(n + L);
  const std::uint32_t count = w.root_list(n, lists);
  if (count == 0) return;

  detail::StreamItem stack[detail::kWideStack];
  int size = 0;
  detail::StreamItem cur{bvh.root, 0, count};
  std::size_t top = count;
  for (;;) {
    if (cur.count < kStreamSwitchRays && !(cur.ref & wide_ref::kLeafBit)) {
      w.hand_off(lists + cur.begin, cur.count, cur.ref);
    } else if (cur.ref & wide_ref::kLeafBit) {
      w.leaf(lists + cur.begin, cur.count, cur.ref);
    } else {
      const WideNode<N>& node = wide_ref::node_at(bvh.nodes, cur.ref);
      const std::size_t cap = cur.count + L;
      std::uint32_t* const split = scratch.split(N * cap);
      int used = 0;
      while (used < N && node.child[used] != wide_ref::kEmptyRef) ++used;
      std::uint32_t child_count[N] = {};
      typename StreamWalk<Query>::B entry_sum[N];
      for (int j = 0; j < N; ++j) entry_sum[j] = typename StreamWalk<Query>::B(0.0f);
      w.split(node, used, lists + cur.begin, cur.count, split, cap, child_count, entry_sum);
      int order[N];
      const int pushed = StreamWalk<Query>::push_order(used, child_count, entry_sum, order);
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

template <class Arch, TriangleTest Test, bool Robust, int PK>
template <class Query, class At>
void WideKernels<Arch, Test, Robust, PK>::stream_batches(const View& bvh, const Ray* rays, std::size_t count,
                                                         Query& query, At&& at) {
  for (std::size_t first = 0; first < count; first += kStreamBatch) {
    at(query, first);
    trace_stream(bvh, rays + first, count - first < kStreamBatch ? count - first : kStreamBatch, query);
  }
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
void WideKernels<Arch, Test, Robust, PK>::occluded(const View& bvh, const Ray* rays, std::size_t count,
                                               std::uint8_t* blocked) {
  std::memset(blocked, 0, count);
  detail::AnyHitStream<WideKernels> query{blocked};
  stream_batches(bvh, rays, count, query, [&](auto& q, std::size_t first) { q.blocked = blocked + first; });
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
void WideKernels<Arch, Test, Robust, PK>::intersect(const View& bvh, const Ray* rays, std::size_t count, Hit* hits) {
  detail::ClosestHitStream<WideKernels> query{hits};
  stream_batches(bvh, rays, count, query, [&](auto& q, std::size_t first) { q.hits = hits + first; });
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
void WideKernels<Arch, Test, Robust, PK>::occluded_excluding(const View& bvh, const Ray* rays, std::size_t count,
                                                             const std::uint32_t* excluded, std::uint8_t* blocked) {
  std::memset(blocked, 0, count);
  detail::AnyHitStream<WideKernels, true> query{blocked, excluded};
  stream_batches(bvh, rays, count, query, [&](auto& q, std::size_t first) {
    q.blocked = blocked + first;
    q.excluded = excluded + first;
  });
}

template <class Arch, TriangleTest Test, bool Robust, int PK>
void WideKernels<Arch, Test, Robust, PK>::intersect_excluding(const View& bvh, const Ray* rays, std::size_t count,
                                                              const std::uint32_t* excluded, Hit* hits) {
  detail::ClosestHitStream<WideKernels, true> query{hits, excluded};
  stream_batches(bvh, rays, count, query, [&](auto& q, std::size_t first) {
    q.hits = hits + first;
    q.excluded = excluded + first;
  });
}

}  // namespace volley::simd
