// The binned SAH builder's data in SSE registers (bvh_build.cpp): the primitive record it
// partitions, boxes in two 4-lane registers, the bin grid and the bins of the three axes.
// Internal to the builder; SSE2/SSE4.1 only (the x86-64-v2 baseline).
#pragma once
#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <glm/glm.hpp>

#include "core/bbox.h"

namespace volley::core::bvh_build_detail {

inline constexpr float kInf = std::numeric_limits<float>::infinity();

// A primitive as the builder moves it around: its bounds and its id. The builder
// partitions an array of these in place, so each pass reads memory sequentially
// instead of gathering boxes through prim_index. The centroid is recomputed from the
// bounds as lo/2 + hi/2 (BBox::center(); the SSE and scalar forms below evaluate the
// same float operations, so a primitive always falls into the same bin).
struct Item {
  glm::vec3 lo;        // 12 bytes
  float zero;          //  4 bytes: always 0, the 4th lane of a 16-byte load of lo
  glm::vec3 hi;        // 12 bytes
  std::uint32_t prim;  //  4 bytes: masked off after a 16-byte load of hi (its bits
                       //           would be a subnormal float, slow in arithmetic)
  BBox box() const { return {lo, hi}; }
  float center(int axis) const { return 0.5f * lo[axis] + 0.5f * hi[axis]; }
};
static_assert(sizeof(Item) == 32, "Item is 32 bytes");

// Lanes x, y, z set, lane 3 cleared: applied to a 16-byte load of Item::hi.
inline __m128 xyz_mask() { return _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0)); }
inline __m128 load_lo(const Item& it) { return _mm_loadu_ps(&it.lo.x); }
inline __m128 load_hi(const Item& it) { return _mm_and_ps(_mm_loadu_ps(&it.hi.x), xyz_mask()); }
inline __m128 center4(__m128 lo, __m128 hi) {
  const __m128 half = _mm_set1_ps(0.5f);
  return _mm_add_ps(_mm_mul_ps(lo, half), _mm_mul_ps(hi, half));
}
inline __m128 load3(const glm::vec3& v) { return _mm_setr_ps(v.x, v.y, v.z, 0.0f); }
inline glm::vec3 store3(__m128 v) {
  alignas(16) float f[4];
  _mm_store_ps(f, v);
  return {f[0], f[1], f[2]};
}

// A box in two registers; empty is lo = +inf, hi = -inf as for BBox. Only primitive
// boxes with finite bounds go through it (no NaN reaches minps/maxps).
struct alignas(16) Box4 {
  __m128 lo = _mm_set1_ps(kInf);   // 16 bytes
  __m128 hi = _mm_set1_ps(-kInf);  // 16 bytes
  void extend(__m128 l, __m128 h) {
    lo = _mm_min_ps(lo, l);
    hi = _mm_max_ps(hi, h);
  }
  void extend(const Box4& b) { extend(b.lo, b.hi); }
  BBox to_bbox() const { return {store3(lo), store3(hi)}; }
  // Half surface area dx dy + dy dz + dz dx (summed in that order, as
  // BBox::half_area), 0 when empty.
  float half_area() const {
    const __m128 d = _mm_sub_ps(hi, lo);
    if (_mm_movemask_ps(_mm_cmplt_ps(d, _mm_setzero_ps())) & 7) return 0.0f;
    // (dx dy, dy dz, dz dx, 0): d times d rotated by one lane.
    const __m128 p = _mm_mul_ps(d, _mm_shuffle_ps(d, d, _MM_SHUFFLE(3, 0, 2, 1)));
    const __m128 s = _mm_add_ss(p, _mm_shuffle_ps(p, p, _MM_SHUFFLE(3, 3, 3, 1)));
    return _mm_cvtss_f32(_mm_add_ss(s, _mm_movehl_ps(p, p)));
  }
};

// How a node's centroids map to bins: nb bins per axis from cbox.lo with scale
// nb / extent on an active axis (finite extent > 0 and finite scale; a subnormal extent
// would give scale = inf and NaN bins); an inactive axis gets scale 0, so all its
// primitives land in bin 0, unused.
struct BinGrid {
  int nb = 0;
  float scale[3] = {0, 0, 0};
  bool active[3] = {false, false, false};
  glm::vec3 cmin{0.0f};

  BinGrid(const BBox& cbox, int bins) : nb(bins), cmin(cbox.lo) {
    for (int a = 0; a < 3; ++a) {
      const float extent = cbox.hi[a] - cbox.lo[a];
      const float s = static_cast<float>(nb) / extent;
      active[a] = extent > 0.0f && std::isfinite(s) && s > 0.0f;
      scale[a] = active[a] ? s : 0.0f;
    }
  }
  bool any_active() const { return active[0] || active[1] || active[2]; }
};

// Clears flush-to-zero and denormals-are-zero (MXCSR bits 15 and 6) for its scope and
// restores them after. Bins carry their counts as subnormal patterns, which a maxps reads as
// 0 under DAZ; and Embree sets both on the oneTBB threads it runs on (and asks applications
// to). Each build task and binning chunk holds one: two MXCSR writes per task, and only on
// threads that had the bits set.
class ExactSubnormals {
 public:
  ExactSubnormals() : csr_(_mm_getcsr()) {
    if (csr_ & kFlushBits) _mm_setcsr(csr_ & ~kFlushBits);
  }
  ~ExactSubnormals() {
    if (csr_ & kFlushBits) _mm_setcsr(csr_);
  }
  ExactSubnormals(const ExactSubnormals&) = delete;
  ExactSubnormals& operator=(const ExactSubnormals&) = delete;

 private:
  static constexpr unsigned kFlushBits = 0x8040u;
  unsigned csr_;
};

// A bin: the bounds of its primitives in lanes x, y, z of a Box4 and their count, as
// integer bits, in lane 3 of hi. Items' hi has 0 in lane 3, and maxps keeps a positive
// subnormal pattern against +0 (with DAZ clear: ExactSubnormals), so the count survives the
// bound update and one integer add bumps it: no separate counter to load, increment and
// store per axis. Exact while a count stays below 2^23 (a subnormal pattern): add() sees at
// most bvh_build.cpp's kParallelBinning items.
inline Box4 empty_bin() {
  Box4 b;
  b.hi = _mm_and_ps(b.hi, xyz_mask());  // count 0
  return b;
}
inline std::uint32_t bin_count(const Box4& b) {
  return static_cast<std::uint32_t>(_mm_extract_epi32(_mm_castps_si128(b.hi), 3));
}
// Merges bin b into bin a: bounds extended, counts added.
inline void merge_bin(Box4& a, const Box4& b) {
  const __m128i counts = _mm_add_epi32(_mm_castps_si128(a.hi), _mm_castps_si128(b.hi));
  a.lo = _mm_min_ps(a.lo, b.lo);
  a.hi = _mm_blend_ps(_mm_max_ps(a.hi, b.hi), _mm_castsi128_ps(counts), 0b1000);
}

// The bins of the three axes (axis a: bins [a * cap, a * cap + nb)), plus a second set of
// the same shape that add() fills with every other primitive: two independent
// read-modify-write chains, where one chain stalls on store forwarding whenever
// neighbouring primitives (neighbours in a mesh) fall into the same bin.
struct Bins {
  int cap = 0;
  std::vector<Box4> box;  // 2 sets x 3 axes x cap

  explicit Bins(int capacity) : cap(capacity), box(6 * std::size_t(capacity), empty_bin()) {}
  void clear(int nb, int set = 0) {
    for (int a = 3 * set; a < 3 * set + 3; ++a) std::fill_n(&box[a * cap], nb, empty_bin());
  }
  const Box4& at(int axis, int b) const { return box[axis * cap + b]; }
  // Adds items [begin, end) on the three axes in one pass (Wald 2007, sec. 3), into set 0.
  void add(const Item* items, std::uint32_t begin, std::uint32_t end, const BinGrid& g) {
    // Below this many items clearing and folding the second set costs more than it saves.
    constexpr std::uint32_t kTwoSets = 64;
    if (end - begin < kTwoSets) return add_to<1>(items, begin, end, g);
    clear(g.nb, 1);
    add_to<2>(items, begin, end, g);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < g.nb; ++b) merge_bin(box[a * cap + b], box[(a + 3) * cap + b]);
  }
  void merge(const Bins& o, int nb) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < nb; ++b) merge_bin(box[a * cap + b], o.box[a * cap + b]);
  }

 private:
  // Adds items [begin, end), item begin + k into set k % kSets, in one pass over them.
  template <int kSets>
  void add_to(const Item* items, std::uint32_t begin, std::uint32_t end, const BinGrid& g) {
    const __m128 cmin = load3(g.cmin);
    const __m128 scale4 = _mm_setr_ps(g.scale[0], g.scale[1], g.scale[2], 0.0f);
    const __m128i last = _mm_set1_epi32(g.nb - 1);
    const __m128i first = _mm_setzero_si128();
    const __m128i one_count = _mm_setr_epi32(0, 0, 0, 1);
    // Byte offsets of the axes' bins from the set's first: one base pointer for all three,
    // a bin's offset computed in the same register as its index.
    constexpr int kShift = 5;
    static_assert(sizeof(Box4) == 1 << kShift);
    const int axis_bytes = cap * static_cast<int>(sizeof(Box4));
    const __m128i axis_offset = _mm_setr_epi32(0, axis_bytes, 2 * axis_bytes, 0);
    char* const base = reinterpret_cast<char*>(box.data());
    const std::size_t set_bytes = 3 * std::size_t(axis_bytes);
    auto bump = [&](char* set, std::uint32_t offset, __m128 lo, __m128 hi) {
      Box4& bin = *reinterpret_cast<Box4*>(set + offset);
      bin.lo = _mm_min_ps(bin.lo, lo);
      bin.hi = _mm_castsi128_ps(_mm_add_epi32(_mm_castps_si128(_mm_max_ps(bin.hi, hi)), one_count));
    };
    // In blocks: the bin offsets of kBlock items first, then their bins' updates. Computed
    // item by item, an update's address came at the end of a long chain (load, centroid,
    // convert, clamp), and the next item's bin loads ran ahead of the stores whose address
    // was still unknown, often to the same bin (neighbouring primitives): the loads waited or
    // were replayed. Here the addresses are ready in a buffer (perf/reports/build.md).
    constexpr std::uint32_t kBlock = 16;
    static_assert(kBlock % kSets == 0, "item begin + k goes into set k % kSets");
    alignas(16) std::uint32_t offsets[kBlock][4];
    for (std::uint32_t i = begin; i < end; i += kBlock) {
      const std::uint32_t n = std::min(kBlock, end - i);
      for (std::uint32_t j = 0; j < n; ++j) {
        const Item& item = items[i + j];
        // Clamped on both sides: on an inactive axis whose centroid extent overflowed,
        // (c - cmin) * 0 is inf * 0 = NaN, which converts to INT_MIN.
        const __m128i k = _mm_max_epi32(
            _mm_min_epi32(
                _mm_cvttps_epi32(_mm_mul_ps(_mm_sub_ps(center4(load_lo(item), load_hi(item)), cmin), scale4)), last),
            first);
        _mm_store_si128(reinterpret_cast<__m128i*>(offsets[j]), _mm_add_epi32(_mm_slli_epi32(k, kShift), axis_offset));
      }
      for (std::uint32_t j = 0; j < n; ++j) {
        const Item& item = items[i + j];
        const __m128 lo = load_lo(item);
        const __m128 hi = load_hi(item);
        char* const bins = base + (j % kSets) * set_bytes;
        bump(bins, offsets[j][0], lo, hi);
        bump(bins, offsets[j][1], lo, hi);
        bump(bins, offsets[j][2], lo, hi);
      }
    }
  }
};

}  // namespace volley::core::bvh_build_detail
