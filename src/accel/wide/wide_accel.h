// The wide BVH of one triangle test on one ISA, type-erased for Accel: owns the nodes and
// triangle blocks, forwards queries to the traversal kernels instantiated in the per-ISA
// files (simd/wide/wide_traverse.h). No xsimd here: Accel compiles at the baseline ISA.
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/bvh.h"
#include "core/point_triangle.h"
#include "simd/wide/wide_bvh.h"
#include "volley/options.h"
#include "volley/packet.h"
#include "volley/ray.h"

namespace volley {
/// volley::load for the double packets of WideAccel::occluded (src/accel/packet_convert.cpp).
void load(RayPacket<32>& packet, const Ray* rays, int count);
}  // namespace volley

namespace volley::accel {

/// A built wide BVH as plain memory (Accel::save writes it, Accel::load maps it back).
struct WideImage {
  const void* nodes = nullptr;  ///< node_count WideNode<kWideN>, 64-byte aligned
  std::size_t node_count = 0;
  const void* blocks = nullptr;  ///< block_count blocks of block_bytes each, 64-byte aligned
  std::size_t block_count = 0;
  std::size_t block_bytes = 0;
  std::uint32_t root = simd::wide_ref::kEmptyRef;
  simd::WideStats stats;
  /// Keeps nodes and blocks alive while the WideAccel uses them (the mapped file).
  std::shared_ptr<const void> owner;
};

/// What the triangle blocks of an image may name: ids below `id_limit`, none of `not_triangles`
/// (sorted; the polygons' ids).
struct ImageIds {
  std::uint32_t id_limit;
  const std::vector<std::uint32_t>* not_triangles;
};

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
  /// Whether occlusion packets defer their hand-offs to single rays
  /// (simd::WideView::defer_handoffs). Set from the structure's size (simd::kDeferHandoffBytes)
  /// whenever a structure is built or adopted; the tests turn it on for small trees.
  virtual void defer_handoffs(bool on) = 0;
  /// The built structure as memory (valid while this WideAccel lives and is not rebuilt).
  virtual WideImage image() const = 0;
  /// Takes a saved structure and queries it in place (a refit copies it first). Checks it
  /// as untrusted input: the block layout, every child reference in range and met once,
  /// children after their parent, depth within the walks' stacks (check_wide_tree); the
  /// blocks' triangle ids are the caller's to check (check_block_ids, while it reads them).
  /// Throws std::invalid_argument saying what is wrong (nothing adopted).
  virtual void adopt(WideImage image) = 0;
  /// Bytes of one triangle block.
  virtual std::size_t block_bytes() const = 0;
  /// Where a block keeps its W triangle ids (offsetof(Block, prim)).
  virtual std::size_t prim_offset() const = 0;
  /// Size and quality of the built structure.
  virtual const simd::WideStats& stats() const = 0;

  /// Closest hit: updates `hit` with a triangle hit at tmin <= t < min(hit.t, tmax).
  /// Not virtual: a direct call of the kernel's entry (a layer of calls less per ray).
  void intersect(const Ray& ray, Hit& hit) const { single_.intersect(single_.bvh, ray, hit); }
  /// Any hit with tmin <= t < tmax.
  bool occluded(const Ray& ray) const { return single_.occluded(single_.bvh, ray); }
  /// The two above with the triangle of id `excluded` left out (kInvalidPrim: none).
  void intersect(const Ray& ray, std::uint32_t excluded, Hit& hit) const {
    single_.intersect_excluding(single_.bvh, ray, excluded, hit);
  }
  bool occluded(const Ray& ray, std::uint32_t excluded) const {
    return single_.occluded_excluding(single_.bvh, ray, excluded);
  }
  /// Closest hits of the active lanes (hits.t bounds each lane's search; only lanes with a
  /// nearer hit are written).
  virtual void intersect(const RayPacket<16>& rays, HitPacket<16>& hits) const = 0;
  /// Mask of the active lanes that something occludes.
  virtual std::uint32_t occluded(const RayPacket<16>& rays) const = 0;
  /// The same for a double packet of 32 rays, walked as one where the ISA has the walk
  /// (double_packets()), else as two packets of 16.
  virtual std::uint32_t occluded(const RayPacket<32>& rays) const = 0;
  /// Whether occluded(RayPacket<32>) walks the 32 rays as one packet (AVX2).
  virtual bool double_packets() const = 0;
  /// Streams by the stream walk (simd/wide/stream_walk.h): blocked[i] = 1 when something
  /// occludes rays[i], else 0; the closest hit of each ray into hits[i] (hits[i].t bounds
  /// its search).
  virtual void occluded(const Ray* rays, std::size_t count, std::uint8_t* blocked) const = 0;
  virtual void intersect(const Ray* rays, std::size_t count, Hit* hits) const = 0;
  /// The two above with ray i passing over the triangle of id excluded[i] (kInvalidPrim: none).
  virtual void occluded(const Ray* rays, std::size_t count, const std::uint32_t* excluded,
                        std::uint8_t* blocked) const = 0;
  virtual void intersect(const Ray* rays, std::size_t count, const std::uint32_t* excluded, Hit* hits) const = 0;
  /// Every triangle hit with tmin <= t < tmax by the crossing test (the watertight test's
  /// exactly-once rule), appended to `out` in visiting order (prim = the triangle's id).
  virtual void all_hits(const Ray& ray, std::vector<Hit>& out) const = 0;
  /// What the single-ray walk visits for `ray` (closest hit, or any hit).
  virtual WalkCounts walk_counts(const Ray& ray, bool any_hit) const = 0;
  /// The same for the active lanes of a packet: lane i's hits appended to out[i].
  virtual void all_hits(const RayPacket<16>& rays, std::vector<Hit>* out) const = 0;
  /// The nearest triangle point to query.p within sqrt(query.d2): updates `query`. Throws
  /// std::invalid_argument for the plane test (its blocks keep no vertices).
  virtual void closest_point(core::PointQuery& query) const = 0;

 /// The single-ray entries of the kernels (WideKernels::intersect_erased, occluded_erased
  /// and their excluding forms) and the view of the built BVH they take; set by the
  /// implementation. A scene that is this BVH alone calls them without a call between
  /// (Accel::Impl::Queries).
  struct SingleRay {
    void (*intersect)(const void* bvh, const Ray& ray, Hit& hit);
    bool (*occluded)(const void* bvh, const Ray& ray);
    void (*intersect_excluding)(const void* bvh, const Ray& ray, std::uint32_t excluded, Hit& hit);
    bool (*occluded_excluding)(const void* bvh, const Ray& ray, std::uint32_t excluded);
    const void* bvh;
  };
  const SingleRay& single_ray() const { return single_; }

 protected:
  explicit WideAccel(SingleRay single) : single_(single) {}
  SingleRay single_;
};

}  // namespace volley::accel

namespace volley::accel {

/// The tree check of WideAccel::adopt over the nodes of an image (wide_image.cpp): every
/// reference in range and met once, interior children after their parent, leaves within
/// `block_count`, depth within core::kBvhMaxDepth (the walks' stacks). Returns the deepest leaf's
/// depth (WideStats::depth);
/// throws std::invalid_argument naming the first fault.
std::size_t check_wide_tree(const simd::WideNode<simd::kWideN>* nodes, std::size_t node_count,
                            std::size_t block_count, std::uint32_t root);

/// Checks the triangle ids of whole blocks laid out as `layout`'s (from block `first_block`
/// on, for the message): each kInvalidPrim or allowed by `ids`. Throws std::invalid_argument.
void check_block_ids(const unsigned char* blocks, std::size_t count, std::size_t first_block, const WideAccel& layout,
                     const ImageIds& ids);

}  // namespace volley::accel
