// The top level over a layer's instances (Accel::add_instance): an 8-wide BVH collapsed
// from the binned-SAH binary BVH of their world boxes, one instance per leaf, walked
// near-first with the 8 children's slab tests side by side. Baseline code (SSE, two
// halves of 4 lanes: the top level is a small part of an instance walk); the instances'
// own walks are the wide kernels'.
#pragma once
#include <immintrin.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "core/bbox.h"
#include "core/geometry.h"
#include "core/kernel_constants.h"

namespace volley::accel {

class InstanceTree {
 public:
  /// Builds over `boxes` (instance i's world box; an empty box is never entered).
  void build(const std::vector<core::BBox>& boxes);
  bool empty() const { return nodes_.empty(); }
  /// Bytes of the nodes.
  std::size_t bytes() const { return nodes_.size() * sizeof(Node); }
  std::size_t node_count() const { return nodes_.size(); }

  /// Calls leaf(i, tmax) for every instance i whose box the ray meets over [tmin, tmax),
  /// nearest box first; leaf lowers tmax on a hit and returns true. AnyHit: stops at the
  /// first true. Robust: exit distances padded as the core slab test pads them. A ray
  /// with a non-finite origin or direction, or a NaN tmin or tmax, visits nothing.
  template <bool AnyHit, bool Robust, class Leaf>
  bool walk(const core::RayT<float>& ray, Leaf&& leaf) const;

 private:
  static constexpr std::uint32_t kLeaf = 0x80000000u;   ///< child = kLeaf | instance
  static constexpr std::uint32_t kEmpty = 0xffffffffu;  ///< an unused child
  struct alignas(64) Node {
    float lo[3][8], hi[3][8];  ///< children's boxes, one lane each (unused: lo = +inf, hi = -inf)
    std::uint32_t child[8];    ///< interior: node index; leaf: kLeaf | instance; kEmpty
  };
  std::vector<Node> nodes_;
};

namespace instance_tree_detail {
/// Entry distances of the 8 children of a node, and the mask of those the ray enters:
/// two halves of 4 lanes (SSE, the baseline ISA).
inline std::uint32_t enter(const float (&lo)[3][8], const float (&hi)[3][8], const float* org, const float* inv,
                           const bool* neg, float tmin, float tmax, float pad, float* entry) {
  std::uint32_t mask = 0;
  for (int half = 0; half < 8; half += 4) {
    __m128 near = _mm_set1_ps(tmin), far = _mm_set1_ps(tmax);
    for (int a = 0; a < 3; ++a) {
      const __m128 l = _mm_load_ps(&lo[a][half]), h = _mm_load_ps(&hi[a][half]);
      const __m128 o = _mm_set1_ps(org[a]), r = _mm_set1_ps(inv[a]);
      // Near and far planes by the octant. _mm_max_ps(x, y) returns y when x is NaN (a
      // zero direction component on a slab plane): the NaN is dropped, as core::intersect_box does.
      const __m128 tn = _mm_mul_ps(_mm_sub_ps(neg[a] ? h : l, o), r);
      const __m128 tf = _mm_mul_ps(_mm_sub_ps(neg[a] ? l : h, o), r);
      near = _mm_max_ps(tn, near);
      far = _mm_min_ps(tf, far);
    }
    _mm_storeu_ps(entry + half, near);
    mask |= std::uint32_t(_mm_movemask_ps(_mm_cmple_ps(near, _mm_mul_ps(far, _mm_set1_ps(pad))))) << half;
  }
  return mask;
}
}  // namespace instance_tree_detail

template <bool AnyHit, bool Robust, class Leaf>
bool InstanceTree::walk(const core::RayT<float>& ray, Leaf&& leaf) const {
  if (nodes_.empty()) return false;
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(ray.org[a]) || !std::isfinite(ray.dir[a])) return false;
  if (std::isnan(ray.tmin) || std::isnan(ray.tmax)) return false;
  const float org[3] = {ray.org.x, ray.org.y, ray.org.z};
  float inv[3];
  bool neg[3];
  for (int a = 0; a < 3; ++a) inv[a] = 1.0f / ray.dir[a], neg[a] = std::signbit(inv[a]);
  constexpr float pad = Robust ? core::kSlabExitPad : 1.0f;
  float tmax = ray.tmax;
  // Pending children, farthest at the bottom: at most 7 per level of a tree that is at
  // most ~log8(instances) + a few deep.
  struct Item {
    std::uint32_t ref;
    float entry;
  };
  Item stack[8 * core::kBvhMaxDepth];
  int size = 0;
  bool hit = false;
  std::uint32_t ref = 0;  // the root node
  for (;;) {
    if (!(ref & kLeaf)) {
      const Node& node = nodes_[ref];
      float entry[8];
      std::uint32_t mask = instance_tree_detail::enter(node.lo, node.hi, org, inv, neg, ray.tmin, tmax, pad, entry);
      // Push the entered children farthest first, so the nearest is popped next.
      const int base = size;
      for (; mask != 0; mask &= mask - 1) {
        const int c = __builtin_ctz(mask);
        int k = size++;
        for (; k > base && stack[k - 1].entry < entry[c]; --k) stack[k] = stack[k - 1];
        stack[k] = {node.child[c], entry[c]};
      }
    } else if (leaf(ref & ~kLeaf, tmax)) {
      hit = true;
      if constexpr (AnyHit) return true;
    }
    for (;;) {
      if (size == 0) return hit;
      --size;
      if (stack[size].entry <= tmax * pad) break;
    }
    ref = stack[size].ref;
  }
}

}  // namespace volley::accel
