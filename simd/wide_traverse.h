// Wide-BVH traversal kernels: one ray (closest hit, any hit) and packets of 16 rays
// (closest hit, any hit) against WideNode<8> nodes (wide_bvh.h), leaves handed to the
// triangle block kernels (block_kernels.h). Bodies templated on Arch, instantiated only in
// the per-ISA files wide_isa_sse42.cpp, wide_isa_avx2.cpp, wide_isa_avx512.cpp; the
// extern template declarations at the end keep every other file from instantiating them.
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
#include <xsimd/xsimd.hpp>

#include "core/kernel_constants.h"
#include "simd/arch.h"
#include "simd/block_kernels.h"
#include "simd/kernel_common.h"
#include "simd/prepared_packet.h"
#include "simd/prepared_ray.h"
#include "simd/ray_packet.h"
#include "simd/triangle_blocks.h"
#include "simd/wide_bvh.h"
#include "volley/options.h"
#include "volley/ray.h"

namespace volley::simd {

/// Rays per packet of the packet traversal (RayPacket<16>); the API widens K = 4 and 8.
inline constexpr int kWidePacket = 16;

/// Packet traversal hands a subtree to single-ray traversal, lane by lane, once this few
/// lanes (or fewer) are still active in it (Embree's "switch threshold"). Measured on Sponza
/// shadow and diffuse packets: 1 to 5 within noise of each other, 0 (never) and 8 slower.
inline constexpr int kPacketSwitchLanes = 3;

namespace detail {
/// The walk a packet takes, chosen by WideKernels::screen from its valid lanes.
enum class PacketWalk : std::uint32_t {
  mixed_octants,  ///< the per-lane walk, each lane ordering children by its own octant
  one_octant,     ///< the per-lane walk, one near-to-far order for the whole packet
  frustum,        ///< one octant, one origin, no zero direction component: the frustum walk
};

/// What the single-ray entry learns of a ray before its walk (WideKernels::prepare_single).
enum class RayScreen {
  rejected,           ///< the oracle rejects it: a non-finite origin or direction, a NaN interval end
  zero_component,     ///< some direction component is ±0: slab distances may be NaN (0 * inf)
  no_zero_component,  ///< every component nonzero: the walk may combine slab distances as a tree
};

/// The lane setup of a packet, computed once by WideKernels::screen.
template <int K>
struct alignas(64) PacketSetup {
  float inv[3][K];      // 12K bytes: 1 / dir per lane, as the oracle (±inf for ±0)
  std::uint32_t valid;  //  4 bytes: the active lanes the oracle does not reject
  PacketWalk walk;      //  4 bytes
};
}  // namespace detail

/// What the kernels read of a built WideBvh: raw pointers (the owner keeps the storage).
template <class Block>
struct WideView {
  const WideNode<kWideN>* nodes;  ///< 64-byte aligned
  const Block* blocks;            ///< 64-byte aligned
  std::uint32_t root;             ///< root reference (wide_ref)
};

/// Traversal of the wide BVH with the triangle test `Test` on Arch; leaf blocks hold
/// W = kLanes<SingleRayArch<Arch>> triangles (8 on AVX-512, whose packets still run 16
/// lanes: single rays were faster on 8-triangle leaves, packets no slower). Robust = false
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
template <class Arch, TriangleTest Test, bool Robust = true>
struct WideKernels {
  static constexpr int N = kWideN;
  static constexpr int L = kLanes<Arch>;
  static constexpr int K = kWidePacket;
  /// The single-ray leaf kernels' arch; its lanes are the block width (8 on AVX-512).
  using SingleArch = SingleRayArch<Arch>;
  static constexpr int W = kLanes<SingleArch>;
  using Block = BlockFor<Test, W>;
  using View = WideView<Block>;

  /// Closest hit of one ray: updates `hit` with every triangle hit at
  /// ray.tmin <= t < min(hit.t, ray.tmax) that is nearer (as RayBlockKernels::intersect).
  /// `bvh` is a const View*, type-erased so that the facade (accel::WideAccel) calls this
  /// through a plain function pointer: one call per ray.
  static void intersect_erased(const void* bvh, const Ray& ray, Hit& hit);
  /// True when some triangle is hit with ray.tmin <= t < ray.tmax (`bvh` as above).
  static bool occluded_erased(const void* bvh, const Ray& ray);

  /// Closest hits of the active lanes of a packet (bit i of rays.active): lane i's
  /// hits.t[i] on entry bounds its search like tmax (reset() makes it +inf); only lanes
  /// that find a nearer hit are written. Inactive lanes are never hit, but the leaf kernels
  /// load and store whole chunks of lanes (unchanged values in lanes without a hit):
  /// Accel hands a packet with inactive lanes over as a copy.
  static void intersect(const View& bvh, const RayPacket<K>& rays, HitPacket<K>& hits);
  /// The active lanes of `rays` that some triangle occludes (tmin <= t < tmax), as a mask.
  static std::uint32_t occluded(const View& bvh, const RayPacket<K>& rays);

  /// Single-ray traversal of the subtree `start` (the packet traversal's fallback).
  template <bool AnyHit>
  static bool trace_single(const View& bvh, const Ray& ray, std::uint32_t start, Hit& hit);

  /// Leaves the packet's valid lanes active (the active lanes the oracle does not reject:
  /// finite origin and direction, tmin and tmax not NaN), makes the rejected ones inert, and
  /// fills `setup` (see PacketSetup). The frustum walk's common origin is that of the
  /// first valid lane (a rejected lane's origin is no reference).
  static void screen(RayPacket<K>& rays, detail::PacketSetup<K>& setup);

 private:
  /// The start of every single-ray trace, prepare_ray's work done here: the watertight
  /// shear comes from the registers that hold the reciprocal direction (the call to
  /// prepare_ray cost 4% of diffuse rays' time). Returns whether the oracle rejects the ray
  /// (a non-finite origin or direction component, a NaN interval end), else whether some
  /// direction component is ±0, with `pr` complete and the reciprocal direction in `inv`.
  template <bool AnyHit>
  [[gnu::always_inline]] inline static detail::RayScreen prepare_single(const Ray& ray, PreparedRay& pr, __m128& inv);
  /// Single-ray traversal of the subtree `start`, prepared here: intersect_erased,
  /// occluded_erased and trace_single.
  template <bool AnyHit>
  [[gnu::always_inline]] inline static bool trace_ray(const View& bvh, const Ray& ray, std::uint32_t start, Hit& hit);
  /// The single-ray walk. NoZero: no direction component is ±0, so no slab distance can be
  /// NaN and the entry and exit bounds may be combined as a tree (shorter dependency chain).
  /// Inlined into its callers: the call, its frame and the vzeroupper before it cost 1-2.5%
  /// of single rays (Sponza and kitchen diffuse +1%, kitchen primary +2.5%).
  template <bool AnyHit, bool NoZero>
  [[gnu::always_inline]] inline static bool walk(const View& bvh, const PreparedRay& ray, __m128 inv,
                                                 std::uint32_t start, Hit& hit);

  /// Bits of the first L lanes.
  static constexpr std::uint32_t kChunkBits = (1u << L) - 1u;
  /// The frustum walk of a coherent packet: one 8-wide interval test per node for the whole
  /// packet, per-lane tests only at leaves. Requires every valid lane in one octant with no
  /// zero direction component (screen() says so); taken only for packets whose lanes share
  /// one origin (pinhole primary rays): with spread origins (shadow rays from a 4x4 block of
  /// hit points) the interval frustum grows loose and the per-lane walk was measured 2-3x
  /// faster (Sponza, conference), while for one origin the frustum walk was 1.3-1.8x faster.
  template <bool AnyHit>
  static std::uint32_t trace_frustum(const View& bvh, PreparedPacket<K>& prep, const detail::PacketSetup<K>& setup,
                                     HitPacket<K>& hits);
  /// Triangles used in a block: the lanes before its padding (prim = kInvalidPrim).
  static int used_lanes(const Block& block);
  /// A leaf for the active lanes of a packet: the block kernels, except that a last block at
  /// most half full is tested triangle by triangle (padding lanes cost a full test each in
  /// the block form). Same answers and order as PacketKernels::intersect / occluded.
  static void leaf_intersect(const PreparedPacket<K>& prep, const Block* blocks, std::uint32_t count,
                             HitPacket<K>& hits);
  static std::uint32_t leaf_occluded(PreparedPacket<K>& prep, const Block* blocks, std::uint32_t count,
                                     std::uint32_t lanes);
  /// The packet walk over prepared lanes (prep.rays.active is rewritten per leaf).
  template <bool AnyHit, bool Uniform>
  static std::uint32_t trace_packet(const View& bvh, PreparedPacket<K>& prep, const detail::PacketSetup<K>& setup,
                                    HitPacket<K>& hits);
};

namespace detail {

/// Eight float lanes, one per child of a WideNode<8>: one AVX register (AVX2 and AVX-512,
/// whose 16 lanes would be half empty), or two SSE registers. Raw intrinsics (always
/// inlined, no symbols) inside members of a class templated on Arch.
template <class Arch, bool Avx = (kLanes<Arch> >= 8)>
struct Lanes8;

template <class Arch>
struct Lanes8<Arch, true> {
  using V = __m256;
  static V load(const float* p) { return _mm256_load_ps(p); }
  static V set1(float x) { return _mm256_set1_ps(x); }
  /// Lane L of v in every lane, from the register (no store and reload).
  template <int L>
  static V lane(__m128 v) {
    return _mm256_broadcastss_ps(L == 0 ? v : _mm_shuffle_ps(v, v, L * 0x55));
  }
  static V sub(V a, V b) { return _mm256_sub_ps(a, b); }
  static V mul(V a, V b) { return _mm256_mul_ps(a, b); }
  /// The ISA has FMA (AVX2 + FMA, AVX-512): slab distances in one rounding (walk).
  static constexpr bool kFma = true;
  /// a b - c, rounded once.
  static V fmsub(V a, V b, V c) { return _mm256_fmsub_ps(a, b, c); }
  /// maxps(a, b): b when either is NaN.
  static V max(V a, V b) { return _mm256_max_ps(a, b); }
  /// minps(a, b): b when either is NaN.
  static V min(V a, V b) { return _mm256_min_ps(a, b); }
  /// Bit i set when a[i] <= b[i] (false for NaN).
  static std::uint32_t le(V a, V b) {
    return static_cast<std::uint32_t>(_mm256_movemask_ps(_mm256_cmp_ps(a, b, _CMP_LE_OQ)));
  }
  static void store(float* p, V a) { _mm256_store_ps(p, a); }
};

template <class Arch>
struct Lanes8<Arch, false> {
  struct V {
    __m128 a, b;
  };
  static V load(const float* p) { return {_mm_load_ps(p), _mm_load_ps(p + 4)}; }
  static V set1(float x) { return {_mm_set1_ps(x), _mm_set1_ps(x)}; }
  template <int L>
  static V lane(__m128 v) {
    const __m128 b = _mm_shuffle_ps(v, v, L * 0x55);
    return {b, b};
  }
  static V sub(V x, V y) { return {_mm_sub_ps(x.a, y.a), _mm_sub_ps(x.b, y.b)}; }
  static V mul(V x, V y) { return {_mm_mul_ps(x.a, y.a), _mm_mul_ps(x.b, y.b)}; }
  static constexpr bool kFma = false;
  static V max(V x, V y) { return {_mm_max_ps(x.a, y.a), _mm_max_ps(x.b, y.b)}; }
  static V min(V x, V y) { return {_mm_min_ps(x.a, y.a), _mm_min_ps(x.b, y.b)}; }
  static std::uint32_t le(V x, V y) {
    return static_cast<std::uint32_t>(_mm_movemask_ps(_mm_cmple_ps(x.a, y.a)) |
                                      (_mm_movemask_ps(_mm_cmple_ps(x.b, y.b)) << 4));
  }
  static void store(float* p, V x) {
    _mm_store_ps(p, x.a);
    _mm_store_ps(p + 4, x.b);
  }
};

/// A stack entry of single-ray traversal: a subtree and the ray's entry distance into it.
template <class Arch>
struct WideStackItem {
  std::uint32_t ref;
  float entry;
};
static_assert(sizeof(WideStackItem<xsimd::avx2>) == 8 && offsetof(WideStackItem<xsimd::avx2>, entry) == 4,
              "stack_word packs an item as one little-endian 64-bit word");

/// A stack entry of the frustum walk: a subtree, the packet's lower bound of the entry
/// distances into it, and (leaves) the lanes whose own box test passed.
template <class Arch>
struct FrustumItem {
  std::uint32_t ref;
  float entry;
  std::uint32_t lanes;
};

/// Smallest lane of v (no lane NaN).
template <class Arch>
float reduce_min(FloatB<Arch> v) {
  __m128 m;
  if constexpr (kLanes<Arch> == 16) {
    const __m256 h = _mm256_min_ps(_mm512_castps512_ps256(v), _mm512_extractf32x8_ps(v, 1));
    m = _mm_min_ps(_mm256_castps256_ps128(h), _mm256_extractf128_ps(h, 1));
  } else if constexpr (kLanes<Arch> == 8) {
    m = _mm_min_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  } else {
    m = v;
  }
  m = _mm_min_ps(m, _mm_movehl_ps(m, m));
  m = _mm_min_ss(m, _mm_shuffle_ps(m, m, 1));
  return _mm_cvtss_f32(m);
}

/// Largest lane of v (no lane NaN).
template <class Arch>
float reduce_max(FloatB<Arch> v) {
  __m128 m;
  if constexpr (kLanes<Arch> == 16) {
    const __m256 h = _mm256_max_ps(_mm512_castps512_ps256(v), _mm512_extractf32x8_ps(v, 1));
    m = _mm_max_ps(_mm256_castps256_ps128(h), _mm256_extractf128_ps(h, 1));
  } else if constexpr (kLanes<Arch> == 8) {
    m = _mm_max_ps(_mm256_castps256_ps128(v), _mm256_extractf128_ps(v, 1));
  } else {
    m = v;
  }
  m = _mm_max_ps(m, _mm_movehl_ps(m, m));
  m = _mm_max_ss(m, _mm_shuffle_ps(m, m, 1));
  return _mm_cvtss_f32(m);
}

/// A stack item (WideStackItem: ref, then entry) as one 64-bit word: ref in the low half,
/// the entry's bits in the high.
[[gnu::always_inline]] inline std::uint64_t stack_word(std::uint32_t ref, float entry) {
  return (std::uint64_t{std::bit_cast<std::uint32_t>(entry)} << 32) | ref;
}

/// Sorts stack words far to near, stably (odd-even transposition: compare-exchanges of
/// neighbours, swapping only when strictly out of order, as the insertion sort): w[0] is
/// the farthest.
template <int Count>
[[gnu::always_inline]] inline void sort_far_first(std::uint64_t* w) {
  auto entry = [](std::uint64_t x) { return std::bit_cast<float>(static_cast<std::uint32_t>(x >> 32)); };
  for (int round = 0; round < Count; ++round) {
    for (int k = round & 1; k + 1 < Count; k += 2) {
      const bool swap = entry(w[k]) < entry(w[k + 1]);
      const std::uint64_t a = swap ? w[k + 1] : w[k], b = swap ? w[k] : w[k + 1];
      w[k] = a, w[k + 1] = b;
    }
  }
}

/// Entries a traversal stack needs: every wide level pushes at most N - 1 entries more
/// than it pops, and a wide BVH is no deeper than its binary BVH (< kBvhMaxDepth).
inline constexpr int kWideStack = (kWideN - 1) * core::kBvhMaxDepth + 1;

}  // namespace detail

// ---------------------------------------------------------------------------------------
// Single ray

template <class Arch, TriangleTest Test, bool Robust>
template <bool AnyHit>
bool WideKernels<Arch, Test, Robust>::trace_single(const View& bvh, const Ray& ray, std::uint32_t start, Hit& hit) {
  return trace_ray<AnyHit>(bvh, ray, start, hit);
}

template <class Arch, TriangleTest Test, bool Robust>
template <bool AnyHit>
bool WideKernels<Arch, Test, Robust>::trace_ray(const View& bvh, const Ray& ray, std::uint32_t start, Hit& hit) {
  if (start == wide_ref::kEmptyRef) return false;
  PreparedRay pr;
  __m128 inv;
  switch (prepare_single<AnyHit>(ray, pr, inv)) {
    case detail::RayScreen::no_zero_component:
      return walk<AnyHit, true>(bvh, pr, inv, start, hit);
    case detail::RayScreen::zero_component:
      return walk<AnyHit, false>(bvh, pr, inv, start, hit);
    case detail::RayScreen::rejected:
      break;
  }
  return false;
}

template <class Arch, TriangleTest Test, bool Robust>
template <bool AnyHit, bool NoZero>
bool WideKernels<Arch, Test, Robust>::walk(const View& bvh, const PreparedRay& pr, __m128 inv, std::uint32_t start,
                                           Hit& hit) {
  using V8 = detail::Lanes8<Arch>;
  using Leaf = RayBlockKernels<SingleArch, Test>;
  static_assert(N == 8, "the single-ray node test reads eight children");
  const Ray& ray = pr.ray;
  // The octant by the sign bit of the reciprocal; near plane of axis a is bounds[2a + neg],
  // far the other.
  const int negative = _mm_movemask_ps(inv);
  int near_plane[3];
  for (int a = 0; a < 3; ++a) near_plane[a] = 2 * a + ((negative >> a) & 1);
  const int fx = near_plane[0] ^ 1, fy = near_plane[1] ^ 1, fz = near_plane[2] ^ 1;
  const int nx = near_plane[0], ny = near_plane[1], nz = near_plane[2];
  const auto ox = V8::set1(ray.org[0]), oy = V8::set1(ray.org[1]), oz = V8::set1(ray.org[2]);
  const auto ix = V8::template lane<0>(inv), iy = V8::template lane<1>(inv), iz = V8::template lane<2>(inv);
  const auto tmin = V8::set1(ray.tmin);
  const float pad1 = Robust ? core::kSlabExitPad : 1.0f;
  // Far distances use the reciprocal times the exit padding, rounded once per ray:
  // fl(d * fl(inv * pad)) carries the same (1 + eps)^2 bound around d * inv * pad as the
  // oracle's fl(fl(d * inv) * pad), so the 2 gamma(3) margin still covers the rounding of
  // both ends (the padding was sized for the sub, reciprocal and product roundings), and
  // the node test loses a multiply from its longest dependency chain. ±inf stays ±inf.
  const __m128 finv = _mm_mul_ps(inv, _mm_set1_ps(pad1));
  const auto fix = V8::template lane<0>(finv), fiy = V8::template lane<1>(finv), fiz = V8::template lane<2>(finv);
  // With FMA and no zero direction component, a slab distance is one fused operation,
  // b inv - c, where c is org inv rounded outwards (up for near planes, down for far ones)
  // once per ray. Against (b - org) inv that moves near distances down and far ones up by a
  // few ulps of org inv, and rounds once instead of twice, so the padding that covers the
  // two-rounding form covers it (never culls a box the exact ray meets). NaN (inf - inf,
  // only for a subnormal direction component, whose reciprocal overflows) is dropped by
  // max/min as in the other form.
  constexpr bool kFused = NoZero && V8::kFma;
  typename V8::V cnx{}, cny{}, cnz{}, cfx{}, cfy{}, cfz{};
  if constexpr (kFused) {
    // c = p +- (|p| 2^-22 + 2^-149) with p = fl(org inv): p is within 2^-24 |org inv| of the
    // exact product (2^-150 if subnormal), so the widened c lies beyond it even after its
    // own rounding. Three lanes at once; an infinite p gives +inf or NaN, both harmless.
    const __m128 org = _mm_loadu_ps(ray.org), sign = _mm_set1_ps(-0.0f);
    // (Robust = false: c = p, no widening, as it has no padding.)
    const __m128 rel = _mm_set1_ps(Robust ? 0x1p-22f : 0.0f), tiny = _mm_set1_ps(Robust ? 0x1p-149f : 0.0f);
    const __m128 pn = _mm_mul_ps(org, inv);
    const __m128 pf = _mm_mul_ps(org, finv);
    const __m128 cn = _mm_add_ps(pn, _mm_add_ps(_mm_mul_ps(_mm_andnot_ps(sign, pn), rel), tiny));
    const __m128 cf = _mm_sub_ps(pf, _mm_add_ps(_mm_mul_ps(_mm_andnot_ps(sign, pf), rel), tiny));
    cnx = V8::template lane<0>(cn), cny = V8::template lane<1>(cn), cnz = V8::template lane<2>(cn);
    cfx = V8::template lane<0>(cf), cfy = V8::template lane<1>(cf), cfz = V8::template lane<2>(cf);
  }

  // The upper end of the search (as RayBlockKernels: the nearer of hit.t and tmax).
  float tmax = hit.t < ray.tmax ? hit.t : ray.tmax;
  auto tmax8 = V8::set1(tmax * pad1);
  detail::WideStackItem<Arch> stack[detail::kWideStack];
  int size = 0;
  bool found = false;
  std::uint32_t ref = start;
  const WideNode<N>* const nodes = bvh.nodes;  // not reloaded after each leaf call
  const Block* const all_blocks = bvh.blocks;
  for (;;) {
    if (!(ref & wide_ref::kLeafBit)) {
      // Interior: slab test of all eight children at once.
      const WideNode<N>& node = wide_ref::node_at(nodes, ref);
      // The child references sit on the node's fourth cache line, read only after the slab
      // test: request it now, beside the three lines of boxes.
      _mm_prefetch(reinterpret_cast<const char*>(node.child), _MM_HINT_T0);
      typename V8::V tnx, tny, tnz, tfx, tfy, tfz;
      if constexpr (kFused) {
        tnx = V8::fmsub(V8::load(node.bounds[nx]), ix, cnx);
        tny = V8::fmsub(V8::load(node.bounds[ny]), iy, cny);
        tnz = V8::fmsub(V8::load(node.bounds[nz]), iz, cnz);
        tfx = V8::fmsub(V8::load(node.bounds[fx]), fix, cfx);
        tfy = V8::fmsub(V8::load(node.bounds[fy]), fiy, cfy);
        tfz = V8::fmsub(V8::load(node.bounds[fz]), fiz, cfz);
      } else {
        tnx = V8::mul(V8::sub(V8::load(node.bounds[nx]), ox), ix);
        tny = V8::mul(V8::sub(V8::load(node.bounds[ny]), oy), iy);
        tnz = V8::mul(V8::sub(V8::load(node.bounds[nz]), oz), iz);
        tfx = V8::mul(V8::sub(V8::load(node.bounds[fx]), ox), fix);
        tfy = V8::mul(V8::sub(V8::load(node.bounds[fy]), oy), fiy);
        tfz = V8::mul(V8::sub(V8::load(node.bounds[fz]), oz), fiz);
      }
      typename V8::V entry, exit;
      if constexpr (NoZero) {
        // Combined as a tree. No direction component is ±0, but a subnormal one has an
        // infinite reciprocal, so a distance can still be NaN (origin on the plane). The tree
        // stays NaN-free: tmin / tmax8 are never NaN, so the right halves are not; a NaN left
        // half then yields the right one. A NaN drops its partner distance too, which only
        // lowers entry or raises exit: more boxes visited, never fewer (tests/accel:
        // subnormal directions).
        entry = V8::max(V8::max(tnx, tny), V8::max(tnz, tmin));
        exit = V8::min(V8::min(tfx, tfy), V8::min(tfz, tmax8));
      } else {
        entry = V8::max(tnz, V8::max(tny, V8::max(tnx, tmin)));
        exit = V8::min(tfz, V8::min(tfy, V8::min(tfx, tmax8)));
      }
      // The hit children as bits, and the first one's reference. AVX-512 compares into a
      // mask register and takes the reference out of the node's reference vector with one
      // vpcompressd, so the next node's address does not wait for movemask, bit scan and a
      // load indexed by it, the longest chain of the walk (AVX-512, against that: shadow
      // rays +4-7%, primary +8%, diffuse +0-4%).
      std::uint32_t bits;
      std::uint32_t first_ref = 0;
      [[maybe_unused]] __mmask8 k = 0;  // AVX-512: the hit mask and the node's references
      [[maybe_unused]] __m256i refs;
      if constexpr (detail::kHasMaskRegisters<Arch>) {
        k = _mm256_cmp_ps_mask(entry, exit, _CMP_LE_OQ);
        bits = k;
        refs = _mm256_load_si256(reinterpret_cast<const __m256i*>(node.child));
        first_ref =
            static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm256_castsi256_si128(_mm256_maskz_compress_epi32(k, refs))));
      } else {
        bits = V8::le(entry, exit);
        if (bits) first_ref = node.child[std::countr_zero(bits)];
      }
      if (AnyHit && bits != 0) {
        // Any hit: no ordering and no distances (the stack entries are never pruned): the
        // first hit child next, the others on the stack.
        ref = first_ref;
        for (bits &= bits - 1; bits != 0; bits &= bits - 1) stack[size++].ref = node.child[std::countr_zero(bits)];
        continue;
      }
      if (bits != 0) {
        const int i = std::countr_zero(bits);
        bits &= bits - 1;
        if (bits == 0) {
          ref = first_ref;
          continue;
        }
        alignas(32) float dist[8];
        V8::store(dist, entry);
        const int j = std::countr_zero(bits);
        bits &= bits - 1;
        if (bits == 0) {
          // Two children: the nearer next, the other on the stack (selects, not a branch:
          // which one is nearer is a coin toss to the predictor).
          std::uint32_t ci, cj;
          float di, dj;
          if constexpr (detail::kHasMaskRegisters<Arch>) {
            // Both distances and the second reference compressed from registers too, not
            // reloaded from the stored distances.
            const __m128 d = _mm256_castps256_ps128(_mm256_maskz_compress_ps(k, entry));
            ci = first_ref;
            cj = static_cast<std::uint32_t>(
                _mm_extract_epi32(_mm256_castsi256_si128(_mm256_maskz_compress_epi32(k, refs)), 1));
            di = _mm_cvtss_f32(d);
            dj = _mm_cvtss_f32(_mm_movehdup_ps(d));
          } else {
            ci = node.child[i], cj = node.child[j];
            di = dist[i], dj = dist[j];
          }
          const bool swap = dj < di;
          stack[size++] = {swap ? ci : cj, swap ? di : dj};
          ref = swap ? cj : ci;
          continue;
        }
        if (std::popcount(bits) <= 2) {
          // Three or four (90% of the nodes with three or more hit children): sorted in
          // registers by a stable network of compare-exchanges, the nearest reference never
          // stored and reloaded as in the insertion sort below: primary single rays +7-9%,
          // diffuse +1.5-2.5% (AVX2 alike). GCC compiles each exchange to a short branch;
          // branch-free (an xor swap under a mask) was 1-7% slower: the nearest then waits
          // for every exchange. A network for five: no faster.
          std::uint64_t w[4] = {detail::stack_word(node.child[i], dist[i]), detail::stack_word(node.child[j], dist[j]),
                                0, 0};
          const int k = std::countr_zero(bits);
          w[2] = detail::stack_word(node.child[k], dist[k]);
          bits &= bits - 1;
          int n = 3;
          if (bits == 0) {
            detail::sort_far_first<3>(w);
          } else {
            const int l = std::countr_zero(bits);
            w[3] = detail::stack_word(node.child[l], dist[l]);
            detail::sort_far_first<4>(w);
            n = 4;
          }
          std::memcpy(&stack[size], w, 8 * static_cast<std::size_t>(n - 1));
          size += n - 1;
          ref = static_cast<std::uint32_t>(w[n - 1]);
          continue;
        }
        // Five or more: push all, sort the pushed run far to near (insertion sort of at
        // most eight), and continue with the nearest (the top).
        const int base = size;
        stack[size++] = {node.child[i], dist[i]};
        stack[size++] = {node.child[j], dist[j]};
        for (; bits != 0; bits &= bits - 1) {
          const int k = std::countr_zero(bits);
          stack[size++] = {node.child[k], dist[k]};
        }
        for (int a = base + 1; a < size; ++a) {
          const detail::WideStackItem<Arch> item = stack[a];
          int b = a;
          for (; b > base && stack[b - 1].entry < item.entry; --b) stack[b] = stack[b - 1];
          stack[b] = item;
        }
        ref = stack[--size].ref;
        continue;
      }
    } else {
      // Leaf: its blocks, closest hit (lowers tmax) or any hit (ends the walk).
      const std::uint32_t count = (ref >> wide_ref::kCountShift) & wide_ref::kCountMask;
      const Block* blocks = all_blocks + (ref & wide_ref::kFirstMask);
      if constexpr (AnyHit) {
        if (count != 0 && Leaf::occluded_inline(pr, blocks, count)) return true;
      } else if (count != 0) {
        Leaf::template intersect_inline<false>(pr, blocks, count, hit);
        if (hit.t < tmax) {
          tmax = hit.t;
          tmax8 = V8::set1(tmax * pad1);
          found = true;
        }
      }
    }
    // Pop the next subtree that may still hold a hit nearer than tmax (padded as the
    // exit distance: its entry was computed with rounding).
    for (;;) {
      if (size == 0) return found;
      --size;
      if (AnyHit || stack[size].entry <= tmax * pad1) break;
    }
    ref = stack[size].ref;
  }
}

template <class Arch, TriangleTest Test, bool Robust>
template <bool AnyHit>
detail::RayScreen WideKernels<Arch, Test, Robust>::prepare_single(const Ray& ray, PreparedRay& pr, __m128& inv) {
  // Rejected as by the oracle: non-finite origin or direction, NaN interval ends. The ray's
  // eight floats in two registers: x - x is 0 exactly for finite x (NaN for ±inf, NaN), and
  // the interval ends (lane 3) need only be ordered, so one compare per kind and one blend.
  static_assert(offsetof(Ray, tmin) == 12 && offsetof(Ray, dir) == 16 && offsetof(Ray, tmax) == 28);
  const float* const f = reinterpret_cast<const float*>(&ray);  // org, tmin, dir, tmax
  const __m128 org_tmin = _mm_loadu_ps(f), dir = _mm_loadu_ps(f + 4);
  const __m128 zero = _mm_setzero_ps();
  const __m128 ok_o =
      _mm_blend_ps(_mm_cmpeq_ps(_mm_sub_ps(org_tmin, org_tmin), zero), _mm_cmpord_ps(org_tmin, org_tmin), 0b1000);
  const __m128 ok_d = _mm_blend_ps(_mm_cmpeq_ps(_mm_sub_ps(dir, dir), zero), _mm_cmpord_ps(dir, dir), 0b1000);
  if (_mm_movemask_ps(_mm_and_ps(ok_o, ok_d)) != 0xf) return detail::RayScreen::rejected;
  // The oracle's make_box_ray: reciprocal direction, ±inf for a ±0 component (one division
  // for the three; lane 3 is 1 / tmax, unused).
  inv = _mm_div_ps(_mm_set1_ps(1.0f), dir);
  const auto screened = (_mm_movemask_ps(_mm_cmpeq_ps(dir, zero)) & 0x7) == 0 ? detail::RayScreen::no_zero_component
                                                                              : detail::RayScreen::zero_component;
  pr.ray = ray;
  if constexpr (Test != TriangleTest::watertight) {
    pr.k[0] = pr.k[1] = pr.k[2] = 0;  // (moller and plane need nothing more)
    pr.s[0] = pr.s[1] = pr.s[2] = pr.sure[0] = pr.sure[1] = 0.0f;
  } else {
    // core::make_woop_ray, bit for bit. The axes: core::kWoopAxes at the comparisons of |d|
    // and the signs of d, two compares. The quotients, each one IEEE division: d / d[kz] in
    // one divps, and 1 / d[kz] is inv's lane kz.
    const __m128 a = _mm_andnot_ps(_mm_set1_ps(-0.0f), dir);
    const __m128 ge = _mm_cmpge_ps(_mm_shuffle_ps(a, a, _MM_SHUFFLE(3, 1, 0, 0)),   // |d0| |d0| |d1|
                                   _mm_shuffle_ps(a, a, _MM_SHUFFLE(3, 2, 2, 1)));  // |d1| |d2| |d2|
    const int c = _mm_movemask_ps(ge) & 7;
    const int n = _mm_movemask_ps(_mm_cmplt_ps(dir, zero)) & 7;
    // data()[]: with _GLIBCXX_ASSERTIONS (sanitizer builds) std::array's operator[] is an
    // out-of-line weak function, which a per-ISA object must not define. The index is < 64.
    const int e = core::kWoopAxes.data()[c | n << 3];
    const int kx = e & 3, ky = (e >> 2) & 3, kz = e >> 4;
    alignas(16) float q[4], r[4];
    _mm_store_ps(q, _mm_div_ps(dir, _mm_set1_ps(ray.dir[kz])));
    _mm_store_ps(r, inv);
    pr.k[0] = kx, pr.k[1] = ky, pr.k[2] = kz;
    pr.s[0] = q[kx], pr.s[1] = q[ky], pr.s[2] = r[kz];
    const auto [lo, hi] = AnyHit ? core::sure_quotient_range(ray.tmin, ray.tmax) : std::pair{0.0f, 0.0f};
    pr.sure[0] = lo, pr.sure[1] = hi;  // (any hit only)
  }
  return screened;
}

template <class Arch, TriangleTest Test, bool Robust>
void WideKernels<Arch, Test, Robust>::intersect_erased(const void* bvh, const Ray& ray, Hit& hit) {
  const View& view = *static_cast<const View*>(bvh);
  trace_ray<false>(view, ray, view.root, hit);
}

template <class Arch, TriangleTest Test, bool Robust>
bool WideKernels<Arch, Test, Robust>::occluded_erased(const void* bvh, const Ray& ray) {
  const View& view = *static_cast<const View*>(bvh);
  Hit unused;
  return trace_ray<true>(view, ray, view.root, unused);
}

// ---------------------------------------------------------------------------------------
// Packets of 16 rays

template <class Arch, TriangleTest Test, bool Robust>
void WideKernels<Arch, Test, Robust>::intersect(const View& bvh, const RayPacket<K>& rays, HitPacket<K>& hits) {
  if (bvh.root == wide_ref::kEmptyRef || (rays.active & ((1u << K) - 1u)) == 0) return;
  PreparedPacket<K> prep;
  prep.rays = rays;
  detail::PacketSetup<K> setup;
  screen(prep.rays, setup);
  if (setup.valid == 0) return;
  PacketKernels<Arch, Test, K, W>::prepare(prep.rays, prep);
  switch (setup.walk) {
    case detail::PacketWalk::frustum:
      trace_frustum<false>(bvh, prep, setup, hits);
      break;
    case detail::PacketWalk::one_octant:
      trace_packet<false, true>(bvh, prep, setup, hits);
      break;
    case detail::PacketWalk::mixed_octants:
      trace_packet<false, false>(bvh, prep, setup, hits);
      break;
  }
}

template <class Arch, TriangleTest Test, bool Robust>
std::uint32_t WideKernels<Arch, Test, Robust>::occluded(const View& bvh, const RayPacket<K>& rays) {
  if (bvh.root == wide_ref::kEmptyRef || (rays.active & ((1u << K) - 1u)) == 0) return 0;
  PreparedPacket<K> prep;
  prep.rays = rays;
  detail::PacketSetup<K> setup;
  screen(prep.rays, setup);
  if (setup.valid == 0) return 0;
  PacketKernels<Arch, Test, K, W>::prepare(prep.rays, prep);
  HitPacket<K> unused;
  switch (setup.walk) {
    case detail::PacketWalk::frustum:
      return trace_frustum<true>(bvh, prep, setup, unused);
    case detail::PacketWalk::one_octant:
      return trace_packet<true, true>(bvh, prep, setup, unused);
    case detail::PacketWalk::mixed_octants:
      break;
  }
  return trace_packet<true, false>(bvh, prep, setup, unused);
}

template <class Arch, TriangleTest Test, bool Robust>
void WideKernels<Arch, Test, Robust>::screen(RayPacket<K>& rays, detail::PacketSetup<K>& setup) {
  using B = detail::FloatB<Arch>;
  using M = detail::MaskB<Arch>;
  constexpr int C = K / L;
  const B zero(0.0f);
  std::uint32_t valid = 0, negx = 0, negy = 0, negz = 0, zeros = 0, other_origin = 0;
  for (int c = 0; c < C; ++c) {
    const int o = c * L;
    const B ox = B::load_aligned(rays.ox + o), oy = B::load_aligned(rays.oy + o), oz = B::load_aligned(rays.oz + o);
    const B dx = B::load_aligned(rays.dx + o), dy = B::load_aligned(rays.dy + o), dz = B::load_aligned(rays.dz + o);
    const B tmin = B::load_aligned(rays.tmin + o), tmax = B::load_aligned(rays.tmax + o);
    // Finite: x - x is 0, NaN for Inf and NaN. Not NaN: x == x.
    const M ok = detail::mask_from_bits<Arch>((rays.active >> o) & kChunkBits) & ((ox - ox) == zero) &
                 ((oy - oy) == zero) & ((oz - oz) == zero) & ((dx - dx) == zero) & ((dy - dy) == zero) &
                 ((dz - dz) == zero) & (tmin == tmin) & (tmax == tmax);
    // The oracle's reciprocal and octant (sign bit of 1 / dir: 1 / -0 = -inf < 0).
    const B ix = B(1.0f) / dx, iy = B(1.0f) / dy, iz = B(1.0f) / dz;
    ix.store_aligned(setup.inv[0] + o);
    iy.store_aligned(setup.inv[1] + o);
    iz.store_aligned(setup.inv[2] + o);
    const std::uint32_t okb = detail::bits_from_mask<Arch>(ok);
    valid |= okb << o;
    negx |= (detail::bits_from_mask<Arch>(ix < zero) & okb) << o;
    negy |= (detail::bits_from_mask<Arch>(iy < zero) & okb) << o;
    negz |= (detail::bits_from_mask<Arch>(iz < zero) & okb) << o;
    zeros |= (detail::bits_from_mask<Arch>((dx == zero) | (dy == zero) | (dz == zero)) & okb) << o;
    // Rejected lanes become inert: org = dir = 0, tmin = 0, tmax = -inf.
    if (okb != kChunkBits) {
      xsimd::select(ok, ox, zero).store_aligned(rays.ox + o);
      xsimd::select(ok, oy, zero).store_aligned(rays.oy + o);
      xsimd::select(ok, oz, zero).store_aligned(rays.oz + o);
      xsimd::select(ok, dx, zero).store_aligned(rays.dx + o);
      xsimd::select(ok, dy, zero).store_aligned(rays.dy + o);
      xsimd::select(ok, dz, zero).store_aligned(rays.dz + o);
      xsimd::select(ok, tmin, zero).store_aligned(rays.tmin + o);
      xsimd::select(ok, tmax, B(-std::numeric_limits<float>::infinity())).store_aligned(rays.tmax + o);
    }
  }
  // The common origin of the frustum walk: the first valid lane's (a rejected lane, NaN
  // origin or not, would make every other lane differ).
  const int first = std::countr_zero(valid | (1u << (K - 1)));
  const B fx(rays.ox[first]), fy(rays.oy[first]), fz(rays.oz[first]);
  for (int c = 0; c < C; ++c) {
    const int o = c * L;
    const B ox = B::load_aligned(rays.ox + o), oy = B::load_aligned(rays.oy + o), oz = B::load_aligned(rays.oz + o);
    other_origin |= (detail::bits_from_mask<Arch>((ox != fx) | (oy != fy) | (oz != fz)) & (valid >> o) & kChunkBits)
                    << o;
  }
  rays.active = valid;
  setup.valid = valid;
  const bool one_octant = (negx == 0 || negx == valid) && (negy == 0 || negy == valid) && (negz == 0 || negz == valid);
  setup.walk = !one_octant                       ? detail::PacketWalk::mixed_octants
               : zeros == 0 && other_origin == 0 ? detail::PacketWalk::frustum
                                                 : detail::PacketWalk::one_octant;
}

template <class Arch, TriangleTest Test, bool Robust>
int WideKernels<Arch, Test, Robust>::used_lanes(const Block& block) {
  using I = detail::IntB<SingleArch>;
  const I ids = I::load_aligned(reinterpret_cast<const std::int32_t*>(block.prim));
  const auto used = xsimd::bool_cast(ids != I(static_cast<std::int32_t>(kInvalidPrim)));
  return std::popcount(detail::bits_from_mask<SingleArch>(used));
}

template <class Arch, TriangleTest Test, bool Robust>
void WideKernels<Arch, Test, Robust>::leaf_intersect(const PreparedPacket<K>& prep, const Block* blocks,
                                                     std::uint32_t count, HitPacket<K>& hits) {
  using LeafPacket = PacketKernels<Arch, Test, K, W>;
  const Block& last = blocks[count - 1];
  const int used = used_lanes(last);
  if (used > W / 2) return LeafPacket::intersect(prep, blocks, count, hits);
  if (count > 1) LeafPacket::intersect(prep, blocks, count - 1, hits);
  for (int j = 0; j < used; ++j) LeafPacket::intersect_triangle(prep, last, j, hits);
}

template <class Arch, TriangleTest Test, bool Robust>
std::uint32_t WideKernels<Arch, Test, Robust>::leaf_occluded(PreparedPacket<K>& prep, const Block* blocks,
                                                             std::uint32_t count, std::uint32_t lanes) {
  using LeafPacket = PacketKernels<Arch, Test, K, W>;
  const Block& last = blocks[count - 1];
  const int used = used_lanes(last);
  if (used > W / 2) return LeafPacket::occluded(prep, blocks, count, lanes);
  std::uint32_t hit = count > 1 ? LeafPacket::occluded(prep, blocks, count - 1, lanes) : 0u;
  if (hit == lanes) return hit;
  // Any hit within [tmin, tmax) of a lane: a closest-hit test against a fresh +inf bound.
  HitPacket<K> scratch;
  for (int i = 0; i < K; ++i) scratch.t[i] = std::numeric_limits<float>::infinity(), scratch.prim[i] = kInvalidPrim;
  const std::uint32_t saved = prep.rays.active;
  prep.rays.active = lanes & ~hit;
  for (int j = 0; j < used; ++j) LeafPacket::intersect_triangle(prep, last, j, scratch);
  prep.rays.active = saved;
  for (int i = 0; i < K; ++i)
    if (scratch.prim[i] != kInvalidPrim) hit |= 1u << i;
  return hit & lanes;
}

// Frustum traversal of a coherent packet (the interval form of Reshetov et al., "Multi-level
// ray tracing algorithm", SIGGRAPH 2005; Embree's coherent mode): the slab distances of all
// lanes are bounded by interval arithmetic on [min, max] of origins and reciprocal
// directions, so one 8-wide test per node answers "may any lane hit this child?".
//
// Conservative by monotonicity, with no padding of its own: for a lane, the oracle's slab
// distance fl(fl(b - o) * inv) is monotone in o and, for fixed sign of b - o, in inv
// (rounding to nearest is monotone), so over the packet's box of (o, inv) its extremes are
// at corners: the near distance is at least min(fl(d * inv_min), fl(d * inv_max)) with
// d = fl(b - o) for the origin bound that makes d smallest along the ray (inv > 0: o_max;
// inv < 0: o_min), and the far distance at most the max of the products of the other
// bound. Every valid lane has a finite, nonzero direction (screen()), but a subnormal
// component has an infinite reciprocal, so a product 0 * inf (an origin bound on the plane)
// can be NaN: min / max then take the other corner's product (0 for a zero difference), or
// drop the axis at the entry / exit combination (tmin and far_hi are never NaN); the bounds
// stay NaN-free (tests/accel: subnormal directions, against the oracle).
// Inert children give ±inf products. A child passes when
// max(near bounds, min tmin) <= min(far bounds, max tfar) * kSlabExitPad, which holds
// whenever some lane's own padded test would. Leaves are tested per lane (the oracle's test
// exactly, against each lane's own tfar) to pick the lanes handed to the block kernels.
template <class Arch, TriangleTest Test, bool Robust>
template <bool AnyHit>
std::uint32_t WideKernels<Arch, Test, Robust>::trace_frustum(const View& bvh, PreparedPacket<K>& prep,
                                                             const detail::PacketSetup<K>& setup, HitPacket<K>& hits) {
  using V8 = detail::Lanes8<Arch>;
  using B = detail::FloatB<Arch>;
  constexpr int C = K / L;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const RayPacket<K>& rays = prep.rays;
  const std::uint32_t valid = setup.valid;
  const float pad1 = Robust ? core::kSlabExitPad : 1.0f;
  const B pinf(kInf), ninf(-kInf);

  // Per-lane rays (for the leaf box tests) and the packet's intervals.
  B ox[C], oy[C], oz[C], ix[C], iy[C], iz[C], tmin[C], tfar[C];
  B olo[3] = {pinf, pinf, pinf}, ohi[3] = {ninf, ninf, ninf}, ilo[3] = {pinf, pinf, pinf}, ihi[3] = {ninf, ninf, ninf};
  B tmin_lo = pinf, tfar_hi = ninf;
  for (int c = 0; c < C; ++c) {
    const int o = c * L;
    const auto ok = detail::mask_from_bits<Arch>((valid >> o) & kChunkBits);
    ox[c] = B::load_aligned(rays.ox + o);
    oy[c] = B::load_aligned(rays.oy + o);
    oz[c] = B::load_aligned(rays.oz + o);
    ix[c] = B::load_aligned(setup.inv[0] + o);
    iy[c] = B::load_aligned(setup.inv[1] + o);
    iz[c] = B::load_aligned(setup.inv[2] + o);
    tmin[c] = B::load_aligned(rays.tmin + o);
    B upper = B::load_aligned(rays.tmax + o);
    if constexpr (!AnyHit) upper = detail::upper_bound<Arch>(B::load_aligned(hits.t + o), upper);
    tfar[c] = xsimd::select(ok, upper, ninf);
    const B* org[3] = {&ox[c], &oy[c], &oz[c]};
    const B* inv[3] = {&ix[c], &iy[c], &iz[c]};
    for (int a = 0; a < 3; ++a) {
      olo[a] = xsimd::min(olo[a], xsimd::select(ok, *org[a], pinf));
      ohi[a] = xsimd::max(ohi[a], xsimd::select(ok, *org[a], ninf));
      ilo[a] = xsimd::min(ilo[a], xsimd::select(ok, *inv[a], pinf));
      ihi[a] = xsimd::max(ihi[a], xsimd::select(ok, *inv[a], ninf));
    }
    tmin_lo = xsimd::min(tmin_lo, xsimd::select(ok, tmin[c], pinf));
    tfar_hi = xsimd::max(tfar_hi, tfar[c]);
  }
  // Near plane of axis a: bounds[2a + neg]; its differences use the origin bound that
  // makes them smallest along the ray (inv > 0: o_max, inv < 0: o_min), the far plane the other.
  int np[3];
  float o_near[3], o_far[3], i_lo[3], i_hi[3];
  for (int a = 0; a < 3; ++a) {
    const float lo = detail::reduce_min<Arch>(olo[a]), hi = detail::reduce_max<Arch>(ohi[a]);
    i_lo[a] = detail::reduce_min<Arch>(ilo[a]);
    i_hi[a] = detail::reduce_max<Arch>(ihi[a]);
    const bool neg = i_hi[a] < 0.0f;
    np[a] = 2 * a + (neg ? 1 : 0);
    o_near[a] = neg ? lo : hi;
    o_far[a] = neg ? hi : lo;
  }
  const auto onx = V8::set1(o_near[0]), ony = V8::set1(o_near[1]), onz = V8::set1(o_near[2]);
  const auto ofx = V8::set1(o_far[0]), ofy = V8::set1(o_far[1]), ofz = V8::set1(o_far[2]);
  const auto ilx = V8::set1(i_lo[0]), ily = V8::set1(i_lo[1]), ilz = V8::set1(i_lo[2]);
  const auto ihx = V8::set1(i_hi[0]), ihy = V8::set1(i_hi[1]), ihz = V8::set1(i_hi[2]);
  const auto tmin8 = V8::set1(detail::reduce_min<Arch>(tmin_lo));
  const auto pad8 = V8::set1(pad1);
  float far_hi = detail::reduce_max<Arch>(tfar_hi);
  const B padb(pad1);

  detail::FrustumItem<Arch> stack[detail::kWideStack];
  int size = 0;
  std::uint32_t occluded = 0;
  std::uint32_t cur = bvh.root;
  std::uint32_t cur_lanes = valid;
  for (;;) {
    if (!(cur & wide_ref::kLeafBit)) {
      // Interior: the interval slab test of all eight children.
      const WideNode<N>& node = wide_ref::node_at(bvh.nodes, cur);
      const auto dnx = V8::sub(V8::load(node.bounds[np[0]]), onx);
      const auto dny = V8::sub(V8::load(node.bounds[np[1]]), ony);
      const auto dnz = V8::sub(V8::load(node.bounds[np[2]]), onz);
      const auto dfx = V8::sub(V8::load(node.bounds[np[0] ^ 1]), ofx);
      const auto dfy = V8::sub(V8::load(node.bounds[np[1] ^ 1]), ofy);
      const auto dfz = V8::sub(V8::load(node.bounds[np[2] ^ 1]), ofz);
      const auto tnx = V8::min(V8::mul(dnx, ilx), V8::mul(dnx, ihx));
      const auto tny = V8::min(V8::mul(dny, ily), V8::mul(dny, ihy));
      const auto tnz = V8::min(V8::mul(dnz, ilz), V8::mul(dnz, ihz));
      const auto tfx = V8::max(V8::mul(dfx, ilx), V8::mul(dfx, ihx));
      const auto tfy = V8::max(V8::mul(dfy, ily), V8::mul(dfy, ihy));
      const auto tfz = V8::max(V8::mul(dfz, ilz), V8::mul(dfz, ihz));
      const auto entry = V8::max(V8::max(tnx, tny), V8::max(tnz, tmin8));
      const auto exit = V8::mul(V8::min(V8::min(tfx, tfy), V8::min(tfz, V8::set1(far_hi))), pad8);
      std::uint32_t bits = V8::le(entry, exit);
      if (bits != 0) {
        alignas(32) float dist[8];
        V8::store(dist, entry);
        // Push the hit children far to near (insertion by entry bound); the top is next.
        const int base = size;
        for (; bits != 0; bits &= bits - 1) {
          const int j = std::countr_zero(bits);
          const std::uint32_t child = node.child[j];
          std::uint32_t lanes = valid & ~occluded;
          if (child & wide_ref::kLeafBit) {
            // A leaf: the oracle's box test per lane, against each lane's own tfar.
            lanes = 0;
            for (int c = 0; c < C; ++c) {
              const B tnx_l = (B(node.bounds[np[0]][j]) - ox[c]) * ix[c];
              const B tny_l = (B(node.bounds[np[1]][j]) - oy[c]) * iy[c];
              const B tnz_l = (B(node.bounds[np[2]][j]) - oz[c]) * iz[c];
              const B tfx_l = (B(node.bounds[np[0] ^ 1][j]) - ox[c]) * ix[c];
              const B tfy_l = (B(node.bounds[np[1] ^ 1][j]) - oy[c]) * iy[c];
              const B tfz_l = (B(node.bounds[np[2] ^ 1][j]) - oz[c]) * iz[c];
              const B e = xsimd::max(tnz_l, xsimd::max(tny_l, xsimd::max(tnx_l, tmin[c])));
              const B x = xsimd::min(tfz_l, xsimd::min(tfy_l, xsimd::min(tfx_l, tfar[c]))) * padb;
              lanes |= detail::bits_from_mask<Arch>(e <= x) << (c * L);
            }
            lanes &= valid & ~occluded;
            if (lanes == 0) continue;
          }
          int k = size++;
          for (; k > base && stack[k - 1].entry < dist[j]; --k) stack[k] = stack[k - 1];
          stack[k] = {child, dist[j], lanes};
        }
      }
    } else {
      // Leaf: the block kernels on the lanes that entered its box.
      const std::uint32_t count = (cur >> wide_ref::kCountShift) & wide_ref::kCountMask;
      const Block* blocks = bvh.blocks + (cur & wide_ref::kFirstMask);
      const std::uint32_t lanes = cur_lanes & ~occluded;
      if (count != 0 && lanes != 0) {
        B hi = ninf;
        if constexpr (AnyHit) {
          const std::uint32_t now = leaf_occluded(prep, blocks, count, lanes);
          if (now != 0) {
            occluded |= now;
            if (occluded == valid) return occluded;
            for (int c = 0; c < C; ++c) {
              tfar[c] = xsimd::select(detail::mask_from_bits<Arch>((now >> (c * L)) & kChunkBits), ninf, tfar[c]);
              hi = xsimd::max(hi, tfar[c]);
            }
            far_hi = detail::reduce_max<Arch>(hi);
          }
        } else {
          prep.rays.active = lanes;
          leaf_intersect(prep, blocks, count, hits);
          for (int c = 0; c < C; ++c) {
            const B ht = B::load_aligned(hits.t + c * L);
            tfar[c] = xsimd::select(ht < tfar[c], ht, tfar[c]);
            hi = xsimd::max(hi, tfar[c]);
          }
          far_hi = detail::reduce_max<Arch>(hi);
        }
      }
    }
    // Pop the next subtree some lane may still reach before its tfar.
    for (;;) {
      if (size == 0) return occluded;
      --size;
      if (stack[size].entry <= far_hi * pad1) break;
    }
    cur = stack[size].ref;
    cur_lanes = stack[size].lanes;
  }
}

// Packet traversal after Embree's BVHNIntersectorKHybrid: a stack of (subtree, entry
// distance per lane), NaN for lanes that did not hit the subtree's box; a lane is active in
// a subtree while its entry distance is within its current tmax (padded). Children are
// visited nearest first by the heuristic "any lane enters it before the current best".
// Uniform: every valid lane has the same octant, so the near and far planes are picked once
// for the packet instead of per lane.
template <class Arch, TriangleTest Test, bool Robust>
template <bool AnyHit, bool Uniform>
std::uint32_t WideKernels<Arch, Test, Robust>::trace_packet(const View& bvh, PreparedPacket<K>& prep,
                                                            const detail::PacketSetup<K>& setup, HitPacket<K>& hits) {
  using B = detail::FloatB<Arch>;
  using M = detail::MaskB<Arch>;
  static_assert(B::size == L, "kLanes<Arch> must be the float lane count");
  constexpr int C = K / L;  // chunks of L lanes
  const RayPacket<K>& rays = prep.rays;
  const std::uint32_t valid = setup.valid;
  const float kNaN = std::numeric_limits<float>::quiet_NaN();
  const B inf(std::numeric_limits<float>::infinity());
  const B pad(Robust ? core::kSlabExitPad : 1.0f);

  // Per chunk: origin, reciprocal direction, octant masks, tmin and the current upper end
  // tfar (closest hit: min(tmax, hit t); invalid or finished lanes: -inf).
  B ox[C], oy[C], oz[C], ix[C], iy[C], iz[C], tmin[C], tfar[C];
  M negx[C], negy[C], negz[C];
  for (int c = 0; c < C; ++c) {
    const int o = c * L;
    ox[c] = B::load_aligned(rays.ox + o);
    oy[c] = B::load_aligned(rays.oy + o);
    oz[c] = B::load_aligned(rays.oz + o);
    ix[c] = B::load_aligned(setup.inv[0] + o);
    iy[c] = B::load_aligned(setup.inv[1] + o);
    iz[c] = B::load_aligned(setup.inv[2] + o);
    negx[c] = ix[c] < B(0.0f);
    negy[c] = iy[c] < B(0.0f);
    negz[c] = iz[c] < B(0.0f);
    tmin[c] = B::load_aligned(rays.tmin + o);
    const M ok = detail::mask_from_bits<Arch>((valid >> o) & kChunkBits);
    B upper = B::load_aligned(rays.tmax + o);
    if constexpr (!AnyHit) upper = detail::upper_bound<Arch>(B::load_aligned(hits.t + o), upper);
    tfar[c] = xsimd::select(ok, upper, -inf);
  }
  // Uniform octant: the plane arrays of a valid lane's octant.
  const int lane0 = std::countr_zero(valid);
  const int nx = Uniform && setup.inv[0][lane0] < 0.0f ? 1 : 0;
  const int ny = Uniform && setup.inv[1][lane0] < 0.0f ? 3 : 2;
  const int nz = Uniform && setup.inv[2][lane0] < 0.0f ? 5 : 4;

  alignas(64) float stack_dist[detail::kWideStack][K];
  std::uint32_t stack_ref[detail::kWideStack];
  int size = 0;
  std::uint32_t occluded = 0;

  std::uint32_t cur = bvh.root;
  B cur_dist[C];
  for (int c = 0; c < C; ++c)
    cur_dist[c] = xsimd::select(detail::mask_from_bits<Arch>((valid >> (c * L)) & kChunkBits), tmin[c], B(kNaN));

  for (;;) {
    // Lanes active in `cur`: entry within the current upper end (NaN: not entered).
    M act[C];
    std::uint32_t bits = 0;
    for (int c = 0; c < C; ++c) {
      act[c] = cur_dist[c] <= tfar[c] * pad;
      bits |= detail::bits_from_mask<Arch>(act[c]) << (c * L);
    }
    if constexpr (AnyHit) bits &= ~occluded;
    if (bits != 0 && std::popcount(bits) <= kPacketSwitchLanes) {
      // Few lanes left: the rest of this subtree one ray at a time.
      alignas(64) float far_lanes[K];
      for (int c = 0; c < C; ++c) tfar[c].store_aligned(far_lanes + c * L);
      for (std::uint32_t b = bits; b != 0; b &= b - 1) {
        const int i = std::countr_zero(b);
        const Ray r{
            {rays.ox[i], rays.oy[i], rays.oz[i]}, rays.tmin[i], {rays.dx[i], rays.dy[i], rays.dz[i]}, rays.tmax[i]};
        if constexpr (AnyHit) {
          Hit unused;
          if (trace_single<true>(bvh, r, cur, unused)) {
            occluded |= 1u << i;
            far_lanes[i] = -std::numeric_limits<float>::infinity();
          }
        } else {
          Hit h{hits.t[i], hits.u[i], hits.v[i], hits.prim[i]};
          if (trace_single<false>(bvh, r, cur, h)) {
            hits.t[i] = h.t, hits.u[i] = h.u, hits.v[i] = h.v, hits.prim[i] = h.prim;
            far_lanes[i] = h.t;
          }
        }
      }
      for (int c = 0; c < C; ++c) tfar[c] = B::load_aligned(far_lanes + c * L);
      if (AnyHit && occluded == valid) return occluded;
      bits = 0;
    }
    if (bits != 0) {
      if (!(cur & wide_ref::kLeafBit)) {
        // Interior: each child against the active lanes; keep the first-entered child as the
        // next `cur`, push the others.
        const WideNode<N>& node = wide_ref::node_at(bvh.nodes, cur);
        std::uint32_t next = wide_ref::kEmptyRef;
        B next_dist[C];
        for (int c = 0; c < C; ++c) next_dist[c] = B(kNaN);
        for (int j = 0; j < N; ++j) {
          const std::uint32_t child = node.child[j];
          if (child == wide_ref::kEmptyRef) break;  // used children come first
          B dist[C];
          bool any = false;
          for (int c = 0; c < C; ++c) {
            if (!xsimd::any(act[c])) {
              dist[c] = B(kNaN);
              continue;
            }
            B tnx(0.0f), tny(0.0f), tnz(0.0f), tfx(0.0f), tfy(0.0f), tfz(0.0f);  // set below
            if constexpr (Uniform) {
              tnx = (B(node.bounds[nx][j]) - ox[c]) * ix[c];
              tny = (B(node.bounds[ny][j]) - oy[c]) * iy[c];
              tnz = (B(node.bounds[nz][j]) - oz[c]) * iz[c];
              tfx = (B(node.bounds[nx ^ 1][j]) - ox[c]) * ix[c];
              tfy = (B(node.bounds[ny ^ 1][j]) - oy[c]) * iy[c];
              tfz = (B(node.bounds[nz ^ 1][j]) - oz[c]) * iz[c];
            } else {
              const B lx = (B(node.bounds[0][j]) - ox[c]) * ix[c], hx = (B(node.bounds[1][j]) - ox[c]) * ix[c];
              const B ly = (B(node.bounds[2][j]) - oy[c]) * iy[c], hy = (B(node.bounds[3][j]) - oy[c]) * iy[c];
              const B lz = (B(node.bounds[4][j]) - oz[c]) * iz[c], hz = (B(node.bounds[5][j]) - oz[c]) * iz[c];
              tnx = xsimd::select(negx[c], hx, lx), tfx = xsimd::select(negx[c], lx, hx);
              tny = xsimd::select(negy[c], hy, ly), tfy = xsimd::select(negy[c], ly, hy);
              tnz = xsimd::select(negz[c], hz, lz), tfz = xsimd::select(negz[c], lz, hz);
            }
            // NaN-safe order: xsimd::max/min(distance, running) is maxps/minps with the
            // running bound second.
            const B entry = xsimd::max(tnz, xsimd::max(tny, xsimd::max(tnx, tmin[c])));
            const B exit = xsimd::min(tfz, xsimd::min(tfy, xsimd::min(tfx, tfar[c]))) * pad;
            const M hit = act[c] & (entry <= exit);
            dist[c] = xsimd::select(hit, entry, B(kNaN));
            any = any || xsimd::any(hit);
          }
          if (!any) continue;
          if (next == wide_ref::kEmptyRef) {
            next = child;
            for (int c = 0; c < C; ++c) next_dist[c] = dist[c];
            continue;
          }
          bool nearer = false;
          for (int c = 0; c < C; ++c) nearer = nearer || xsimd::any(dist[c] < next_dist[c]);
          float* slot = stack_dist[size];
          if (nearer) {
            stack_ref[size++] = next;
            for (int c = 0; c < C; ++c) {
              next_dist[c].store_aligned(slot + c * L);
              next_dist[c] = dist[c];
            }
            next = child;
          } else {
            stack_ref[size++] = child;
            for (int c = 0; c < C; ++c) dist[c].store_aligned(slot + c * L);
          }
        }
        if (next != wide_ref::kEmptyRef) {
          cur = next;
          for (int c = 0; c < C; ++c) cur_dist[c] = next_dist[c];
          continue;
        }
      } else {
        // Leaf: the block kernels on the active lanes.
        const std::uint32_t count = (cur >> wide_ref::kCountShift) & wide_ref::kCountMask;
        const Block* blocks = bvh.blocks + (cur & wide_ref::kFirstMask);
        if (count != 0) {
          if constexpr (AnyHit) {
            const std::uint32_t now = leaf_occluded(prep, blocks, count, bits);
            if (now != 0) {
              occluded |= now;
              if (occluded == valid) return occluded;
              for (int c = 0; c < C; ++c)
                tfar[c] = xsimd::select(detail::mask_from_bits<Arch>((now >> (c * L)) & kChunkBits), -inf, tfar[c]);
            }
          } else {
            prep.rays.active = bits;
            leaf_intersect(prep, blocks, count, hits);
            for (int c = 0; c < C; ++c) {
              const B ht = B::load_aligned(hits.t + c * L);
              tfar[c] = xsimd::select(ht < tfar[c], ht, tfar[c]);
            }
          }
        }
      }
    }
    // Pop the next subtree.
    if (size == 0) return occluded;
    --size;
    cur = stack_ref[size];
    for (int c = 0; c < C; ++c) cur_dist[c] = B::load_aligned(stack_dist[size] + c * L);
  }
}

// Explicit instantiation declarations: the definitions live in the per-ISA files only.
// Every test twice: Robust = true (default) and false (Options::robust = false).
extern template struct WideKernels<Sse42, TriangleTest::moller>;
extern template struct WideKernels<Sse42, TriangleTest::plane>;
extern template struct WideKernels<Sse42, TriangleTest::watertight>;
extern template struct WideKernels<Sse42, TriangleTest::moller, false>;
extern template struct WideKernels<Sse42, TriangleTest::plane, false>;
extern template struct WideKernels<Sse42, TriangleTest::watertight, false>;
extern template struct WideKernels<Avx2, TriangleTest::moller>;
extern template struct WideKernels<Avx2, TriangleTest::plane>;
extern template struct WideKernels<Avx2, TriangleTest::watertight>;
extern template struct WideKernels<Avx2, TriangleTest::moller, false>;
extern template struct WideKernels<Avx2, TriangleTest::plane, false>;
extern template struct WideKernels<Avx2, TriangleTest::watertight, false>;
extern template struct WideKernels<Avx512, TriangleTest::moller>;
extern template struct WideKernels<Avx512, TriangleTest::plane>;
extern template struct WideKernels<Avx512, TriangleTest::watertight>;
extern template struct WideKernels<Avx512, TriangleTest::moller, false>;
extern template struct WideKernels<Avx512, TriangleTest::plane, false>;
extern template struct WideKernels<Avx512, TriangleTest::watertight, false>;

}  // namespace volley::simd
