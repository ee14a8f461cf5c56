// Binned SAH BVH builder (Wald 2007) and BVH statistics. See bvh.h for the contract.
//
// The passes over a node's primitives (binning, partition, the first pass over the input
// and the median split's bounds) and the sweep over the bins use SSE2/SSE4.1 intrinsics,
// part of the x86-64-v2 baseline every volley object is compiled for: a box is two 4-lane
// registers (x, y, z and a 4th lane: 0, or a bin's count), extended with one minps and one
// maxps; the sweep prices the three axes in the lanes of one register. Each is written to
// evaluate the float operations of the scalar formulation it replaced (BBox, one axis at
// a time), so the tree is bit for bit the one those gave (perf/build.md).
//
// Parallel build (oneTBB): a node of at least kTaskNode primitives is split by the
// top-level recursion, which builds its two children as parallel tasks (and bins the
// biggest nodes in parallel chunks, merged in a fixed order); a smaller node is built by
// a sequential SubtreeBuilder into a node array of its own, and the arrays are spliced
// into one depth-first layout at the end. Which path a node takes depends only on its
// primitive count, never on the number of threads, so the tree is the same for any.
#include <immintrin.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_scan.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/bvh.h"
#include "core/bvh_bins.h"
#include "core/large_alloc.h"

namespace volley::core {
namespace {

// Item, Box4, BinGrid, Bins and their SSE helpers (bvh_bins.h).
using namespace bvh_build_detail;

// Nodes with at least this many primitives become parallel tasks; below it a subtree is
// built sequentially (big enough that a task's overhead is noise, small enough that a
// megatriangle scene makes hundreds of tasks).
constexpr std::uint32_t kTaskNode = 1u << 12;
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

// ceil(log2(n)) for n >= 1.
int ceil_log2(std::uint32_t n) {
  int k = 0;
  while ((std::uint64_t{1} << k) < n) ++k;
  return k;
}

void check_options(const BvhBuildOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("build_bvh: " + what); };
  if (o.bins < 2 || o.bins > 256) fail("bins must be in [2, 256], got " + std::to_string(o.bins));
  if (o.max_leaf_size < 1) fail("max_leaf_size must be >= 1");
  if (o.min_leaf_size < 1 || o.min_leaf_size > o.max_leaf_size) fail("min_leaf_size must be in [1, max_leaf_size]");
  if (!(o.traversal_cost > 0.0f) || !(o.intersection_cost > 0.0f))
    fail("traversal_cost and intersection_cost must be > 0");
  if (o.leaf_block_width < 1 || o.leaf_block_width > 64)
    fail("leaf_block_width must be in [1, 64], got " + std::to_string(o.leaf_block_width));
  if (!(o.padding_cost >= 0.0f && o.padding_cost <= 1.0f)) fail("padding_cost must be in [0, 1]");
}

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
    const bool depth_guard = static_cast<int>(t.depth) + ceil_log2(count) + 1 >= kBvhMaxDepth;
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
    // hold most nodes, and there 8 bins find planes as good for a faster build (perf/build.md).
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

  // Test cost of n primitives in leaf blocks of leaf_block_width, in primitive tests: n plus
  // padding_cost per empty slot of the last block (a shift for the usual power-of-two
  // widths: the sweep asks twice per bin).
  float slots(std::uint32_t n) const {
    const std::uint32_t w = static_cast<std::uint32_t>(opt_.leaf_block_width);
    const std::uint32_t padded =
        block_shift_ >= 0 ? ((n + w - 1) >> block_shift_) << block_shift_ : (n + w - 1) / w * w;
    return static_cast<float>(n) + opt_.padding_cost * static_cast<float>(padded - n);
  }
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

// Builds the subtree of one task depth first into its own node array: nodes[0] is the
// task's node, child indices are local, leaves index the shared item array.
class SubtreeBuilder {
 public:
  SubtreeBuilder(const BvhBuildOptions& options, Item* items) : splitter_(options, items) {}

  // Callers hold an ExactSubnormals (Builder::build_top).
  std::vector<BvhNode> build(Task root, const BBox& box) {
    nodes_.reserve(2 * std::size_t{root.end - root.begin} - 1);
    nodes_.push_back({box, 0, 0});
    root.node = 0;
    // Iteratively: the task stack holds at most one pending sibling per level.
    tasks_.push_back(root);
    while (!tasks_.empty()) {
      const Task t = tasks_.back();
      tasks_.pop_back();
      Split s;
      if (!splitter_.split(t, nodes_[t.node].box, false, s)) {
        nodes_[t.node].first_or_child = t.begin;
        nodes_[t.node].count = t.end - t.begin;
        continue;
      }
      const std::uint32_t child = static_cast<std::uint32_t>(nodes_.size());
      nodes_[t.node].first_or_child = child;
      nodes_[t.node].count = 0;
      nodes_.push_back({s.lbox, 0, 0});
      nodes_.push_back({s.rbox, 0, 0});
      // Right first so that the left child is processed next (depth-first layout).
      tasks_.push_back({child + 1, s.mid, t.end, t.depth + 1, s.rcbox, t.spatial});
      tasks_.push_back({child, t.begin, s.mid, t.depth + 1, s.lcbox, t.spatial});
    }
    return std::move(nodes_);
  }

 private:
  Splitter splitter_;
  std::vector<BvhNode> nodes_;
  std::vector<Task> tasks_;
};

// A node of the parallel top levels: either split (left and right set) or the root of
// a subtree built sequentially (`subtree`, root first, local child indices).
struct TopNode {
  BBox box;
  std::unique_ptr<TopNode> left, right;
  std::vector<BvhNode> subtree;
};

class Builder {
 public:
  Builder(std::span<const BBox> boxes, const BvhBuildOptions& options)
      : opt_(options), n_(static_cast<std::uint32_t>(boxes.size())), items_(boxes.size()) {
    // Valid primitives (non-empty box, finite centroid, hence finite bounds) go to the
    // front in input order, the others to the back (written back to front, reversed below);
    // both sets are bounded. A parallel prefix scan over the counts: one pass on one thread,
    // on more a counting pass where oneTBB needs the prefix of a range it has not reached
    // (serial, this pass showed in many-thread builds). The bounds join with min / max that
    // keep the first of equal values (as BBox::extend): the same for any split.
    const Scan total = tbb::parallel_scan(
        tbb::blocked_range<std::uint32_t>(0, n_, kInputChunk), Scan{},
        [&](const tbb::blocked_range<std::uint32_t>& r, Scan sum, bool is_final) {
          const ExactSubnormals exact;
          for (std::uint32_t i = r.begin(); i < r.end(); ++i) {
            const Classified p = classify(boxes[i]);
            if (is_final) {
              Item& item = items_[p.valid ? sum.valid : n_ - 1 - sum.invalid];
              _mm_storeu_ps(&item.lo.x, p.lo);
              _mm_storeu_ps(&item.hi.x,
                            _mm_castsi128_ps(_mm_insert_epi32(_mm_castps_si128(p.hi), static_cast<int>(i), 3)));
            }
            if (p.valid) {
              ++sum.valid;
              sum.box.lo = _mm_min_ps(p.lo, sum.box.lo);
              sum.box.hi = _mm_max_ps(p.hi, sum.box.hi);
              sum.cbox.lo = _mm_min_ps(p.c, sum.cbox.lo);
              sum.cbox.hi = _mm_max_ps(p.c, sum.cbox.hi);
            } else {
              ++sum.invalid;
              sum.invalid_box.extend(boxes[i]);
            }
          }
          return sum;
        },
        [](const Scan& left, const Scan& right) {
          Scan s = left;
          s.valid += right.valid;
          s.invalid += right.invalid;
          s.box.lo = _mm_min_ps(right.box.lo, left.box.lo);
          s.box.hi = _mm_max_ps(right.box.hi, left.box.hi);
          s.cbox.lo = _mm_min_ps(right.cbox.lo, left.cbox.lo);
          s.cbox.hi = _mm_max_ps(right.cbox.hi, left.cbox.hi);
          s.invalid_box.extend(right.invalid_box);
          return s;
        });
    valid_box_ = total.box.to_bbox();
    valid_cbox_ = total.cbox.to_bbox();
    invalid_box_ = total.invalid_box;
    n_valid_ = total.valid;
    std::reverse(items_.get() + n_valid_, items_.get() + n_);
  }

  Bvh run() {
    TopNode root;
    root.box = valid_box_;
    root.box.extend(invalid_box_);
    if (n_valid_ == n_ || n_valid_ == 0) {
      build_top(root, {0, 0, n_, 0, valid_cbox_, n_valid_ == n_});
    } else {
      // Root = (valid subtree, invalid subtree).
      root.left = std::make_unique<TopNode>();
      root.right = std::make_unique<TopNode>();
      root.left->box = valid_box_;
      root.right->box = invalid_box_;
      tbb::parallel_invoke(
          [&] {
            build_top(*root.left, {0, 0, n_valid_, 1, valid_cbox_, true});
          },
          [&] {
            build_top(*root.right, {0, n_valid_, n_, 1, BBox{}, false});
          });
    }

    Bvh bvh;
    bvh.nodes.reserve(2 * std::size_t{n_} - 1);
    bvh.nodes.push_back({});
    std::vector<Splice> splices;
    place(root, 0, bvh.nodes, splices);
    tbb::parallel_for(std::size_t{0}, splices.size(), [&](std::size_t k) { splice(splices[k], bvh.nodes); });
    bvh.prim_index.resize(n_);
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, n_, 1u << 14), [&](const auto& r) {
      for (std::uint32_t i = r.begin(); i < r.end(); ++i) bvh.prim_index[i] = items_[i].prim;
    });
    return bvh;
  }

 private:
  // A sequentially built subtree's place in the final array: its root at `root`, its
  // other nodes (local index j >= 1) at base + j - 1.
  struct Splice {
    const std::vector<BvhNode>* nodes;
    std::uint32_t root;
    std::uint32_t base;
  };

  // Recursion depth <= tree depth < kBvhMaxDepth.
  void build_top(TopNode& node, const Task& t) {
    const ExactSubnormals exact;
    const std::uint32_t count = t.end - t.begin;
    if (count < kTaskNode || !t.spatial) {
      node.subtree = SubtreeBuilder(opt_, items_.get()).build(t, node.box);
      return;
    }
    Split s;
    if (!Splitter(opt_, items_.get()).split(t, node.box, count >= kParallelBinning, s)) {
      node.subtree = {BvhNode{node.box, t.begin, count}};
      return;
    }
    node.left = std::make_unique<TopNode>();
    node.right = std::make_unique<TopNode>();
    node.left->box = s.lbox;
    node.right->box = s.rbox;
    tbb::parallel_invoke(
        [&] {
          build_top(*node.left, {0, t.begin, s.mid, t.depth + 1, s.lcbox, t.spatial});
        },
        [&] {
          build_top(*node.right, {0, s.mid, t.end, t.depth + 1, s.rcbox, t.spatial});
        });
  }

  // Lays out the top levels depth first as SubtreeBuilder would (a node's children as a
  // pair, then the left subtree, then the right) and reserves room for each subtree.
  static void place(const TopNode& node, std::uint32_t index, std::vector<BvhNode>& out, std::vector<Splice>& splices) {
    if (node.left) {
      const std::uint32_t child = static_cast<std::uint32_t>(out.size());
      out[index] = {node.box, child, 0};
      out.push_back({node.left->box, 0, 0});
      out.push_back({node.right->box, 0, 0});
      place(*node.left, child, out, splices);
      place(*node.right, child + 1, out, splices);
      return;
    }
    const std::uint32_t base = static_cast<std::uint32_t>(out.size());
    out.resize(out.size() + node.subtree.size() - 1);
    splices.push_back({&node.subtree, index, base});
  }

  static void splice(const Splice& s, std::vector<BvhNode>& out) {
    const std::vector<BvhNode>& sub = *s.nodes;
    auto to_global = [&](std::uint32_t j) { return j == 0 ? s.root : s.base + j - 1; };
    for (std::uint32_t j = 0; j < sub.size(); ++j) {
      BvhNode node = sub[j];
      if (!node.is_leaf()) node.first_or_child = to_global(node.first_or_child);
      out[to_global(j)] = node;
    }
  }

  // Input boxes per task of the constructor's scan.
  static constexpr std::uint32_t kInputChunk = 1u << 14;
  // The constructor's running sums: valid and invalid counts, their bounds.
  struct Scan {
    std::uint32_t valid = 0, invalid = 0;
    Box4 box, cbox;
    BBox invalid_box;
  };
  // An input box as an item's two lanes (lo, 0), (hi, -), its centroid, and whether it is
  // valid: !b.empty() (lo <= hi, false for NaN) and a finite centroid (|c| < inf).
  struct Classified {
    __m128 lo, hi, c;
    bool valid;
  };
  static Classified classify(const BBox& b) {
    // Two loads inside the 24-byte box: lo.x lo.y lo.z hi.x and lo.z hi.x hi.y hi.z.
    const __m128 lo = _mm_and_ps(_mm_loadu_ps(&b.lo.x), xyz_mask());
    const __m128 upper = _mm_loadu_ps(&b.lo.z);
    const __m128 hi = _mm_and_ps(_mm_shuffle_ps(upper, upper, _MM_SHUFFLE(0, 3, 2, 1)), xyz_mask());
    const __m128 c = center4(lo, hi);  // BBox::center()
    const __m128 ok =
        _mm_and_ps(_mm_cmple_ps(lo, hi), _mm_cmplt_ps(_mm_andnot_ps(_mm_set1_ps(-0.0f), c), _mm_set1_ps(kInf)));
    return {lo, hi, c, (_mm_movemask_ps(ok) & 7) == 7};
  }

  const BvhBuildOptions opt_;
  const std::uint32_t n_;
  LargeArray<Item> items_;  // uninitialised: every slot is written above
  std::uint32_t n_valid_ = 0;
  BBox valid_box_, valid_cbox_, invalid_box_;
};

}  // namespace

Bvh build_bvh(std::span<const BBox> prim_boxes, const BvhBuildOptions& options) {
  check_options(options);
  if (prim_boxes.size() >= std::numeric_limits<std::uint32_t>::max())
    throw std::length_error("build_bvh: more than 2^32 - 2 primitives");
  if (prim_boxes.empty()) return Bvh{};
  return Builder(prim_boxes, options).run();
}
namespace {
// One subtree's terms of BvhStats. Its two halves in parallel for the top six levels (2^6
// tasks: enough for 16 threads), below a depth-first walk with an explicit stack, left child
// first (the order the builder lays nodes out in, so the walk reads the array nearly
// sequentially). Summed in a fixed order: the same for any number of threads.
struct SubtreeStats {
  double cost = 0.0;
  std::size_t prims = 0, leaves = 0, depth = 0;
};
SubtreeStats subtree_stats(const Bvh& bvh, const BvhBuildOptions& options, std::uint32_t root, std::size_t root_depth) {
  SubtreeStats s;
  const BvhNode& top = bvh.nodes[root];
  if (root_depth < 6 && !top.is_leaf()) {
    SubtreeStats l, r;
    const std::uint32_t c = top.first_or_child;
    tbb::parallel_invoke([&] { l = subtree_stats(bvh, options, c, root_depth + 1); },
                         [&] { r = subtree_stats(bvh, options, c + 1, root_depth + 1); });
    return {options.traversal_cost * top.box.half_area() + l.cost + r.cost, l.prims + r.prims, l.leaves + r.leaves,
            std::max(l.depth, r.depth)};
  }
  std::vector<std::pair<std::uint32_t, std::size_t>> stack{{root, root_depth}};
  while (!stack.empty()) {
    const auto [index, depth] = stack.back();
    stack.pop_back();
    const BvhNode& node = bvh.nodes[index];
    const double area = node.box.half_area();
    s.depth = std::max(s.depth, depth);
    if (node.is_leaf()) {
      ++s.leaves;
      s.prims += node.count;
      s.cost += options.intersection_cost * area * node.count;
    } else {
      s.cost += options.traversal_cost * area;
      stack.push_back({node.first_or_child + 1, depth + 1});
      stack.push_back({node.first_or_child, depth + 1});
    }
  }
  return s;
}
}  // namespace

BvhStats bvh_stats(const Bvh& bvh, const BvhBuildOptions& options) {
  BvhStats s;
  s.nodes = bvh.nodes.size();
  s.bytes = bvh.nodes.size() * sizeof(BvhNode) + bvh.prim_index.size() * sizeof(std::uint32_t);
  if (bvh.nodes.empty()) return s;
  const SubtreeStats t = subtree_stats(bvh, options, 0, 0);
  s.depth = t.depth;
  s.leaves = t.leaves;
  const double root_area = bvh.nodes[0].box.half_area();
  s.sah_cost =
      root_area > 0.0 && std::isfinite(root_area) ? t.cost / root_area : std::numeric_limits<double>::quiet_NaN();
  s.mean_leaf_size = static_cast<double>(t.prims) / static_cast<double>(s.leaves);
  return s;
}

}  // namespace volley::core
