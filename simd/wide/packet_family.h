// The interval family of a packet whose valid lanes share one octant and have no zero
// direction component: every ray whose origin lies in the box of the lanes' origins and
// whose reciprocal direction lies in the box of theirs. One 8-wide test of a node's children
// bounds what all lanes do there: the frustum walk's node test (`maybe`) and the any-hit
// packet walk's shortcut past its per-lane tests (`all`).
#pragma once
#include <cstdint>
#include <limits>

#include "simd/wide/node_lanes.h"
#include "simd/wide/packet_lanes.h"
#include "simd/wide/stack.h"

namespace volley::simd::detail {

// The interval form of Reshetov et al., "Multi-level ray tracing algorithm" (SIGGRAPH
// 2005; Embree's coherent mode).
//
// `maybe` is conservative by monotonicity, with no padding of its own: for a lane, the
// oracle's slab distance fl(fl(b - o) * inv) is monotone in o and, for fixed sign of b - o,
// in inv (rounding to nearest is monotone), so over the family's box of (o, inv) its
// extremes are at corners: the near distance is at least min(fl(d * inv_min), fl(d *
// inv_max)) with d = fl(b - o) for the origin bound that makes d smallest along the ray
// (inv > 0: o_max; inv < 0: o_min), and the far distance at most the max of the products of
// the other bound. Every valid lane has a finite, nonzero direction (screen()), but a
// subnormal component has an infinite reciprocal, so a product 0 * inf (an origin bound on
// the plane) can be NaN: min / max then take the other corner's product (0 for a zero
// difference), or drop the axis at the entry / exit combination (tmin and far are never
// NaN); the bounds stay NaN-free (tests/accel: subnormal directions, against the oracle).
// Inert children give ±inf products. A child passes when max(near bounds, min tmin) <=
// min(far bounds, far) * kSlabExitPad, which holds whenever some lane's own padded test
// would.
//
// `all` is the same test from the other corners (the largest near distance, the smallest far
// one, the largest tmin, the smallest upper end, no padding): a child passes where every ray
// of the family enters it. Its rounding is not bounded, so a lane it counts in may miss the
// child by an ulp: a walk that takes its word visits such a subtree for nothing, which costs
// time, never an answer, as long as the walk's answer does not depend on which subtrees it
// visits (any hit).
template <class Arch, int K>
struct PacketFamily {
  using V8 = Lanes8<Arch>;
  using V = typename V8::V;
  static constexpr int L = kLanes<Arch>;
  static constexpr int C = K / L;

  int np[3];  // near plane of axis a: node.bounds[np[a]], far: np[a] ^ 1
  V o_near[3], o_far[3], i_lo[3], i_hi[3];
  V tmin_lo, tmin_hi, far_lo, pad;

  PacketFamily() = default;
  /// The family of the `valid` lanes of `lanes` (at least one); pad1 is the exit padding.
  PacketFamily(const PacketLanes<Arch, K>& lanes, std::uint32_t valid, float pad1) {
    using B = FloatB<Arch>;
    constexpr float kInf = std::numeric_limits<float>::infinity();
    const B pinf(kInf), ninf(-kInf);
    B olo[3] = {pinf, pinf, pinf}, ohi[3] = {ninf, ninf, ninf}, ilo[3] = {pinf, pinf, pinf}, ihi[3] = {ninf, ninf, ninf};
    B tlo = pinf, thi = ninf, flo = pinf;
    for (int c = 0; c < C; ++c) {
      const auto ok = mask_from_bits<Arch>((valid >> (c * L)) & ((1u << L) - 1u));
      const B* org[3] = {&lanes.ox[c], &lanes.oy[c], &lanes.oz[c]};
      const B* inv[3] = {&lanes.ix[c], &lanes.iy[c], &lanes.iz[c]};
      for (int a = 0; a < 3; ++a) {
        olo[a] = xsimd::min(olo[a], xsimd::select(ok, *org[a], pinf));
        ohi[a] = xsimd::max(ohi[a], xsimd::select(ok, *org[a], ninf));
        ilo[a] = xsimd::min(ilo[a], xsimd::select(ok, *inv[a], pinf));
        ihi[a] = xsimd::max(ihi[a], xsimd::select(ok, *inv[a], ninf));
      }
      tlo = xsimd::min(tlo, xsimd::select(ok, lanes.tmin[c], pinf));
      thi = xsimd::max(thi, xsimd::select(ok, lanes.tmin[c], ninf));
      flo = xsimd::min(flo, xsimd::select(ok, lanes.tfar[c], pinf));
    }
    for (int a = 0; a < 3; ++a) {
      const float lo = reduce_min<Arch>(olo[a]), hi = reduce_max<Arch>(ohi[a]);
      const float il = reduce_min<Arch>(ilo[a]), ih = reduce_max<Arch>(ihi[a]);
      const bool neg = ih < 0.0f;
      np[a] = 2 * a + (neg ? 1 : 0);
      // The near planes' differences from the origin bound that makes them smallest along
      // the ray (inv > 0: o_max, inv < 0: o_min), the far planes' from the other.
      o_near[a] = V8::set1(neg ? lo : hi);
      o_far[a] = V8::set1(neg ? hi : lo);
      i_lo[a] = V8::set1(il);
      i_hi[a] = V8::set1(ih);
    }
    tmin_lo = V8::set1(reduce_min<Arch>(tlo));
    tmin_hi = V8::set1(reduce_max<Arch>(thi));
    far_lo = V8::set1(reduce_min<Arch>(flo));
    pad = V8::set1(pad1);
  }

  /// The children of `node` that some ray of the family may enter before `far_hi` (at
  /// least every lane's upper end), as bits; `entry` their lower bounds of the entry
  /// distance.
  [[gnu::always_inline]] std::uint32_t maybe(const WideNode<kWideN>& node, V far_hi, V& entry) const {
    V tn[3], tf[3];
    for (int a = 0; a < 3; ++a) {
      const V dn = V8::sub(V8::load(node.bounds[np[a]]), o_near[a]);
      const V df = V8::sub(V8::load(node.bounds[np[a] ^ 1]), o_far[a]);
      tn[a] = V8::min(V8::mul(dn, i_lo[a]), V8::mul(dn, i_hi[a]));
      tf[a] = V8::max(V8::mul(df, i_lo[a]), V8::mul(df, i_hi[a]));
    }
    entry = V8::max(V8::max(tn[0], tn[1]), V8::max(tn[2], tmin_lo));
    const V exit = V8::mul(V8::min(V8::min(tf[0], tf[1]), V8::min(tf[2], far_hi)), pad);
    return V8::le(entry, exit);
  }

  /// The children of `node` that every ray of the family enters (see above: not bounded
  /// against rounding), as bits.
  [[gnu::always_inline]] std::uint32_t all(const WideNode<kWideN>& node) const {
    V tn[3], tf[3];
    for (int a = 0; a < 3; ++a) {
      const V dn = V8::sub(V8::load(node.bounds[np[a]]), o_far[a]);
      const V df = V8::sub(V8::load(node.bounds[np[a] ^ 1]), o_near[a]);
      tn[a] = V8::max(V8::mul(dn, i_lo[a]), V8::mul(dn, i_hi[a]));
      tf[a] = V8::min(V8::mul(df, i_lo[a]), V8::mul(df, i_hi[a]));
    }
    const V entry = V8::max(V8::max(tn[0], tn[1]), V8::max(tn[2], tmin_hi));
    const V exit = V8::min(V8::min(tf[0], tf[1]), V8::min(tf[2], far_lo));
    return V8::le(entry, exit);
  }
};

}  // namespace volley::simd::detail
