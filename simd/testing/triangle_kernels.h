// The type-erased triangle kernels of the tests and benchmarks (the testing library, not
// shipped): one triangle test on one ISA, its blocks, and the single-ray and packet query
// forms over runs of blocks. No xsimd here: callers compile at the baseline ISA.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "simd/rays/prepared_packet.h"
#include "simd/rays/prepared_ray.h"
#include "simd/testing/prepare_ray.h"
#include "simd/rays/ray_packet.h"
#include "volley/options.h"
#include "volley/ray.h"

namespace volley::simd {

/// The blocks of one BVH leaf: blocks first .. first + count of a TriangleKernels.
struct BlockRange {
  std::uint32_t first;  ///< index of the leaf's first block
  std::uint32_t count;  ///< number of blocks (0 for an empty leaf)
};

/// Rays per packet in the packet forms.
inline constexpr int kPacketSize = 16;
/// The packet types of the packet forms.
using Packet = RayPacket<kPacketSize>;
using PacketHits = HitPacket<kPacketSize>;
using PreparedPacket16 = PreparedPacket<kPacketSize>;

/// One triangle test on one ISA: owns the triangle blocks (64-byte aligned, W triangles
/// each) and intersects rays with runs of them.
///
/// Build once with build(); afterwards the object is immutable and every query is
/// const and thread-safe (any number of threads may query concurrently). Results agree
/// with the scalar oracle of the same test (src/core/triangle_*.h) triangle by triangle:
/// same hit/miss, same prim, bit-identical t, u, v.
///
/// Closest-hit semantics: triangles are taken in block order, lane order (i.e. in the
/// order given to build() within a group); a triangle replaces the current hit when it is
/// hit with tmin <= t < upper, where upper starts as min(hit.t, ray.tmax) (NaN tmax: no
/// hit) and becomes the t of every accepted hit.
class TriangleKernels {
 public:
  /// Kernels of `test` for `isa`. `isa` must already be resolved (resolve_isa): sse42,
  /// avx2 or avx512, supported by this CPU. Throws std::invalid_argument otherwise.
  static std::unique_ptr<TriangleKernels> create(TriangleTest test, Isa isa);
  virtual ~TriangleKernels() = default;

  TriangleTest test() const { return test_; }
  Isa isa() const { return isa_; }
  /// W: triangles per block (4 for sse42, 8 for avx2, 16 for avx512).
  virtual int width() const = 0;
  /// Bytes of block storage (blocks * sizeof(block)).
  virtual std::size_t bytes() const = 0;
  /// Blocks held.
  virtual std::size_t blocks() const = 0;

  /// Packs triangles into blocks, replacing any earlier build. Triangle i has vertices
  /// xyz[9*i .. 9*i+9) (p0, p1, p2) and id prim_ids[i] (any value but kInvalidPrim).
  /// `groups` has ngroups + 1 entries, non-decreasing, groups[ngroups] <= n: group g
  /// (one BVH leaf) is triangles groups[g] .. groups[g+1], and gets its own blocks, the last
  /// one padded with inert lanes. Returns one BlockRange per group. Degenerate triangles
  /// are kept (they never hit). Not thread-safe.
  virtual std::vector<BlockRange> build(const float* xyz, const std::uint32_t* prim_ids, std::size_t n,
                                        const std::uint32_t* groups, std::size_t ngroups) = 0;

  /// The per-ray precomputation of this test, to reuse for every leaf a ray visits.
  PreparedRay prepare(const Ray& ray) const { return prepare_ray(ray, test_ == TriangleTest::watertight); }

  /// Closest hit over the blocks of `r`: updates `hit` (t, u, v, prim) as described above;
  /// untouched when nothing nearer is hit. `ray` must come from this object's prepare().
  virtual void intersect(const PreparedRay& ray, BlockRange r, Hit& hit) const = 0;
  /// True when a triangle in the blocks of `r` is hit with tmin <= t < ray.tmax.
  virtual bool occluded(const PreparedRay& ray, BlockRange r) const = 0;
  /// As above, preparing the ray on the fly.
  void intersect(const Ray& ray, BlockRange r, Hit& hit) const { intersect(prepare(ray), r, hit); }
  bool occluded(const Ray& ray, BlockRange r) const { return occluded(prepare(ray), r); }

  /// The per-lane precomputation of this test for a packet (the Woop shear of every lane
  /// for watertight; a copy for moller and plane), to reuse for every leaf it visits.
  virtual void prepare(const Packet& rays, PreparedPacket16& out) const = 0;
  /// Closest hit of each active lane (bit i of rays.rays.active) over the blocks of `r`,
  /// each triangle tested against all 16 lanes at once. Writes only lanes that hit
  /// something nearer than hits.t[i] (and the lane's tmax); inactive lanes are never
  /// written. `rays` must come from this object's prepare().
  virtual void intersect(const PreparedPacket16& rays, BlockRange r, PacketHits& hits) const = 0;
  /// The lanes of `active` (ANDed with rays.rays.active) occluded by a triangle of `r`
  /// (tmin <= t < tmax), as a bit mask. Stops when all of them are occluded.
  virtual std::uint32_t occluded(const PreparedPacket16& rays, BlockRange r, std::uint32_t active) const = 0;
  /// As above, preparing the packet on the fly (costs one prepare() per call).
  void intersect(const Packet& rays, BlockRange r, PacketHits& hits) const {
    PreparedPacket16 p;
    prepare(rays, p);
    intersect(p, r, hits);
  }
  std::uint32_t occluded(const Packet& rays, BlockRange r, std::uint32_t active) const {
    PreparedPacket16 p;
    prepare(rays, p);
    return occluded(p, r, active);
  }

 protected:
  TriangleKernels(TriangleTest test, Isa isa) : test_(test), isa_(isa) {}

 private:
  TriangleTest test_;
  Isa isa_;
};

}  // namespace volley::simd
