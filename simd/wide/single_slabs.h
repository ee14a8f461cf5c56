// The single-ray walk's node test: the ray's constants, set up once per walk, and the slab
// test of a node's eight children against them (kernels.h states the test and its NaN
// rule; the far distances and the fused form are why this one may differ from the
// oracle's by a few ulps, never by culling).
#pragma once
#include <immintrin.h>

#include <cstddef>
#include <cstdint>

#include "simd/wide/node_lanes.h"

namespace volley::simd {

namespace detail {

/// A ray as the node test reads it: the near planes of its octant as byte offsets into a
/// node's boxes, and the origin, reciprocal and interval start in all eight lanes.
/// NoZero: no direction component is ±0, so the distances may be combined as a tree and,
/// with FMA, each is one fused operation.
template <class Arch, bool Robust, bool NoZero>
struct SingleRaySlabs {
  using V8 = Lanes8<Arch>;
  using V = typename V8::V;
  static constexpr int N = 8;
  /// The exit padding of the conservative test (none for Robust = false).
  static constexpr float kPad = Robust ? core::kSlabExitPad : 1.0f;
  static constexpr bool kFused = NoZero && V8::kFma;

  std::size_t nx, ny, nz, fx, fy, fz;
  V ox, oy, oz, ix, iy, iz, fix, fiy, fiz, tmin;
  V cnx{}, cny{}, cnz{}, cfx{}, cfy{}, cfz{};

  [[gnu::always_inline]] SingleRaySlabs(const Ray& ray, __m128 inv) {
    // The octant by the sign bit of the reciprocal; near plane of axis a is bounds[2a + neg],
    // far the other. As byte offsets, an address is the node plus an offset, with no index
    // to widen and scale at every node.
    const int negative = _mm_movemask_ps(inv);
    constexpr std::size_t kFarPlane = sizeof(WideNode<N>::bounds[0]);  // a far plane's offset from its near one
    nx = ((negative >> 0) & 1) * kFarPlane;
    ny = (2 + ((negative >> 1) & 1)) * kFarPlane;
    nz = (4 + ((negative >> 2) & 1)) * kFarPlane;
    fx = nx ^ kFarPlane, fy = ny ^ kFarPlane, fz = nz ^ kFarPlane;
    ox = V8::set1(ray.org[0]), oy = V8::set1(ray.org[1]), oz = V8::set1(ray.org[2]);
    ix = V8::template lane<0>(inv), iy = V8::template lane<1>(inv), iz = V8::template lane<2>(inv);
    tmin = V8::set1(ray.tmin);
    // Far distances use the reciprocal times the exit padding, rounded once per ray:
    // fl(d * fl(inv * pad)) carries the same (1 + eps)^2 bound around d * inv * pad as the
    // oracle's fl(fl(d * inv) * pad), so the 2 gamma(3) margin still covers the rounding of
    // both ends (the padding was sized for the sub, reciprocal and product roundings), and
    // the node test loses a multiply from its longest dependency chain. ±inf stays ±inf.
    const __m128 finv = _mm_mul_ps(inv, _mm_set1_ps(kPad));
    fix = V8::template lane<0>(finv), fiy = V8::template lane<1>(finv), fiz = V8::template lane<2>(finv);
    if constexpr (kFused) set_fused_offsets(ray, inv, finv);
  }

  /// With FMA and no zero direction component, a slab distance is one fused operation,
  /// b inv - c, where c is org inv rounded outwards (up for near planes, down for far ones)
  /// once per ray. Against (b - org) inv that moves near distances down and far ones up by a
  /// few ulps of org inv, and rounds once instead of twice, so the padding that covers the
  /// two-rounding form covers it (never culls a box the exact ray meets). NaN (inf - inf,
  /// only for a subnormal direction component, whose reciprocal overflows) is dropped by
  /// max/min as in the other form.
  [[gnu::always_inline]] void set_fused_offsets(const Ray& ray, __m128 inv, __m128 finv) {
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

  /// Plane `offset` (a byte offset from near_plane) of `node`'s boxes.
  [[gnu::always_inline]] static const float* plane(const WideNode<N>& node, std::size_t offset) {
    return reinterpret_cast<const float*>(reinterpret_cast<const unsigned char*>(node.bounds) + offset);
  }

  /// The children of `node` the ray enters before `tmax8` (the padded upper end), and
  /// their entry distances in `entry`.
  [[gnu::always_inline]] ChildHits<Arch> test(const WideNode<N>& node, V tmax8, V& entry) const {
    V tnx, tny, tnz, tfx, tfy, tfz;
    if constexpr (kFused) {
      tnx = V8::fmsub(V8::load(plane(node, nx)), ix, cnx);
      tny = V8::fmsub(V8::load(plane(node, ny)), iy, cny);
      tnz = V8::fmsub(V8::load(plane(node, nz)), iz, cnz);
      tfx = V8::fmsub(V8::load(plane(node, fx)), fix, cfx);
      tfy = V8::fmsub(V8::load(plane(node, fy)), fiy, cfy);
      tfz = V8::fmsub(V8::load(plane(node, fz)), fiz, cfz);
    } else {
      tnx = V8::mul(V8::sub(V8::load(plane(node, nx)), ox), ix);
      tny = V8::mul(V8::sub(V8::load(plane(node, ny)), oy), iy);
      tnz = V8::mul(V8::sub(V8::load(plane(node, nz)), oz), iz);
      tfx = V8::mul(V8::sub(V8::load(plane(node, fx)), ox), fix);
      tfy = V8::mul(V8::sub(V8::load(plane(node, fy)), oy), fiy);
      tfz = V8::mul(V8::sub(V8::load(plane(node, fz)), oz), fiz);
    }
    V exit;
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
    return V8::entered(entry, exit, node.child);
  }
};

}  // namespace detail

}  // namespace volley::simd
