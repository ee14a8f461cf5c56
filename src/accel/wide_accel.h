// The wide BVH of one triangle test on one ISA, type-erased for Accel: owns the nodes and
// triangle blocks, forwards queries to the traversal kernels instantiated in the per-ISA
// files (simd/wide_traverse.h). No xsimd here: Accel compiles at the baseline ISA.
#pragma once
#include <cstdint>
#include <memory>

#include "core/bvh.h"
#include "simd/wide_bvh.h"
#include "volley/options.h"
#include "volley/packet.h"
#include "volley/ray.h"

namespace volley::accel {

/// A wide BVH over triangle blocks for one (test, ISA). Built once with build(); then
/// immutable, and every query is const and thread-safe. Answers agree with the scalar
/// oracle's traversal of the same test: same hit / miss, same prim or the same t at a tie.
class WideAccel {
 public:
  /// Kernels of `test` for `isa` (resolved: sse42, avx2 or avx512, supported by this CPU).
  /// robust = false drops the slab padding (Options::robust = false: faster, may miss a
  /// triangle whose leaf box the ray only grazes). Throws std::invalid_argument.
  static std::unique_ptr<WideAccel> create(TriangleTest test, Isa isa, bool robust = true);
  virtual ~WideAccel() = default;

  /// W: triangles per block (4, 8, 16 for sse42, avx2, avx512).
  virtual int block_width() const = 0;
  /// Collapses `bvh` (a binary BVH over triangles: triangle i has vertices xyz[9i .. 9i+9)
  /// and id ids[i]) and packs its leaves (accel::build_wide). Replaces an earlier build.
  virtual void build(const core::Bvh& bvh, const float* xyz, const std::uint32_t* ids) = 0;
  /// Refits the built BVH to moved triangles (refit_wide): triangle with id `id` now has
  /// vertices xyz[9 * index_of[id] ..]. Not thread-safe (no query may run).
  virtual void refit(const float* xyz, const std::uint32_t* index_of) = 0;
  /// Size and quality of the built structure.
  virtual const simd::WideStats& stats() const = 0;

  /// Closest hit: updates `hit` with a triangle hit at tmin <= t < min(hit.t, tmax).
  /// Not virtual: a direct call of the kernel's entry (a layer of calls less per ray).
  void intersect(const Ray& ray, Hit& hit) const { single_.intersect(single_.bvh, ray, hit); }
  /// Any hit with tmin <= t < tmax.
  bool occluded(const Ray& ray) const { return single_.occluded(single_.bvh, ray); }
  /// Closest hits of the active lanes (hits.t bounds each lane's search; only lanes with a
  /// nearer hit are written).
  virtual void intersect(const RayPacket<16>& rays, HitPacket<16>& hits) const = 0;
  /// Mask of the active lanes that something occludes.
  virtual std::uint32_t occluded(const RayPacket<16>& rays) const = 0;

 protected:
  /// The single-ray entries of the kernels (WideKernels::intersect_erased, occluded_erased)
  /// and the view of the built BVH they take; set by the implementation.
  struct SingleRay {
    void (*intersect)(const void* bvh, const Ray& ray, Hit& hit);
    bool (*occluded)(const void* bvh, const Ray& ray);
    const void* bvh;
  };
  explicit WideAccel(SingleRay single) : single_(single) {}
  SingleRay single_;
};

}  // namespace volley::accel
