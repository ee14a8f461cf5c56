// Scalar oracle: ray/box slab test and single-ray BVH traversal with a leaf callback.
#pragma once
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>

#include "core/bbox.h"
#include "core/bvh.h"
#include "core/geometry.h"
#include "core/kernel_constants.h"

namespace volley::core {

/// A ray prepared for slab tests: origin, reciprocal direction (±inf for a ±0
/// component) and the octant (sign bit of each reciprocal, so -0 counts as negative).
struct BoxRay {
  glm::vec3 org;      // 12 bytes
  glm::vec3 inv_dir;  // 12 bytes
  bool neg[3];        //  3 bytes: inv_dir[a] has its sign bit set
  float tmin;         //  4 bytes
};

/// Precomputes the slab-test data of a ray (one division per axis).
inline BoxRay make_box_ray(const RayT<float>& ray) {
  BoxRay r;
  r.org = ray.org;
  r.inv_dir = 1.0f / ray.dir;
  for (int a = 0; a < 3; ++a) r.neg[a] = std::signbit(r.inv_dir[a]);
  r.tmin = ray.tmin;
  return r;
}

/// Slab test (Kay-Kajiya) of the closed box b against the ray over [tmin, tmax]. On
/// true, `entry` is the distance where the ray enters the box (at least tmin). With
/// Robust = true the exit distance (box exit or tmax, whichever is nearer) is padded by
/// kSlabExitPad, so the test never culls a box that the exact ray meets within
/// [tmin, tmax], rounding included; Robust = false is the plain, unpadded test
/// (Options::robust = false: a little faster; tests show it misses boxes the exact ray
/// touches).
///
/// Zero direction components: inv_dir = ±inf, and when the origin lies exactly on a
/// slab plane (bound - org = 0) the slab distance is 0 * inf = NaN. Picking the near
/// and far plane by the octant (not by min/max of the two distances) leaves the other
/// distance at its correct ±inf (or NaN too, for a box flat in that axis), and the
/// comparisons below drop a NaN distance, so such a slab never culls: the ray runs
/// inside the closed slab. An empty box (lo = +inf, hi = -inf) is always culled.
/// Precondition: the ray's tmin and the tmax passed are not NaN (traverse() rejects NaN
/// rays before calling this). The padding of a negative exit
/// distance makes it more negative: boxes entirely behind tmin = 0 are unaffected, but
/// a ray with a negative tmin gets no padding on the t < 0 side.
template <bool Robust = true>
inline bool intersect_box(const BBox& b, const BoxRay& r, float tmax, float& entry) {
  float t_enter = r.tmin;
  float t_exit = tmax;
  for (int a = 0; a < 3; ++a) {
    // Near and far planes of this slab by the octant of the ray.
    const float near_plane = r.neg[a] ? b.hi[a] : b.lo[a];
    const float far_plane = r.neg[a] ? b.lo[a] : b.hi[a];
    const float t_near = (near_plane - r.org[a]) * r.inv_dir[a];
    const float t_far = (far_plane - r.org[a]) * r.inv_dir[a];
    // NaN is KEPT, not culled: a NaN slab distance (origin on the slab plane, zero
    // direction component: the ray runs inside that plane, which belongs to the
    // closed box) makes the comparison false, so the running bound is left unchanged
    // and the slab does not constrain the ray. The running bound is never NaN (tmin
    // and tmax are not), so it is the operand returned when the comparison fails.
    // std::max(t_near, t_enter) would instead return the NaN, and the final
    // t_enter <= t_exit would cull the box (the grid test in test_bvh.cpp fails then).
    t_enter = t_near > t_enter ? t_near : t_enter;
    t_exit = t_far < t_exit ? t_far : t_exit;
  }
  if constexpr (Robust) t_exit *= kSlabExitPad;
  entry = t_enter;
  return t_enter <= t_exit;
}

/// Traverses the BVH with a single ray and calls `leaf(prim, tmax)` for the primitives of
/// every leaf whose box the ray meets over [ray.tmin, tmax). `leaf` must return true
/// when its primitive is hit with ray.tmin <= t < tmax, and then lower `tmax` to that t
/// (the callback stores whatever else it wants: prim, u, v). Returns true when any leaf
/// call returned true.
///
/// AnyHit = false (closest hit): front to back, the nearer child first by slab entry
/// distance; a node is skipped when its entry distance lies beyond the current tmax
/// (padded by kSlabExitPad, so a primitive hit a few ulps past a box's rounded entry is
/// still visited; the callback's own t < tmax test stays exact). AnyHit = true
/// (occlusion): returns at the first leaf call that returns true.
///
/// Robustness: with Robust = true (the default) the slab test is conservative
/// (intersect_box<true>) and so is the stack pruning (entry <= tmax * kSlabExitPad);
/// Robust = false is the plain walk (Options::robust = false): unpadded boxes, entry <=
/// tmax. Both keep the NaN-safe operand order, so a ray in a box's face plane with a zero
/// direction component is not culled. A ray with a
/// non-finite origin or direction component, or a NaN tmin or tmax, returns false
/// without calling `leaf`. A zero direction terminates too (it visits the boxes that
/// contain the origin). Precondition: the BVH has depth < kBvhMaxDepth (build_bvh
/// guarantees it), the size of the fixed traversal stack. Thread-safe for a shared bvh.
///
/// traverse_leaves is the same walk with a callback per leaf instead of per primitive:
/// leaf(node_index, tmax) for the leaf bvh.nodes[node_index] (for kernels that test a
/// whole leaf at once, such as the SIMD triangle blocks).
template <bool AnyHit, bool Robust = true, class LeafFn>
bool traverse_leaves(const Bvh& bvh, const RayT<float>& ray, LeafFn&& leaf) {
  constexpr float pad = Robust ? kSlabExitPad : 1.0f;
  if (bvh.nodes.empty()) return false;
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(ray.org[a]) || !std::isfinite(ray.dir[a])) return false;
  if (std::isnan(ray.tmin) || std::isnan(ray.tmax)) return false;

  const BoxRay r = make_box_ray(ray);
  float tmax = ray.tmax;
  float entry = 0.0f;
  if (!intersect_box<Robust>(bvh.nodes[0].box, r, tmax, entry)) return false;

  // Far children waiting to be visited, with their entry distances.
  std::uint32_t stack_node[kBvhMaxDepth];
  float stack_entry[kBvhMaxDepth];
  int size = 0;
  bool hit = false;
  std::uint32_t index = 0;
  for (;;) {
    const BvhNode& node = bvh.nodes[index];
    if (!node.is_leaf()) {
      // Interior: test both children, descend into the nearer, push the farther.
      const std::uint32_t c0 = node.first_or_child;
      float e0 = 0.0f;
      float e1 = 0.0f;
      const bool hit0 = intersect_box<Robust>(bvh.nodes[c0].box, r, tmax, e0);
      const bool hit1 = intersect_box<Robust>(bvh.nodes[c0 + 1].box, r, tmax, e1);
      if (hit0 && hit1) {
        const bool swap = e1 < e0;
        assert(size < kBvhMaxDepth && "BVH deeper than kBvhMaxDepth");
        stack_node[size] = swap ? c0 : c0 + 1;
        stack_entry[size] = swap ? e0 : e1;
        ++size;
        index = swap ? c0 + 1 : c0;
        continue;
      }
      if (hit0 || hit1) {
        index = hit0 ? c0 : c0 + 1;
        continue;
      }
    } else {
      // Leaf: the callback tests its primitives and lowers tmax on a hit.
      if (leaf(index, tmax)) {
        hit = true;
        if constexpr (AnyHit) return true;
      }
    }
    // Pop the next far child that can still hold a hit nearer than tmax.
    for (;;) {
      if (size == 0) return hit;
      --size;
      if (stack_entry[size] <= tmax * pad) break;
    }
    index = stack_node[size];
  }
}

template <bool AnyHit, bool Robust = true, class LeafFn>
bool traverse(const Bvh& bvh, const RayT<float>& ray, LeafFn&& leaf) {
  return traverse_leaves<AnyHit, Robust>(bvh, ray, [&](std::uint32_t node_index, float& tmax) {
    // Every primitive of the leaf; the callback lowers tmax on a hit.
    const BvhNode& node = bvh.nodes[node_index];
    bool hit = false;
    const std::uint32_t end = node.first_or_child + node.count;
    for (std::uint32_t i = node.first_or_child; i < end; ++i) {
      if (leaf(bvh.prim_index[i], tmax)) {
        hit = true;
        if constexpr (AnyHit) return true;
      }
    }
    return hit;
  });
}

}  // namespace volley::core
