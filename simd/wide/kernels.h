// The wide-BVH traversal kernels' interface: WideKernels<Arch, Test, Robust, PK> (one ray,
// packets of 16 rays, any-hit packets of 32 on AVX2; closest hit and any hit) against WideNode<8> nodes (wide_bvh.h),
// with leaves handed to the triangle block kernels (block_kernels.h), and the packet setup its walks share. The bodies
// are in the files beside this one, one concept each:
//   query_protocol.h  what a walk asks of a query (the concepts each walk checks)
//   queries.h, packet_queries.h, stream_queries.h
//                   what is asked: each query's leaf action and termination rule
//   node_lanes.h    the eight child lanes of a node on any ISA (Lanes8, ChildHits)
//   stack.h         stack entries, the near-to-far sort and pop, lane reductions
//   packet_lanes.h  a packet's lanes, the per-lane box test of one child, hand-offs
//   single_walk.h   one ray: preparation and the walk, whose steps are
//     single_slabs.h  the ray's constants and the node test
//     child_order.h   the entered children onto the stack, the nearest next
//   single_entries.h  the single-ray entries (erased, counts, all hits, instances)
//   packet_entry.h  packets: the entries and the lane screen that picks a walk
//   frustum_walk.h  coherent packets: one interval test per node
//   packet_walk.h   other packets: per-lane tests, subtrees handed to the single walk,
//                   whose steps are
//     lane_walk.h     the lanes' node test, child order and hand-offs (LaneWalk)
//   stream_walk.h   streams: lists of rays split node by node (its steps: StreamWalk)
// simd/wide/wide_traverse.h includes them all and declares the per-ISA instantiations.
//
// Conservative box test, as the scalar oracle's core::intersect_box (core/bvh_traverse.h),
// operation for operation: slab distances (plane - org) * (1 / dir) with near and far
// plane picked by the octant of the ray (not by min/max), entry = max(near_x, near_y,
// near_z, tmin), exit = min(far_x, far_y, far_z, tmax) * kSlabExitPad (Robust; no padding
// for Robust = false), hit when entry <= exit. NaN-safe operand order: every max/min is maxps/minps(distance, running
// bound), which returns its second operand when either is NaN, so a NaN slab distance
// (0 * inf: an origin on a slab plane with a zero or subnormal direction component, whose
// reciprocal is ±inf; or inf - inf in the fused form) leaves the running bound unchanged
// and never culls, exactly as the oracle's `t_near > t_enter ? t_near : t_enter`. The
// running bounds themselves are never NaN (NaN tmin / tmax rays are rejected first).
// Inert children (lo = +inf, hi = -inf) fail for every ray.
// One exception, the single-ray walk: its far distances are (plane - org) * fl(inv * pad),
// the padding folded into the reciprocal once per ray (same rounding bound, one multiply
// less per node), and with FMA (AVX2, AVX-512) and no zero direction component each slab
// distance is one fused plane * inv - c, c = org * inv widened outwards once per ray (see
// walk). Its slab distances may differ from the oracle's by a few ulps of org * inv, never
// by culling a box the exact ray meets; the triangle answers are the same.
#pragma once
#include <immintrin.h>

#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>
#include <xsimd/xsimd.hpp>

#include "core/kernel_constants.h"
#include "core/point_triangle.h"
#include "simd/isa/arch.h"
#include "simd/triangle/block_kernels.h"
#include "simd/hit_list.h"
#include "simd/triangle/kernel_common.h"
#include "simd/rays/prepared_packet.h"
#include "simd/rays/prepared_ray.h"
#include "simd/rays/ray_packet.h"
#include "simd/triangle/triangle_blocks.h"
#include "simd/wide/instance_view.h"
#include "simd/wide/query_protocol.h"
#include "simd/wide/wide_bvh.h"
#include "volley/options.h"
#include "volley/ray.h"

namespace volley::simd {

/// Rays per packet of the packet traversal (RayPacket<16>); the API widens K = 4 and 8.
inline constexpr int kWidePacket = 16;

/// Packet traversal hands a subtree to single-ray traversal, lane by lane, once this few
/// lanes (or fewer) are still active in it (Embree's "switch threshold"; the value:
/// perf/reports/traversal.md).
inline constexpr int kPacketSwitchLanes = 2;

namespace detail {

/// Whether the packet walks test lanes in the single walk's fused form (one FMA per slab
/// distance; PacketLanes::fused_slabs): on AVX-512. AVX2 has FMA too, but its 16 registers
/// do not hold the form's nine constants beside the rest: kitchen shadow packets lost 6%
/// there (perf/reports/rays.md).
template <class Arch>
inline constexpr bool kFusedLanes = kHasFma<Arch> && kLanes<Arch> == 16;

/// Whether the any-hit packet walk tests a node lane by lane, each lane against all eight
/// children in one register (PacketLanes::lanes_enter): where a register holds one lane per
/// child (AVX2).
template <class Arch>
inline constexpr bool kLaneByLane = kLanes<Arch> == kWideN;

/// The walk a packet takes, chosen by WideKernels::screen from its valid lanes.
enum class PacketWalk : std::uint32_t {
  mixed_octants = 0,  ///< the per-lane walk, each lane ordering children by its own octant
  one_octant = 1,     ///< the per-lane walk, one near-to-far order for the whole packet
  /// One octant, no zero direction component, origins that differ: the frustum walk's
  /// interval test holds (it bounds the origins too) but is taken only where a query asks
  /// for it (Query::kSpreadFrustum: closest hits, instance top levels); otherwise as one_octant.
  spread_frustum = 2,
  frustum = 3,  ///< one octant, one origin, no zero direction component: the frustum walk
};

/// What the single-ray entry learns of a ray before its walk (WideKernels::prepare_single).
enum class RayScreen : int {
  rejected = -1,          ///< the oracle rejects it: a non-finite origin or direction, a NaN interval end
  zero_component = 0,     ///< some direction component is ±0: slab distances may be NaN (0 * inf)
  no_zero_component = 1,  ///< every component nonzero: the walk may combine slab distances as a tree
};

/// The lane setup of a packet, computed once by WideKernels::screen.
template <int K>
struct alignas(64) PacketSetup {
  float inv[3][K];      // 12K bytes: 1 / dir per lane, as the oracle (±inf for ±0)
  std::uint32_t valid;  //  4 bytes: the active lanes the oracle does not reject
  PacketWalk walk;      //  4 bytes
};
}  // namespace detail

/// Traversal of the wide BVH with the triangle test `Test` on Arch, packets of PK rays
/// (kWidePacket; 32 for AVX2's any-hit double packets, whose class instantiates only
/// occluded(View, RayPacket<32>)); leaf blocks hold W = kLanes<SingleRayArch<Arch>>
/// triangles (8 on AVX-512, whose packets still run 16 lanes: single rays were faster on
/// 8-triangle leaves, packets no slower). Robust = false
/// drops the exit padding (kSlabExitPad) from the box test and the stack pruning
/// (Options::robust = false, the fast path; the NaN-safe operand order stays, it costs
/// nothing); its answers may differ from the oracle's where a ray grazes a box (the mutation
/// test in tests/accel shows it). All functions are thread-safe (pure functions of their
/// arguments).
///
/// Semantics, all forms: the answers of the scalar oracle's closest-hit / any-hit
/// traversal with the same triangle test (same hit / miss; same prim, or the same t when
/// two triangles tie). Rays with a non-finite origin or direction component, or a NaN
/// tmin or tmax, hit nothing (as core::traverse_leaves). Visit order differs between the
/// forms, and the oracle's watertight test compares t against the current bound in scaled
/// form, so between two overlapping coplanar triangles whose t differ by an ulp or two the
/// form that meets the farther one first may keep it (4 of 262144 primary rays on
/// conference before its camera file; the oracle's own traversal does the same).
template <class Arch, TriangleTest Test, bool Robust = true, int PK = kWidePacket>
struct WideKernels {
  using Isa = Arch;
  static constexpr TriangleTest kTest = Test;
  static constexpr int N = kWideN;
  static constexpr int L = kLanes<Arch>;
  static constexpr int K = PK;
  /// The single-ray leaf kernels' arch; its lanes are the block width (8 on AVX-512).
  using SingleArch = SingleRayArch<Arch>;
  static constexpr int W = kLanes<SingleArch>;
  using Block = BlockFor<Test, W>;
  using View = WideView<Block>;
  /// Float lanes of the packet forms, and the block kernels of the packet walks' leaves.
  using Float = detail::FloatB<Arch>;
  using LeafPacket = PacketKernels<Arch, Test, K, W>;

  /// Closest hit of one ray: updates `hit` with every triangle hit at
  /// ray.tmin <= t < min(hit.t, ray.tmax) that is nearer (as RayBlockKernels::intersect).
  /// `bvh` is a const View*, type-erased so that the facade (accel::WideAccel) calls this
  /// through a plain function pointer: one call per ray.
  static void intersect_erased(const void* bvh, const Ray& ray, Hit& hit);
  /// True when some triangle is hit with ray.tmin <= t < ray.tmax (`bvh` as above).
  static bool occluded_erased(const void* bvh, const Ray& ray);
  /// The two above with the triangle whose id is `excluded` left out (kInvalidPrim: none):
  /// the answers of the same walk over a tree without it.
  static void intersect_excluding_erased(const void* bvh, const Ray& ray, std::uint32_t excluded, Hit& hit);
  static bool occluded_excluding_erased(const void* bvh, const Ray& ray, std::uint32_t excluded);
  /// Every triangle hit with ray.tmin <= t < ray.tmax by the crossing test
  /// (detail::CrossingTestOf), appended to `out` in visiting order (prim = the block's id).
  static void all_hits(const View& bvh, const Ray& ray, std::vector<Hit>& out);
  /// What the closest-hit (any_hit: occlusion) walk of one ray visits (no answer kept).
  static WalkCounts walk_counts(const View& bvh, const Ray& ray, bool any_hit);
  /// all_hits for the active lanes of a packet: lane i's hits appended to out[i].
  static void all_hits(const View& bvh, const RayPacket<K>& rays, std::vector<Hit>* out);
  /// The nearest point of the triangles to `query.p` within sqrt(query.d2) (point_walk.h).
  static void closest_point(const View& bvh, core::PointQuery& query);
  /// The top level of an instanced scene walked by the single-ray walk, every instance
  /// whose box the ray meets over [tmin, min(tmax, bound)) handed to `visit` as `mode` says
  /// (closest: nearest box first, bounded by the hits so far). The triangle test plays no part. Rays the oracle rejects
  /// (non-finite origin or direction, NaN tmin or tmax) visit nothing. Returns whether some
  /// visit returned true.
  static bool walk_instances(const InstanceView& top, const Ray& ray, float bound, InstanceVisit visit,
                             InstanceWalk mode);
  /// The packet form (closest or any): the active lanes of `rays` walk the top level
  /// together (the packet walks: frustum or per lane, few lanes on by the single-ray walk),
  /// each instance handed to `visit` with the lanes that enter its box. Returns the lanes
  /// for which some visit reported a hit.
  static std::uint32_t walk_instances(const InstanceView& top, const RayPacket<K>& rays, InstancePacketVisit visit,
                                      InstanceWalk mode);

  /// Closest hits of the active lanes of a packet (bit i of rays.active): lane i's
  /// hits.t[i] on entry bounds its search like tmax (reset() makes it +inf); only lanes
  /// that find a nearer hit are written. Inactive lanes are never hit, but the leaf kernels
  /// load and store whole chunks of lanes (unchanged values in lanes without a hit):
  /// Accel hands a packet with inactive lanes over as a copy.
  static void intersect(const View& bvh, const RayPacket<K>& rays, HitPacket<K>& hits);
  /// The active lanes of `rays` that some triangle occludes (tmin <= t < tmax), as a mask.
  static std::uint32_t occluded(const View& bvh, const RayPacket<K>& rays);

  /// Streams (stream_walk.h): blocked[i] = 1 when some triangle occludes rays[i], else 0;
  /// the closest hit of each ray into hits[i] (hits[i].t on entry bounds its search).
  static void occluded(const View& bvh, const Ray* rays, std::size_t count, std::uint8_t* blocked);
  static void intersect(const View& bvh, const Ray* rays, std::size_t count, Hit* hits);
  /// The two above with ray i passing over the triangle of id excluded[i] (kInvalidPrim: none).
  static void occluded_excluding(const View& bvh, const Ray* rays, std::size_t count, const std::uint32_t* excluded,
                                 std::uint8_t* blocked);
  static void intersect_excluding(const View& bvh, const Ray* rays, std::size_t count, const std::uint32_t* excluded,
                                  Hit* hits);

  /// Single-ray traversal of the subtree `start` for `query` (queries.h: ClosestHitRay,
  /// AnyHitRay): returns query.answer(). The packet walks' fallback, and the entry of every
  /// single-ray query.
  template <class Query, class Leaves>
  static bool trace_single(const WideView<Leaves>& bvh, const Ray& ray, std::uint32_t start, Query& query);
  /// trace_single for valid lane i of a screened and prepared packet: the lane's prepared
  /// ray and reciprocal are taken from the packet, whose prepare is make_woop_ray lane by
  /// lane (the values prepare_single computes; tests/simd), so no division is repeated.
  /// The packet walks' hand-offs of few lanes.
  template <class Query, class Leaves>
  static bool trace_lane(const WideView<Leaves>& bvh, const PreparedPacket<K>& prep,
                         const detail::PacketSetup<K>& setup, int i, std::uint32_t start, Query& query);

  /// Leaves the packet's valid lanes active (the active lanes the oracle does not reject:
  /// finite origin and direction, tmin and tmax not NaN), makes the rejected ones inert, and
  /// fills `setup` (see PacketSetup). The frustum walk's common origin is that of the
  /// first valid lane (a rejected lane's origin is no reference).
  static void screen(RayPacket<K>& rays, detail::PacketSetup<K>& setup);

 private:
  /// screen() as the packet entry takes it, inlined: a call there is measurable on shadow
  /// packets (perf/reports/rays.md).
  [[gnu::always_inline]] inline static void screen_inline(RayPacket<K>& rays, detail::PacketSetup<K>& setup);

  /// The start of every single-ray trace, prepare_ray's work done here: the watertight
  /// shear comes from the registers that hold the reciprocal direction (a call to
  /// prepare_ray showed in profiles of diffuse rays). Returns whether the oracle rejects the ray
  /// (a non-finite origin or direction component, a NaN interval end), else whether some
  /// direction component is ±0, with `pr` complete (the sure quotient range when SureRange)
  /// and the reciprocal direction in `inv`.
  template <bool SureRange>
  [[gnu::always_inline]] inline static detail::RayScreen prepare_single(const Ray& ray, PreparedRay& pr, __m128& inv);
  /// trace_single, inlined into the erased entries (of any view: triangle blocks or the
  /// instance ids of a top level).
  template <class Query, class Leaves>
  [[gnu::always_inline]] inline static bool trace_ray(const WideView<Leaves>& bvh, const Ray& ray,
                                                      std::uint32_t start, Query& query);
  /// The single-ray walk. NoZero: no direction component is ±0, so no slab distance can be
  /// NaN and the entry and exit bounds may be combined as a tree (shorter dependency chain).
  /// Inlined into its callers: the call, its frame and the vzeroupper before it cost single
  /// rays measurable time (perf/reports/traversal.md).
  template <class Query, bool NoZero, class Leaves>
  [[gnu::always_inline]] inline static void walk(const WideView<Leaves>& bvh, const PreparedRay& ray, __m128 inv,
                                                 std::uint32_t start, Query& query);

  /// The stream walk of rays[0 .. n) (n <= kStreamBatch) for a stream query (queries.h).
  template <class Query>
  static void trace_stream(const View& bvh, const Ray* rays, std::size_t n, Query& query);
  /// trace_stream over rays[0 .. count), kStreamBatch rays at a time: at(query, first)
  /// first points the query's per-ray arrays at ray `first`.
  template <class Query, class At>
  static void stream_batches(const View& bvh, const Ray* rays, std::size_t count, Query& query, At&& at);
  /// The stream walk's steps over its state (stream_walk.h).
  template <class Query>
  struct StreamWalk;
  /// Bits of the first L lanes.
  static constexpr std::uint32_t kChunkBits = (1u << L) - 1u;
  /// The start of every packet query: screens the packet, prepares it for the triangle
  /// test and hands it to the walk its lanes allow (frustum or per lane). Returns the lanes
  /// the query finished (0 for an empty tree or no valid lane).
  template <class Query, class Leaves>
  static std::uint32_t trace_packet_query(const WideView<Leaves>& bvh, const RayPacket<K>& rays, Query& query);
  /// The frustum walk of a coherent packet: one 8-wide interval test per node for the whole
  /// packet, per-lane tests at leaves and at each subtree popped. Requires every valid lane
  /// in one octant with no zero direction component (screen() says so); taken for packets
  /// whose lanes share one origin (pinhole primary rays), and by closest hits and instance
  /// top levels (Query::kSpreadFrustum) for origins that differ too; occlusion packets with
  /// spread origins (shadow rays from a 4x4 block of hit points, whose interval frustum grows
  /// loose) take the per-lane walk (perf/reports/traversal.md). Returns the lanes the query finished.
  template <class Query, class Leaves>
  [[gnu::always_inline]] inline static std::uint32_t trace_frustum(const WideView<Leaves>& bvh, PreparedPacket<K>& prep,
                                     const detail::PacketSetup<K>& setup, Query& query);
  /// The per-lane packet walk over prepared lanes (prep.rays.active is rewritten per leaf).
  /// Uniform: every valid lane in one octant. NoZero: and no zero direction component,
  /// where the walk has a use for it: the fused slab test on AVX-512
  /// (PacketLanes::fused_slabs), the family's shortcut of any-hit node tests
  /// (PacketFamily). Returns the lanes the query finished.
  template <class Query, bool Uniform, bool NoZero, class Leaves>
  static std::uint32_t trace_packet(const WideView<Leaves>& bvh, PreparedPacket<K>& prep,
                                    const detail::PacketSetup<K>& setup, Query& query);
  /// The per-lane walk's state and steps (lane_walk.h).
  template <class Query, bool Uniform, bool NoZero, class Leaves>
  struct LaneWalk;
};

}  // namespace volley::simd
