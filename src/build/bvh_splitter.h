// The split decision of the binned SAH builder (bvh_build.cpp): a node's bins, its best
// plane by SAH or the fallbacks (object median, split by index), and the partition of its
// items. Internal to the builder; included by bvh_build.cpp only.
#pragma once
#include <immintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_scan.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/bvh.h"
#include "build/bvh_bins.h"

namespace volley::core::bvh_build_detail {

// Nodes this small are binned with at most kSmallNodeBins bins (Splitter::split).
constexpr std::uint32_t kSmallNode = 64;
constexpr int kSmallNodeBins = 8;
// Nodes with at least this many primitives are binned in parallel chunks of kBinChunk.
constexpr std::uint32_t kParallelBinning = 1u << 15;
constexpr std::size_t kBinChunk = 1u << 13;
// Bin counts live in float lanes as subnormal patterns (bvh_bins.h): one Bins::add() call
// must see fewer than 2^23 items.
static_assert(kParallelBinning <= (1u << 23) && kBinChunk <= (1u << 23));

// A node still to be processed: its items are items[begin, end), cbox bounds their
// centroids; `node` is its index in the node array of whoever builds it.
struct Task {
  std::uint32_t node;
  std::uint32_t begin;
  std::uint32_t end;
  std::uint32_t depth;
  BBox cbox;
  bool spatial;  // false for the subtree of invalid primitives: split by index only
};

// How a node is split: items [begin, mid) go left, [mid, end) right.
struct Split {
  std::uint32_t mid;
  BBox lbox, rbox;    // children's bounds
  BBox lcbox, rcbox;  // children's centroid bounds
};

// Decides how to split one node and partitions its items accordingly; the policy of
// build_bvh (bvh.h). One per thread: it owns the bins.
class Splitter {
 public:
  Splitter(const BvhBuildOptions& options, Item* items) : opt_(options), items_(items), bins_(options.bins) {}

  // Node t with bounds `box`: false for a leaf, else true with the split in `out` and
  // the items partitioned. `parallel` bins in parallel chunks.
  bool split(const Task& t, const BBox& box, bool parallel, Split& out) {
    const std::uint32_t count = t.end - t.begin;
    const std::uint32_t max_leaf = static_cast<std::uint32_t>(opt_.max_leaf_size);
    if (count <= static_cast<std::uint32_t>(opt_.min_leaf_size)) return false;

    // Depth guard: median splits need ceil(log2(count)) more levels at most; take
    // them once the SAH could otherwise push a leaf to kBvhMaxDepth.
    const bool depth_guard = near_depth_limit(t.depth, count);
    if (!t.spatial || depth_guard) {
      if (count <= max_leaf) return false;
      return median_split(t, out);
    }
    // Two primitives: the only split is one per child, no binning needed.
    if (count == 2) return split_pair(t, box, out);

    // A node of count < bins primitives gets count bins: at most count of them can be
    // occupied anyway, and clearing and sweeping 3 x bins bins per node would otherwise
    // dominate the build for the many small nodes near the leaves.
    // Nodes of at most kSmallNode primitives get at most kSmallNodeBins: the bottom levels
    // hold most nodes, and there 8 bins find planes as good for a faster build (perf/reports/build.md).
    int nb = count < static_cast<std::uint32_t>(opt_.bins) ? static_cast<int>(count) : opt_.bins;
    if (count <= kSmallNode && nb > kSmallNodeBins) nb = kSmallNodeBins;
    const BinGrid grid(t.cbox, nb);
    if (!grid.any_active()) {
      if (count <= max_leaf) return false;
      return median_split(t, out);
    }
    bin(t, grid, parallel);

    // The cheapest plane: cost in units of intersection_cost * area,
    // A_left slots(N_left) + A_right slots(N_right).
    // Counts below 2^31 (always, but for a node of 2^31 primitives or more) convert with one
    // signed conversion.
    const Plane plane = count < (1u << 31) ? best_plane<true>(grid) : best_plane<false>(grid);
    const float best_cost = plane.cost;
    const int best_axis = plane.axis;
    const int best_bin = plane.bin;  // left side takes bins [0, best_bin]

    // Leaf or split (SAH normalised by this node's area A; compared multiplied by A so
    // that A = 0, a node flat to a segment or a point, is no division by zero):
    // leaf cost  C_i slots(N)  vs  split cost  C_t + C_i (A_l slots(N_l) + A_r slots(N_r)) / A.
    const float area = box.half_area();
    const float ci = opt_.intersection_cost;
    if (count <= max_leaf) {
      const float leaf = ci * slots(count) * area;
      const float split_cost = opt_.traversal_cost * area + ci * best_cost;
      if (best_axis < 0 || !(split_cost < leaf)) return false;
    }
    // No plane separates the centroids (possible only when the areas overflow).
    if (best_axis < 0) return median_split(t, out);
    partition(t, grid, best_axis, best_bin, out);
    return true;
  }

 private:
  // A plane between bins: the left side takes bins [0, bin] of `axis`; axis -1: none.
  struct Plane {
    float cost = kInf;
    int axis = -1;
    int bin = -1;
  };

  // Sweeps the bins from both sides, the three axes at once (lane a: axis a), in the order
  // and with the float operations of one axis at a time: the same plane, ties included
  // (the first axis, then the highest bin, of the least cost).
  template <bool kBelow2To31>
  Plane best_plane(const BinGrid& grid) const {
    const int nb = grid.nb;
    __m128* const left_area = left_area_;  // lane a: area of bins [0, b] of axis a
    __m128i* const left_count = left_count_;
    Box4 acc[3];
    __m128i n = _mm_setzero_si128();
    for (int b = 0; b < nb - 1; ++b) {
      n = _mm_add_epi32(n, add_bins(acc, b));
      left_area[b] = half_areas(acc);
      left_count[b] = n;
    }
    const __m128 active =
        _mm_castsi128_ps(_mm_setr_epi32(grid.active[0] ? -1 : 0, grid.active[1] ? -1 : 0, grid.active[2] ? -1 : 0, 0));
    const __m128i zero = _mm_setzero_si128();
    __m128 best_cost = _mm_set1_ps(kInf);
    __m128i best_bin = _mm_set1_epi32(-1);
    acc[0] = acc[1] = acc[2] = Box4{};
    n = zero;
    for (int b = nb - 1; b > 0; --b) {
      n = _mm_add_epi32(n, add_bins(acc, b));
      const __m128i lc = left_count[b - 1];
      const __m128 cost = _mm_add_ps(_mm_mul_ps(left_area[b - 1], slots<kBelow2To31>(lc)),
                                       _mm_mul_ps(half_areas(acc), slots<kBelow2To31>(n)));
      const __m128i a_side_empty = _mm_or_si128(_mm_cmpeq_epi32(n, zero), _mm_cmpeq_epi32(lc, zero));
      const __m128 better =
          _mm_andnot_ps(_mm_castsi128_ps(a_side_empty), _mm_and_ps(active, _mm_cmplt_ps(cost, best_cost)));
      best_cost = _mm_blendv_ps(best_cost, cost, better);
      best_bin = _mm_blendv_epi8(best_bin, _mm_set1_epi32(b - 1), _mm_castps_si128(better));
    }
    alignas(16) float costs[4];
    alignas(16) std::int32_t bins[4];
    _mm_store_ps(costs, best_cost);
    _mm_store_si128(reinterpret_cast<__m128i*>(bins), best_bin);
    Plane plane;
    for (int a = 0; a < 3; ++a)
      if (costs[a] < plane.cost) plane = {costs[a], a, bins[a]};
    return plane;
  }

  // Extends acc[a] by bin b of axis a; returns the three bins' counts in lanes 0, 1, 2.
  __m128i add_bins(Box4 (&acc)[3], int b) const {
    const Box4& x = bins_.at(0, b);
    const Box4& y = bins_.at(1, b);
    const Box4& z = bins_.at(2, b);
    // Lane 3 of hi (the count) cleared: the areas do arithmetic on these lanes.
    acc[0].extend(x.lo, _mm_and_ps(x.hi, xyz_mask()));
    acc[1].extend(y.lo, _mm_and_ps(y.hi, xyz_mask()));
    acc[2].extend(z.lo, _mm_and_ps(z.hi, xyz_mask()));
    const __m128 xy = _mm_unpackhi_ps(x.hi, y.hi);              // x2 y2 x3 y3
    const __m128 z0 = _mm_unpackhi_ps(z.hi, _mm_setzero_ps());  // z2 0 z3 0
    return _mm_castps_si128(_mm_movehl_ps(z0, xy));             // x3 y3 z3 0
  }

  // Box4::half_area of acc[0], acc[1], acc[2] in lanes 0, 1, 2 (the same products and sums).
  static __m128 half_areas(const Box4 (&acc)[3]) {
    const __m128 zero = _mm_setzero_ps();
    const __m128 d0 = _mm_sub_ps(acc[0].hi, acc[0].lo);
    const __m128 d1 = _mm_sub_ps(acc[1].hi, acc[1].lo);
    const __m128 d2 = _mm_sub_ps(acc[2].hi, acc[2].lo);
    // Transposed: dx, dy, dz of the three boxes.
    const __m128 lo01 = _mm_unpacklo_ps(d0, d1), lo2 = _mm_unpacklo_ps(d2, zero);
    const __m128 hi01 = _mm_unpackhi_ps(d0, d1), hi2 = _mm_unpackhi_ps(d2, zero);
    const __m128 dx = _mm_movelh_ps(lo01, lo2);
    const __m128 dy = _mm_movehl_ps(lo2, lo01);
    const __m128 dz = _mm_movelh_ps(hi01, hi2);
    const __m128 area = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dy), _mm_mul_ps(dy, dz)), _mm_mul_ps(dz, dx));
    const __m128 empty = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(dx, zero), _mm_cmplt_ps(dy, zero)), _mm_cmplt_ps(dz, zero));
    return _mm_andnot_ps(empty, area);
  }

  // slots() of each lane of n, with the same float operations. kBelow2To31: every lane is
  // below 2^31, where the signed conversion rounds as static_cast<float>(std::uint32_t).
  template <bool kBelow2To31>
  __m128 slots(__m128i n) const {
    const __m128 nf = kBelow2To31 ? _mm_cvtepi32_ps(n) : u32_to_float(n);
    // Without padding the sum below is n + 0: skip it (the scalar leaf ISA's options).
    if (!padded_leaves_) return nf;
    const std::uint32_t w = static_cast<std::uint32_t>(opt_.leaf_block_width);
    __m128i empty;  // padded - n, the empty slots of the last block
    if (block_shift_ >= 0) {
      // (-n) mod w for a power of two w: the same as ((n + w - 1) >> shift << shift) - n
      // modulo 2^32, and below w <= 64, so the signed conversion is exact.
      empty = _mm_and_si128(_mm_sub_epi32(_mm_setzero_si128(), n), _mm_set1_epi32(static_cast<int>(w - 1)));
      return _mm_add_ps(nf, _mm_mul_ps(_mm_set1_ps(opt_.padding_cost), _mm_cvtepi32_ps(empty)));
    }
    alignas(16) std::uint32_t lanes[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(lanes), n);
    for (std::uint32_t& v : lanes) v = (v + w - 1) / w * w - v;
    empty = _mm_load_si128(reinterpret_cast<const __m128i*>(lanes));
    return _mm_add_ps(nf, _mm_mul_ps(_mm_set1_ps(opt_.padding_cost), u32_to_float(empty)));
  }

  // Unsigned lanes to float, rounded once as static_cast<float>(std::uint32_t): both halves
  // convert exactly and the one rounding is the sum's.
  static __m128 u32_to_float(__m128i v) {
    const __m128 high = _mm_cvtepi32_ps(_mm_srli_epi32(v, 16));
    const __m128 low = _mm_cvtepi32_ps(_mm_and_si128(v, _mm_set1_epi32(0xffff)));
    return _mm_add_ps(_mm_mul_ps(high, _mm_set1_ps(65536.0f)), low);
  }

  // Test cost of n primitives (BvhBuildOptions::leaf_slots; the sweep prices its lanes with
  // the SSE form above).
  float slots(std::uint32_t n) const { return opt_.leaf_slots(n); }
  static int shift_of(int w) {
    for (int k = 0; k < 7; ++k)
      if (w == 1 << k) return k;
    return -1;
  }

  void bin(const Task& t, const BinGrid& grid, bool parallel) {
    if (!parallel) {
      bins_.clear(grid.nb);
      return bins_.add(items_, t.begin, t.end, grid);
    }
    // Fixed chunks joined in a fixed order: the same bins for any number of threads.
    const Bins empty(opt_.bins);  // constructed cleared
    bins_ = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<std::uint32_t>(t.begin, t.end, kBinChunk), empty,
        [&](const tbb::blocked_range<std::uint32_t>& r, Bins acc) {
          const ExactSubnormals exact;
          acc.add(items_, r.begin(), r.end(), grid);
          return acc;
        },
        [&](Bins a, const Bins& b) {
          a.merge(b, grid.nb);
          return a;
        });
  }

  // In-place partition by bin, branch-free (Lomuto with an unconditional swap: the side
  // of a primitive is a coin toss to the branch predictor), bounding the children's
  // centroids on the way: lanes of the other side are blended to the empty bound so
  // that one min and one max per side serve both sides.
  void partition(const Task& t, const BinGrid& grid, int a, int best_bin, Split& out) {
    if (a == 0) return partition_on<0>(t, grid, best_bin, out);
    if (a == 1) return partition_on<1>(t, grid, best_bin, out);
    return partition_on<2>(t, grid, best_bin, out);
  }

  // partition() along axis A: the side computed in lane A, as binning computed the bin.
  template <int A>
  void partition_on(const Task& t, const BinGrid& grid, int best_bin, Split& out) {
    const __m128 pos_inf = _mm_set1_ps(kInf);
    const __m128 neg_inf = _mm_set1_ps(-kInf);
    // The grid as registers: the item stores below could alias its fields, which would
    // make the compiler reload them for every item.
    const __m128 cmin = load3(grid.cmin);
    const __m128 scale = _mm_setr_ps(grid.scale[0], grid.scale[1], grid.scale[2], 0.0f);
    const __m128i last_bin = _mm_set1_epi32(grid.nb - 1);
    const __m128i first_right = _mm_set1_epi32(best_bin + 1);
    Box4 lc, rc;
    std::uint32_t mid = t.begin;
    for (std::uint32_t i = t.begin; i < t.end; ++i) {
      const Item item = items_[i];
      const __m128 c = center4(load_lo(item), load_hi(item));
      // Its bin, clamped because c == cmax maps to nb (c >= cmin, so the index is not
      // negative on the active axis A); left when below first_right, lane A broadcast.
      const __m128i b = _mm_min_epi32(_mm_cvttps_epi32(_mm_mul_ps(_mm_sub_ps(c, cmin), scale)), last_bin);
      const __m128i left = _mm_shuffle_epi32(_mm_cmpgt_epi32(first_right, b), _MM_SHUFFLE(A, A, A, A));
      items_[i] = items_[mid];
      items_[mid] = item;
      mid -= static_cast<std::uint32_t>(_mm_cvtsi128_si32(left));  // -1 on the left
      const __m128 is_left = _mm_castsi128_ps(left);
      lc.extend(_mm_blendv_ps(pos_inf, c, is_left), _mm_blendv_ps(neg_inf, c, is_left));
      rc.extend(_mm_blendv_ps(c, pos_inf, is_left), _mm_blendv_ps(c, neg_inf, is_left));
    }
    // Child bounds from the bins; the partition recomputed the same bin indices.
    Box4 lbox, rbox;
    std::uint32_t left_count = 0;
    for (int b = 0; b <= best_bin; ++b) {
      lbox.extend(bins_.at(A, b));
      left_count += bin_count(bins_.at(A, b));
    }
    for (int b = best_bin + 1; b < grid.nb; ++b) rbox.extend(bins_.at(A, b));
    assert(mid - t.begin == left_count && "partition disagrees with the bins");
    (void)left_count;
    out = {mid, lbox.to_bbox(), rbox.to_bbox(), lc.to_bbox(), rc.to_bbox()};
  }

  // Object-median split: along the largest centroid axis when the centroids are
  // finite and spread, else (coincident centroids, invalid primitives) by position.
  // Scalar code: the invalid primitives' bounds may be NaN or infinite.
  bool median_split(const Task& t, Split& out) {
    const std::uint32_t mid = t.begin + (t.end - t.begin) / 2;
    if (t.spatial && !t.cbox.empty()) {
      const int axis = t.cbox.largest_axis();
      if (t.cbox.hi[axis] > t.cbox.lo[axis]) {
        std::nth_element(items_ + t.begin, items_ + mid, items_ + t.end,
                         [axis](const Item& a, const Item& b) { return a.center(axis) < b.center(axis); });
      }
    }
    out = Split{mid, {}, {}, {}, {}};
    bound(t.begin, mid, t.spatial, out.lbox, out.lcbox);
    bound(mid, t.end, t.spatial, out.rbox, out.rcbox);
    return true;
  }

  // Bounds of items [begin, end) and, with `centroids`, of their centroids, bit for bit as
  // BBox::extend grows them one item at a time: minps(new, acc) is new < acc ? new : acc,
  // so NaN bounds of invalid primitives are ignored the same way.
  void bound(std::uint32_t begin, std::uint32_t end, bool centroids, BBox& box, BBox& cbox) const {
    Box4 b, c;
    for (std::uint32_t i = begin; i < end; ++i) {
      const __m128 lo = load_lo(items_[i]);
      const __m128 hi = load_hi(items_[i]);
      b.lo = _mm_min_ps(lo, b.lo);
      b.hi = _mm_max_ps(hi, b.hi);
      if (!centroids) continue;
      const __m128 center = center4(lo, hi);
      c.lo = _mm_min_ps(center, c.lo);
      c.hi = _mm_max_ps(center, c.hi);
    }
    box = b.to_bbox();
    if (centroids) cbox = c.to_bbox();
  }

  // A node of two primitives: SAH leaf-or-split (as in split()) with the children
  // being the two primitives themselves.
  bool split_pair(const Task& t, const BBox& box, Split& out) {
    const BBox p = items_[t.begin].box();
    const BBox q = items_[t.begin + 1].box();
    if (2 <= opt_.max_leaf_size) {
      const float area = box.half_area();
      const float ci = opt_.intersection_cost;
      const float leaf = ci * slots(2) * area;
      const float split_cost = opt_.traversal_cost * area + ci * slots(1) * (p.half_area() + q.half_area());
      if (!(split_cost < leaf)) return false;
    }
    const glm::vec3 cp = p.center();
    const glm::vec3 cq = q.center();
    out = {t.begin + 1, p, q, BBox{cp, cp}, BBox{cq, cq}};
    return true;
  }

  const BvhBuildOptions& opt_;
  Item* items_;
  Bins bins_;
  // best_plane()'s sweep state, per bin (members: no 8 KB stack frame, probed page by page,
  // per node).
  mutable __m128 left_area_[256];
  mutable __m128i left_count_[256];
  int block_shift_ = shift_of(opt_.leaf_block_width);  // log2(leaf_block_width), -1 if not a power of two
  bool padded_leaves_ = opt_.leaf_block_width > 1 && opt_.padding_cost > 0.0f;  // slots(n) > n for some n
};

}  // namespace volley::core::bvh_build_detail
