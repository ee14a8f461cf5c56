// The spatial-split builder (SBVH, Stich, Friedrich and Dietrich 2009): build_bvh_spatial
// in bvh.h. A node is split by the cheaper of the binned object split (centroids) and,
// where the object split's children overlap, a binned spatial split that cuts the
// triangles straddling its plane into two references with clipped boxes; a reference
// whose cut does not pay is kept whole on one side (reference unsplitting).
//
// Clipped boxes are conservative: the points where an edge crosses a plane are computed in
// double and rounded outwards, and every box is intersected with the triangle's own box,
// so the union of a triangle's references' boxes covers the whole triangle and no node
// box grows past what the triangle occupies.
//
// Parallel on oneTBB: a node of at least kTaskRefs references builds its two children as
// tasks, each into a node array of its own, joined depth first at the end; which nodes are
// tasks depends on their sizes only, so the tree is the same for any number of threads.
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/bvh.h"
#include "build/bvh_spatial_bins.h"

namespace volley::core {
namespace {

using spatial::bin_of;
using spatial::chop;
using spatial::Grid;

constexpr float kInf = std::numeric_limits<float>::infinity();
// Bins of the spatial split per axis (over the node's box, not its centroids).
constexpr int kSpatialBins = 32;
// Spatial splits are tried where the object split's children overlap by more than this
// fraction of the root's area (Stich et al.'s alpha: nearly everywhere near the root,
// rarely deep down where boxes are small).
constexpr float kOverlapAlpha = 1e-5f;
// Nodes of at most kSmallNode references get kSmallNodeSpatialBins (they are most of the
// nodes, and the references of a small node span many of its bins).
constexpr std::size_t kSmallNode = 64;
constexpr int kSmallNodeSpatialBins = 8;
// Object bins per axis at most (BvhBuildOptions::bins' range).
constexpr int kMaxBins = 256;
static_assert(kSpatialBins <= kMaxBins);
// Nodes of at least this many references build their children as parallel tasks.
constexpr std::size_t kTaskRefs = 4096;

struct Ref {
  BBox box;
  std::uint32_t prim;
};

float area(const BBox& b) { return b.half_area(); }

// A subtree built by one task: nodes[0] is its root, child indices local; its leaves'
// references in `prims` (first_or_child local to it too).
struct Subtree {
  std::vector<BvhNode> nodes;
  std::vector<std::uint32_t> prims;
  // Children built as tasks: node index here -> the task's subtree (joined later).
  std::vector<std::pair<std::uint32_t, std::unique_ptr<Subtree>>> tasks;
};

class SpatialBuilder {
 public:
  SpatialBuilder(const glm::vec3* vertices, const BvhBuildOptions& options, float root_area)
      : v_(vertices), opt_(options), root_area_(root_area) {}

  // Builds the subtree over `refs` (bounds `box`) at `depth` into `out`; its splits may add
  // up to `budget` references.
  void build(std::vector<Ref> refs, const BBox& box, std::uint32_t depth, std::size_t budget, Subtree& out) const {
    out.nodes.push_back({box, 0, 0});
    grow(std::move(refs), 0, depth, budget, out);
  }

 private:
  struct Choice {
    float cost = kInf;  // in units of intersection_cost * area
    int axis = -1;
    int bin = -1;  // the left side takes bins [0, bin]
    bool spatial = false;
  };

  float slots(std::size_t n) const { return opt_.leaf_slots(n); }

  // The budget of added references is shared by the children in proportion to their
  // sizes, so that it never depends on which task runs first.
  void grow(std::vector<Ref> refs, std::uint32_t node, std::uint32_t depth, std::size_t budget, Subtree& out) const {
    const BBox box = out.nodes[node].box;
    std::vector<Ref> left, right;
    if (!split(refs, box, depth, budget, left, right)) {
      out.nodes[node].first_or_child = static_cast<std::uint32_t>(out.prims.size());
      out.nodes[node].count = static_cast<std::uint32_t>(refs.size());
      for (const Ref& r : refs) out.prims.push_back(r.prim);
      return;
    }
    const std::size_t added = left.size() + right.size() - refs.size();
    std::vector<Ref>().swap(refs);
    const std::size_t rest = budget - added, total = left.size() + right.size();
    const auto lbudget = static_cast<std::size_t>(static_cast<double>(rest) * static_cast<double>(left.size()) /
                                                  static_cast<double>(total));
    const std::size_t rbudget = rest - lbudget;
    const std::uint32_t child = static_cast<std::uint32_t>(out.nodes.size());
    out.nodes[node].first_or_child = child;
    out.nodes[node].count = 0;
    out.nodes.push_back({bounds(left), 0, 0});
    out.nodes.push_back({bounds(right), 0, 0});
    if (left.size() + right.size() >= kTaskRefs) {
      auto l = std::make_unique<Subtree>(), r = std::make_unique<Subtree>();
      tbb::parallel_invoke([&] { build(std::move(left), out.nodes[child].box, depth + 1, lbudget, *l); },
                           [&] { build(std::move(right), out.nodes[child + 1].box, depth + 1, rbudget, *r); });
      out.tasks.emplace_back(child, std::move(l));
      out.tasks.emplace_back(child + 1, std::move(r));
      return;
    }
    grow(std::move(left), child, depth + 1, lbudget, out);
    grow(std::move(right), child + 1, depth + 1, rbudget, out);
  }

  static BBox bounds(const std::vector<Ref>& refs) {
    BBox b;
    for (const Ref& r : refs) b.extend(r.box);
    return b;
  }

  // False for a leaf; else the references of the two children.
  bool split(std::vector<Ref>& refs, const BBox& box, std::uint32_t depth, std::size_t budget, std::vector<Ref>& left,
             std::vector<Ref>& right) const {
    const std::size_t count = refs.size();
    if (count <= static_cast<std::size_t>(opt_.min_leaf_size)) return false;
    const bool forced = count > static_cast<std::size_t>(opt_.max_leaf_size);
    if (near_depth_limit(depth, count)) {
      if (!forced) return false;
      return median(refs, left, right);
    }
    BBox cbox;
    for (const Ref& r : refs) cbox.extend(r.box.center());
    BBox lobj, robj;
    const Choice best_object = object_choice(refs, cbox, lobj, robj);
    Choice best = best_object;
    if (best.axis >= 0 && budget > 0 && area(box_intersection(lobj, robj)) > kOverlapAlpha * root_area_) {
      const Choice s = spatial_choice(refs, box);
      if (s.cost < best.cost) best = s;
    }
    const float a = area(box);
    if (!forced) {
      const float leaf = opt_.intersection_cost * slots(count) * a;
      const float inner = opt_.traversal_cost * a + opt_.intersection_cost * best.cost;
      if (best.axis < 0 || !(inner < leaf)) return false;
    }
    if (best.axis < 0) return median(refs, left, right);
    if (best.spatial) {
      spatial_partition(refs, box, best, left, right);
      if (left.empty() || right.empty() || left.size() >= count || right.size() >= count ||
          left.size() + right.size() - count > budget) {
        // Not a usable cut after all (unsplitting moved everything to one side, or it
        // needs more references than the budget): the object split, as if never tried.
        left.clear(), right.clear();
        if (best_object.axis < 0) return median(refs, left, right);
        object_partition(refs, cbox, best_object, left, right);
      }
      return true;
    }
    object_partition(refs, cbox, best, left, right);
    return true;
  }

  // Binned SAH over the references' centroids; lobj and robj: the best split's children.
  Choice object_choice(const std::vector<Ref>& refs, const BBox& cbox, BBox& lobj, BBox& robj) const {
    Choice best;
    const int nb = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(opt_.bins), refs.size()));
    float scale[3];
    for (int axis = 0; axis < 3; ++axis) {
      const float extent = cbox.hi[axis] - cbox.lo[axis];
      scale[axis] = extent > 0.0f ? static_cast<float>(nb) / extent : 0.0f;
    }
    // One pass over the references bins all three axes.
    BBox bins[3][kMaxBins];
    std::size_t counts[3][kMaxBins] = {};
    for (const Ref& r : refs)
      for (int axis = 0; axis < 3; ++axis) {
        const int b = object_bin(r, axis, cbox.lo[axis], scale[axis], nb);
        bins[axis][b].extend(r.box);
        ++counts[axis][b];
      }
    for (int axis = 0; axis < 3; ++axis)
      if (scale[axis] > 0.0f) sweep(bins[axis], counts[axis], counts[axis], nb, axis, false, best);
    if (best.axis < 0) return best;
    for (int b = 0; b < nb; ++b) (b <= best.bin ? lobj : robj).extend(bins[best.axis][b]);
    return best;
  }

  static int object_bin(const Ref& r, int axis, float lo, float scale, int nb) {
    return bin_of((r.box.center()[axis] - lo) * scale, nb);
  }

  // The cheapest plane between bins: enter[b] references start in bin b, leave[b] end in it
  // (the same for object bins).
  void sweep(const BBox* bins, const std::size_t* enter, const std::size_t* leave, int nb, int axis, bool spatial,
             Choice& best) const {
    float left_area[kMaxBins];
    std::size_t left_count[kMaxBins];
    BBox acc;
    std::size_t n = 0;
    for (int b = 0; b < nb - 1; ++b) {
      acc.extend(bins[b]);
      n += enter[b];
      left_area[b] = area(acc);
      left_count[b] = n;
    }
    acc = BBox{};
    n = 0;
    for (int b = nb - 1; b > 0; --b) {
      acc.extend(bins[b]);
      n += leave[b];
      const std::size_t nl = left_count[b - 1];
      if (nl == 0 || n == 0) continue;
      const float cost = left_area[b - 1] * slots(nl) + area(acc) * slots(n);
      if (cost < best.cost) best = {cost, axis, b - 1, spatial};
    }
  }

  Grid grid_of(const BBox& box, std::size_t count) const {
    return {box, count <= kSmallNode ? kSmallNodeSpatialBins : kSpatialBins};
  }

  // Binned spatial split: each reference chopped into the bins it spans.
  Choice spatial_choice(const std::vector<Ref>& refs, const BBox& box) const {
    Choice best;
    const Grid grid = grid_of(box, refs.size());
    for (int axis = 0; axis < 3; ++axis) {
      if (!(box.hi[axis] > box.lo[axis])) continue;
      BBox bins[kSpatialBins];
      std::size_t enter[kSpatialBins] = {}, leave[kSpatialBins] = {};
      for (const Ref& r : refs) {
        const int first = grid.bin(axis, r.box.lo[axis]);
        const int last = grid.bin(axis, r.box.hi[axis]);
        ++enter[first];
        ++leave[last];
        if (first == last) {
          bins[first].extend(r.box);
          continue;
        }
        chop(v_ + 3 * std::size_t{r.prim}, r.box, grid, axis, first, last, bins);
      }
      sweep(bins, enter, leave, grid.nb, axis, true, best);
    }
    return best;
  }

  // References wholly below the plane go left, wholly above right; a straddling one is cut
  // in two, or kept whole on one side when that is cheaper (unsplitting).
  void spatial_partition(const std::vector<Ref>& refs, const BBox& box, const Choice& c, std::vector<Ref>& left,
                         std::vector<Ref>& right) const {
    const int axis = c.axis;
    const Grid grid = grid_of(box, refs.size());
    const float x = grid.plane(axis, c.bin + 1);
    BBox lbox, rbox;
    std::vector<const Ref*> straddling;
    for (const Ref& r : refs) {
      const int first = grid.bin(axis, r.box.lo[axis]);
      const int last = grid.bin(axis, r.box.hi[axis]);
      if (last <= c.bin) {
        left.push_back(r), lbox.extend(r.box);
      } else if (first > c.bin) {
        right.push_back(r), rbox.extend(r.box);
      } else {
        straddling.push_back(&r);
      }
    }
    for (const Ref* r : straddling) {
      const glm::vec3* v = v_ + 3 * std::size_t{r->prim};
      const BBox lpart = clipped_triangle_box(v, axis, -kInf, x, r->box);
      const BBox rpart = clipped_triangle_box(v, axis, x, kInf, r->box);
      if (lpart.empty() || rpart.empty()) {
        (lpart.empty() ? right : left).push_back(*r);
        (lpart.empty() ? rbox : lbox).extend(r->box);
        continue;
      }
      const float nl = slots(left.size() + 1), nr = slots(right.size() + 1);
      BBox lsplit = lbox, rsplit = rbox, lwhole = lbox, rwhole = rbox;
      lsplit.extend(lpart), rsplit.extend(rpart), lwhole.extend(r->box), rwhole.extend(r->box);
      const float cut = area(lsplit) * nl + area(rsplit) * nr;
      const float keep_left = area(lwhole) * nl + area(rbox) * slots(right.size());
      const float keep_right = area(lbox) * slots(left.size()) + area(rwhole) * nr;
      if (keep_left <= cut && keep_left <= keep_right) {
        left.push_back(*r), lbox = lwhole;
      } else if (keep_right <= cut) {
        right.push_back(*r), rbox = rwhole;
      } else {
        left.push_back({lpart, r->prim}), lbox = lsplit;
        right.push_back({rpart, r->prim}), rbox = rsplit;
      }
    }
  }

  void object_partition(const std::vector<Ref>& refs, const BBox& cbox, const Choice& c, std::vector<Ref>& left,
                        std::vector<Ref>& right) const {
    const int nb = static_cast<int>(std::min<std::size_t>(static_cast<std::size_t>(opt_.bins), refs.size()));
    const float scale = static_cast<float>(nb) / (cbox.hi[c.axis] - cbox.lo[c.axis]);
    for (const Ref& r : refs) (object_bin(r, c.axis, cbox.lo[c.axis], scale, nb) <= c.bin ? left : right).push_back(r);
  }

  // Half and half along the centroids' largest axis (or by position when they coincide).
  static bool median(std::vector<Ref>& refs, std::vector<Ref>& left, std::vector<Ref>& right) {
    BBox cbox;
    for (const Ref& r : refs) cbox.extend(r.box.center());
    const auto mid = refs.begin() + static_cast<std::ptrdiff_t>(refs.size() / 2);
    const int axis = cbox.largest_axis();
    if (cbox.hi[axis] > cbox.lo[axis])
      std::nth_element(refs.begin(), mid, refs.end(),
                       [axis](const Ref& a, const Ref& b) { return a.box.center()[axis] < b.box.center()[axis]; });
    left.assign(refs.begin(), mid);
    right.assign(mid, refs.end());
    return true;
  }

  const glm::vec3* v_;
  const BvhBuildOptions& opt_;
  const float root_area_;
};

// Appends `sub` (and the task subtrees below it) to `bvh` depth first; returns where its
// root went. Node `at` was reserved by the caller (the root: index 0).
void join(Subtree& sub, std::uint32_t at, Bvh& bvh) {
  // Local node j >= 1 goes to base + j - 1, the root to `at`.
  const std::uint32_t base = static_cast<std::uint32_t>(bvh.nodes.size());
  const std::uint32_t prim_base = static_cast<std::uint32_t>(bvh.prim_index.size());
  bvh.nodes.resize(bvh.nodes.size() + sub.nodes.size() - 1);
  bvh.prim_index.insert(bvh.prim_index.end(), sub.prims.begin(), sub.prims.end());
  auto global = [&](std::uint32_t j) { return j == 0 ? at : base + j - 1; };
  for (std::uint32_t j = 0; j < sub.nodes.size(); ++j) {
    BvhNode n = sub.nodes[j];
    n.first_or_child = n.is_leaf() ? n.first_or_child + prim_base : global(n.first_or_child);
    bvh.nodes[global(j)] = n;
  }
  for (auto& [node, task] : sub.tasks) join(*task, global(node), bvh);
}

}  // namespace

Bvh build_bvh_spatial(std::span<const BBox> prim_boxes, const glm::vec3* vertices, const BvhBuildOptions& options,
                      double max_growth) {
  check_build_options(options, "build_bvh_spatial");
  if (!(max_growth >= 0.0 && max_growth <= 16.0))
    throw std::invalid_argument("build_bvh_spatial: max_growth must be in [0, 16], got " + std::to_string(max_growth));
  const std::size_t n = prim_boxes.size();
  if (n >= std::numeric_limits<std::uint32_t>::max()) throw std::length_error("build_bvh_spatial: more than 2^32 - 2 primitives");
  std::vector<Ref> refs;
  refs.reserve(n);
  BBox root;
  for (std::size_t i = 0; i < n; ++i) {
    const BBox& b = prim_boxes[i];
    const glm::vec3 c = b.center();
    if (b.empty() || !(std::abs(c.x) < kInf && std::abs(c.y) < kInf && std::abs(c.z) < kInf)) continue;
    refs.push_back({b, static_cast<std::uint32_t>(i)});
    root.extend(b);
  }
  Bvh bvh;
  if (refs.empty()) return bvh;
  const auto budget = static_cast<std::size_t>(max_growth * static_cast<double>(refs.size()));
  const SpatialBuilder builder(vertices, options, root.half_area());
  Subtree top;
  builder.build(std::move(refs), root, 0, budget, top);
  bvh.nodes.resize(1);
  join(top, 0, bvh);
  return bvh;
}

}  // namespace volley::core
