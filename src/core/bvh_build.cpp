// Binned SAH BVH builder (Wald 2007) and BVH statistics. See bvh.h for the contract.
//
// The two passes over a node's primitives (binning, partition) use SSE2/SSE4.1
// intrinsics, part of the x86-64-v2 baseline every volley object is compiled for:
// a box is two 4-lane registers (x, y, z and an unused 4th lane), extended with one
// minps and one maxps. Everything else is plain scalar code.
#include <immintrin.h>

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/bvh.h"

namespace volley::core {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

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

// A node still to be processed: its items are items[begin, end), its box is already
// stored in nodes[node], cbox bounds the items' centroids.
struct Task {
  std::uint32_t node;
  std::uint32_t begin;
  std::uint32_t end;
  std::uint32_t depth;
  BBox cbox;
  bool spatial;  // false for the subtree of invalid primitives: split by index only
};

// ceil(log2(n)) for n >= 1.
int ceil_log2(std::uint32_t n) {
  int k = 0;
  while ((std::uint64_t{1} << k) < n) ++k;
  return k;
}

void check_options(const BvhBuildOptions& o) {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("build_bvh: " + what);
  };
  if (o.bins < 2 || o.bins > 256) fail("bins must be in [2, 256], got " + std::to_string(o.bins));
  if (o.max_leaf_size < 1) fail("max_leaf_size must be >= 1");
  if (o.min_leaf_size < 1 || o.min_leaf_size > o.max_leaf_size)
    fail("min_leaf_size must be in [1, max_leaf_size]");
  if (!(o.traversal_cost > 0.0f) || !(o.intersection_cost > 0.0f))
    fail("traversal_cost and intersection_cost must be > 0");
}

class Builder {
 public:
  Builder(std::span<const BBox> boxes, const BvhBuildOptions& options)
      : opt_(options), nbins_(options.bins) {
    const std::size_t n = boxes.size();
    items_.resize(n);
    bins_.resize(3 * static_cast<std::size_t>(nbins_));
    bin_count_.resize(3 * static_cast<std::size_t>(nbins_));
    left_area_.resize(nbins_);
    left_count_.resize(nbins_);
    bvh_.nodes.reserve(2 * n - 1);
    bvh_.prim_index.resize(n);

    // Valid primitives (non-empty box, finite centroid, hence finite bounds) go to
    // the front in input order, the others to the back; both sets are bounded.
    std::uint32_t front = 0;
    std::uint32_t back = static_cast<std::uint32_t>(n);
    for (std::size_t i = 0; i < n; ++i) {
      const BBox& b = boxes[i];
      const glm::vec3 c = b.center();
      const bool valid =
          !b.empty() && std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z);
      const Item item{b.lo, 0.0f, b.hi, static_cast<std::uint32_t>(i)};
      if (valid) {
        items_[front++] = item;
        valid_box_.extend(b);
        valid_cbox_.extend(c);
      } else {
        items_[--back] = item;
        invalid_box_.extend(b);
      }
    }
    // The invalid ones were stored back to front; restore input order among them.
    std::reverse(items_.begin() + back, items_.end());
    n_valid_ = front;
  }

  Bvh run() {
    const std::uint32_t n = static_cast<std::uint32_t>(items_.size());
    BBox root_box = valid_box_;
    root_box.extend(invalid_box_);
    bvh_.nodes.push_back({root_box, 0, 0});
    if (n_valid_ == n || n_valid_ == 0) {
      tasks_.push_back({0, 0, n, 0, valid_cbox_, n_valid_ == n});
    } else {
      // Root = (valid subtree, invalid subtree).
      bvh_.nodes[0].first_or_child = 1;
      bvh_.nodes.push_back({valid_box_, 0, 0});
      bvh_.nodes.push_back({invalid_box_, 0, 0});
      tasks_.push_back({2, n_valid_, n, 1, BBox{}, false});
      tasks_.push_back({1, 0, n_valid_, 1, valid_cbox_, true});
    }
    // Depth first, iteratively: the task stack holds at most one pending sibling
    // per level.
    while (!tasks_.empty()) {
      const Task task = tasks_.back();
      tasks_.pop_back();
      process(task);
    }
    for (std::uint32_t i = 0; i < n; ++i) bvh_.prim_index[i] = items_[i].prim;
    return std::move(bvh_);
  }

 private:
  // Bin index of centroid coordinate c on an active axis (finite extent > 0) of nb
  // bins from cmin with scale nb / extent; clamped because c == cmax maps to nb.
  // c >= cmin, so the index is not negative.
  static int bin_of(float c, float cmin, float scale, int nb) {
    const int b = static_cast<int>((c - cmin) * scale);
    return b < nb - 1 ? b : nb - 1;
  }

  void make_leaf(const Task& t) {
    bvh_.nodes[t.node].first_or_child = t.begin;
    bvh_.nodes[t.node].count = t.end - t.begin;
  }

  // Allocates the child pair of t.node and queues both children.
  void split(const Task& t, std::uint32_t mid, const BBox& lbox, const BBox& rbox,
             const BBox& lcbox, const BBox& rcbox) {
    const std::uint32_t child = static_cast<std::uint32_t>(bvh_.nodes.size());
    bvh_.nodes[t.node].first_or_child = child;
    bvh_.nodes[t.node].count = 0;
    bvh_.nodes.push_back({lbox, 0, 0});
    bvh_.nodes.push_back({rbox, 0, 0});
    // Right first so that the left child is processed next (depth-first layout).
    tasks_.push_back({child + 1, mid, t.end, t.depth + 1, rcbox, t.spatial});
    tasks_.push_back({child, t.begin, mid, t.depth + 1, lcbox, t.spatial});
  }

  // Object-median split: along the largest centroid axis when the centroids are
  // finite and spread, else (coincident centroids, invalid primitives) by position.
  // Scalar code: the invalid primitives' bounds may be NaN or infinite.
  void median_split(const Task& t) {
    const std::uint32_t mid = t.begin + (t.end - t.begin) / 2;
    if (t.spatial && !t.cbox.empty()) {
      const int axis = t.cbox.largest_axis();
      if (t.cbox.hi[axis] > t.cbox.lo[axis]) {
        std::nth_element(items_.begin() + t.begin, items_.begin() + mid, items_.begin() + t.end,
                         [axis](const Item& a, const Item& b) {
                           return a.center(axis) < b.center(axis);
                         });
      }
    }
    BBox lbox, rbox, lcbox, rcbox;
    for (std::uint32_t i = t.begin; i < t.end; ++i) {
      const BBox b = items_[i].box();
      (i < mid ? lbox : rbox).extend(b);
      if (t.spatial) (i < mid ? lcbox : rcbox).extend(b.center());
    }
    split(t, mid, lbox, rbox, lcbox, rcbox);
  }

  // A node of two primitives: SAH leaf-or-split (as in process()) with the children
  // being the two primitives themselves.
  void split_pair(const Task& t) {
    const BBox p = items_[t.begin].box();
    const BBox q = items_[t.begin + 1].box();
    if (2 <= opt_.max_leaf_size) {
      const float area = bvh_.nodes[t.node].box.half_area();
      const float ci = opt_.intersection_cost;
      const float leaf = ci * 2.0f * area;
      const float split_cost = opt_.traversal_cost * area + ci * (p.half_area() + q.half_area());
      if (!(split_cost < leaf)) return make_leaf(t);
    }
    const glm::vec3 cp = p.center();
    const glm::vec3 cq = q.center();
    split(t, t.begin + 1, p, q, BBox{cp, cp}, BBox{cq, cq});
  }

  void process(const Task& t) {
    const std::uint32_t count = t.end - t.begin;
    const std::uint32_t max_leaf = static_cast<std::uint32_t>(opt_.max_leaf_size);
    if (count <= static_cast<std::uint32_t>(opt_.min_leaf_size)) return make_leaf(t);

    // Depth guard: median splits need ceil(log2(count)) more levels at most; take
    // them once the SAH could otherwise push a leaf to kBvhMaxDepth.
    const bool depth_guard = static_cast<int>(t.depth) + ceil_log2(count) + 1 >= kBvhMaxDepth;
    if (!t.spatial || depth_guard) {
      if (count <= max_leaf) return make_leaf(t);
      return median_split(t);
    }

    // Two primitives: the only split is one per child, no binning needed.
    if (count == 2) return split_pair(t);

    // Binning setup per axis: an axis takes part when its centroid extent is > 0 and
    // its scale finite (a subnormal extent would give scale = inf and NaN bins); an
    // axis that does not gets scale 0, so its primitives all land in bin 0, unused.
    // A node of count < bins primitives gets count bins: at most count of them can
    // be occupied anyway, and clearing and sweeping 3 x bins bins per node would
    // otherwise dominate the build for the many small nodes near the leaves.
    const int nb = count < static_cast<std::uint32_t>(nbins_) ? static_cast<int>(count) : nbins_;
    float scale[3];
    bool active[3];
    bool any_active = false;
    for (int a = 0; a < 3; ++a) {
      const float extent = t.cbox.hi[a] - t.cbox.lo[a];
      const float s = static_cast<float>(nb) / extent;
      active[a] = extent > 0.0f && std::isfinite(s) && s > 0.0f;
      scale[a] = active[a] ? s : 0.0f;
      any_active = any_active || active[a];
    }
    if (!any_active) {
      if (count <= max_leaf) return make_leaf(t);
      return median_split(t);
    }

    // Bin primitive boxes by centroid on the three axes in one pass (Wald 2007, sec. 3).
    for (int a = 0; a < 3; ++a) {
      std::fill_n(&bins_[a * nbins_], nb, Box4{});
      std::fill_n(&bin_count_[a * nbins_], nb, 0u);
    }
    {
      const __m128 cmin = load3(t.cbox.lo);
      const __m128 scale4 = _mm_setr_ps(scale[0], scale[1], scale[2], 0.0f);
      const __m128i last = _mm_set1_epi32(nb - 1);
      const __m128i first = _mm_setzero_si128();
      Box4* bx = &bins_[0];
      Box4* by = &bins_[nbins_];
      Box4* bz = &bins_[2 * nbins_];
      std::uint32_t* cx = &bin_count_[0];
      std::uint32_t* cy = &bin_count_[nbins_];
      std::uint32_t* cz = &bin_count_[2 * nbins_];
      for (std::uint32_t i = t.begin; i < t.end; ++i) {
        const __m128 lo = load_lo(items_[i]);
        const __m128 hi = load_hi(items_[i]);
        // Clamped on both sides: on an inactive axis whose centroid extent overflowed,
        // (c - cmin) * 0 is inf * 0 = NaN, which converts to INT_MIN.
        const __m128i k = _mm_max_epi32(
            _mm_min_epi32(
                _mm_cvttps_epi32(_mm_mul_ps(_mm_sub_ps(center4(lo, hi), cmin), scale4)), last),
            first);
        const int kx = _mm_cvtsi128_si32(k);
        const int ky = _mm_extract_epi32(k, 1);
        const int kz = _mm_extract_epi32(k, 2);
        bx[kx].extend(lo, hi);
        by[ky].extend(lo, hi);
        bz[kz].extend(lo, hi);
        ++cx[kx];
        ++cy[ky];
        ++cz[kz];
      }
    }

    // Sweep the bins from both sides to find the cheapest plane: cost in units of
    // intersection_cost * area, A_left N_left + A_right N_right.
    float best_cost = kInf;
    int best_axis = -1;
    int best_bin = -1;  // left side takes bins [0, best_bin]
    for (int a = 0; a < 3; ++a) {
      if (!active[a]) continue;
      const Box4* bins = &bins_[a * nbins_];
      const std::uint32_t* counts = &bin_count_[a * nbins_];
      Box4 acc;
      std::uint32_t n = 0;
      for (int b = 0; b < nb - 1; ++b) {
        acc.extend(bins[b]);
        n += counts[b];
        left_area_[b] = acc.half_area();
        left_count_[b] = n;
      }
      acc = Box4{};
      n = 0;
      for (int b = nb - 1; b > 0; --b) {
        acc.extend(bins[b]);
        n += counts[b];
        if (n == 0 || left_count_[b - 1] == 0) continue;
        const float cost = left_area_[b - 1] * static_cast<float>(left_count_[b - 1]) +
                           acc.half_area() * static_cast<float>(n);
        if (cost < best_cost) {
          best_cost = cost;
          best_axis = a;
          best_bin = b - 1;
        }
      }
    }

    // Leaf or split (SAH normalised by this node's area A; compared multiplied by A so
    // that A = 0, a node flat to a segment or a point, is no division by zero):
    // leaf cost  C_i N  vs  split cost  C_t + C_i (A_l N_l + A_r N_r) / A.
    const float area = bvh_.nodes[t.node].box.half_area();
    const float ci = opt_.intersection_cost;
    if (count <= max_leaf) {
      const float leaf = ci * static_cast<float>(count) * area;
      const float split_cost = opt_.traversal_cost * area + ci * best_cost;
      if (best_axis < 0 || !(split_cost < leaf)) return make_leaf(t);
    }
    // No plane separates the centroids (possible only when the areas overflow).
    if (best_axis < 0) return median_split(t);

    // In-place partition by bin, branch-free (Lomuto with an unconditional swap: the
    // side of a primitive is a coin toss to the branch predictor), bounding the
    // children's centroids on the way: lanes of the other side are blended to the
    // empty bound so that one min and one max per side serve both sides.
    const int a = best_axis;
    const float cmin = t.cbox.lo[a];
    const float s = scale[a];
    const __m128 pos_inf = _mm_set1_ps(kInf);
    const __m128 neg_inf = _mm_set1_ps(-kInf);
    Box4 lc, rc;
    std::uint32_t mid = t.begin;
    for (std::uint32_t i = t.begin; i < t.end; ++i) {
      const Item item = items_[i];
      const bool left = bin_of(item.center(a), cmin, s, nb) <= best_bin;
      items_[i] = items_[mid];
      items_[mid] = item;
      mid += left ? 1u : 0u;
      const __m128 c = center4(load_lo(item), load_hi(item));
      const __m128 is_left = _mm_castsi128_ps(_mm_set1_epi32(left ? -1 : 0));
      lc.extend(_mm_blendv_ps(pos_inf, c, is_left), _mm_blendv_ps(neg_inf, c, is_left));
      rc.extend(_mm_blendv_ps(c, pos_inf, is_left), _mm_blendv_ps(c, neg_inf, is_left));
    }
    // Child bounds from the bins; the partition recomputed the same bin indices.
    Box4 lbox, rbox;
    std::uint32_t left_count = 0;
    for (int b = 0; b <= best_bin; ++b) {
      lbox.extend(bins_[a * nbins_ + b]);
      left_count += bin_count_[a * nbins_ + b];
    }
    for (int b = best_bin + 1; b < nb; ++b) rbox.extend(bins_[a * nbins_ + b]);
    assert(mid - t.begin == left_count && "partition disagrees with the bins");
    (void)left_count;
    split(t, mid, lbox.to_bbox(), rbox.to_bbox(), lc.to_bbox(), rc.to_bbox());
  }

  BvhBuildOptions opt_;
  int nbins_;
  Bvh bvh_;
  std::vector<Item> items_;
  std::vector<Box4> bins_;              // 3 axes x nbins_: bounds of the primitives binned
  std::vector<std::uint32_t> bin_count_;  // 3 axes x nbins_: primitives per bin
  std::vector<float> left_area_;        // sweep: area of bins [0, b]
  std::vector<std::uint32_t> left_count_;  // sweep: primitives in bins [0, b]
  std::vector<Task> tasks_;
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

BvhStats bvh_stats(const Bvh& bvh, const BvhBuildOptions& options) {
  BvhStats s;
  s.nodes = bvh.nodes.size();
  s.bytes = bvh.nodes.size() * sizeof(BvhNode) + bvh.prim_index.size() * sizeof(std::uint32_t);
  if (bvh.nodes.empty()) return s;

  // Depth-first walk with an explicit stack of (node, depth).
  double cost = 0.0;
  std::size_t prims = 0;
  std::vector<std::pair<std::uint32_t, std::size_t>> stack{{0u, 0u}};
  while (!stack.empty()) {
    const auto [index, depth] = stack.back();
    stack.pop_back();
    const BvhNode& node = bvh.nodes[index];
    const double area = node.box.half_area();
    s.depth = std::max(s.depth, depth);
    if (node.is_leaf()) {
      ++s.leaves;
      prims += node.count;
      cost += options.intersection_cost * area * node.count;
    } else {
      cost += options.traversal_cost * area;
      stack.push_back({node.first_or_child, depth + 1});
      stack.push_back({node.first_or_child + 1, depth + 1});
    }
  }
  const double root_area = bvh.nodes[0].box.half_area();
  s.sah_cost = root_area > 0.0 && std::isfinite(root_area)
                   ? cost / root_area
                   : std::numeric_limits<double>::quiet_NaN();
  s.mean_leaf_size = static_cast<double>(prims) / static_cast<double>(s.leaves);
  return s;
}

}  // namespace volley::core
