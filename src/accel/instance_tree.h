// The top level over a layer's instances (Accel::add_instance): the binned-SAH binary BVH
// of their world boxes, collapsed into the wide nodes the triangle BVH uses, one instance
// per child slot. SIMD ISAs walk it with the single-ray walk of their kernels
// (WideKernels::walk_instances); the scalar ISA walks the binary tree with the oracle's
// walk (core::traverse), its twin.
#pragma once
#include <cstdint>
#include <vector>

#include "accel/engine.h"
#include "core/bbox.h"
#include "core/bvh.h"
#include "core/bvh_traverse.h"
#include "simd/aligned.h"
#include "simd/wide/instance_view.h"
#include "volley/options.h"

namespace volley::accel {

class InstanceTree {
 public:
  /// Builds over `boxes` (instance i's world box; an empty box is never entered) for
  /// walks on `isa` (scalar: the oracle's walk) with the padded slab test when `robust`.
  void build(const std::vector<core::BBox>& boxes, Isa isa, bool robust);
  bool empty() const { return ids_.empty() && bvh_.nodes.empty(); }
  /// Bytes of the nodes and ids (and the binary tree the scalar walk keeps).
  std::size_t bytes() const;

  /// Calls leaf(i, bound) for every instance i whose box the ray meets over [tmin, bound)
  /// (bound: at most ray.tmax, `bound` on entry) as `mode` says (closest: nearest box
  /// first, leaf lowers bound on a hit and returns true; any: stops at the first true;
  /// every: leaf returns false). A ray with a non-finite origin or direction, or a NaN
  /// tmin or tmax, visits nothing. Returns whether some leaf returned true.
  template <class Leaf>
  bool walk(simd::InstanceWalk mode, const Ray& ray, float bound, Leaf& leaf) const;
  /// The packet form (closest or any; built for a SIMD ISA only: the scalar one walks ray
  /// by ray): leaf(i, lanes, bound) for every instance i with the lanes of `rays` that
  /// enter its box (every lane of `rays` is read: inactive ones must be initialised),
  /// bound[lane] as in walk; returns the lanes leaf reported hits for.
  template <class Leaf>
  std::uint32_t walk_packet(simd::InstanceWalk mode, const RayPacket<16>& rays, Leaf& leaf) const;

 private:
  using WalkFn = bool (*)(const simd::InstanceView&, const Ray&, float, simd::InstanceVisit, simd::InstanceWalk);
  using PacketWalkFn = std::uint32_t (*)(const simd::InstanceView&, const RayPacket<16>&, simd::InstancePacketVisit,
                                         simd::InstanceWalk);
  simd::AlignedVector<simd::WideNode<simd::kWideN>> nodes_;
  std::vector<std::uint32_t> ids_;  ///< instance ids in the order of the leaves
  simd::InstanceView view_{nullptr, nullptr, simd::wide_ref::kEmptyRef};
  WalkFn walk_ = nullptr;  ///< the ISA's walk; null: the scalar walk of bvh_
  PacketWalkFn walk_packet_ = nullptr;
  core::Bvh bvh_;          ///< the binary tree (the scalar ISA's; empty otherwise)
  bool robust_ = true;
};

template <class Leaf>
bool InstanceTree::walk(simd::InstanceWalk mode, const Ray& ray, float bound, Leaf& leaf) const {
  if (walk_) {
    auto visit = [](void* context, std::uint32_t instance, float& bound) {
      return (*static_cast<Leaf*>(context))(instance, bound);
    };
    return walk_(view_, ray, bound, {visit, &leaf}, mode);
  }
  core::RayT<float> r = to_core(ray);
  r.tmax = bound < ray.tmax ? bound : ray.tmax;
  auto one = [&](std::uint32_t instance, float& bound) { return leaf(instance, bound); };
  // (every: the closest walk, whose leaf never lowers the bound, visits every box met)
  if (mode == simd::InstanceWalk::any)
    return robust_ ? core::traverse<true, true>(bvh_, r, one) : core::traverse<true, false>(bvh_, r, one);
  return robust_ ? core::traverse<false, true>(bvh_, r, one) : core::traverse<false, false>(bvh_, r, one);
}

template <class Leaf>
std::uint32_t InstanceTree::walk_packet(simd::InstanceWalk mode, const RayPacket<16>& rays, Leaf& leaf) const {
  auto visit = [](void* context, std::uint32_t instance, std::uint32_t lanes, float* bound) {
    return (*static_cast<Leaf*>(context))(instance, lanes, bound);
  };
  return walk_packet_(view_, rays, {visit, &leaf}, mode);
}

}  // namespace volley::accel
