// The frustum walk of a coherent packet (one octant; one origin, or origins that differ
// where the query asks, PacketWalk::spread_frustum): one interval slab test
// per node for the whole packet, the oracle's per-lane test at leaves, whose triangles go
// to the query (queries.h).
#pragma once
#include <bit>
#include <cstdint>
#include <limits>

#include "simd/wide/node_lanes.h"
#include "simd/wide/packet_lanes.h"
#include "simd/wide/queries.h"
#include "simd/wide/stack.h"

namespace volley::simd {

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
// exactly, against each lane's own tfar) to pick the lanes handed to the block kernels, and
// every subtree popped is tested per lane again, against tfar as the hits since its push
// have left it: a subtree no lane enters is skipped, one that few lanes enter
// (kPacketSwitchLanes or fewer) goes to the single-ray walk lane by lane, as in the per-lane
// walk. Without that second test the frustum opened twice the leaves on the kitchen's
// primary rays (perf/traversal.md).
template <class Arch, TriangleTest Test, bool Robust>
template <class Query, class Leaves>
std::uint32_t WideKernels<Arch, Test, Robust>::trace_frustum(const WideView<Leaves>& bvh, PreparedPacket<K>& prep,
                                                             const detail::PacketSetup<K>& setup, Query& query) {
  using V8 = detail::Lanes8<Arch>;
  using B = detail::FloatB<Arch>;
  constexpr int C = K / L;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const RayPacket<K>& rays = prep.rays;
  const std::uint32_t valid = setup.valid;
  const float pad1 = Robust ? core::kSlabExitPad : 1.0f;
  const B pinf(kInf), ninf(-kInf);

  // Per-lane rays (for the leaf box tests) and the packet's intervals. No lane has a zero
  // direction component here, so the lanes' tests take the fused form (kFusedLanes).
  detail::PacketLanes<Arch, K> lanes(rays, setup, query);
  constexpr bool kFused = detail::kFusedLanes<Arch>;
  using FusedLanes = typename detail::PacketLanes<Arch, K>::Fused;
  [[maybe_unused]] const FusedLanes fused = lanes.template fuse_if<kFused>(pad1, Robust);
  B olo[3] = {pinf, pinf, pinf}, ohi[3] = {ninf, ninf, ninf}, ilo[3] = {pinf, pinf, pinf}, ihi[3] = {ninf, ninf, ninf};
  B tmin_lo = pinf;
  for (int c = 0; c < C; ++c) {
    const auto ok = detail::mask_from_bits<Arch>((valid >> (c * L)) & kChunkBits);
    const B* org[3] = {&lanes.ox[c], &lanes.oy[c], &lanes.oz[c]};
    const B* inv[3] = {&lanes.ix[c], &lanes.iy[c], &lanes.iz[c]};
    for (int a = 0; a < 3; ++a) {
      olo[a] = xsimd::min(olo[a], xsimd::select(ok, *org[a], pinf));
      ohi[a] = xsimd::max(ohi[a], xsimd::select(ok, *org[a], ninf));
      ilo[a] = xsimd::min(ilo[a], xsimd::select(ok, *inv[a], pinf));
      ihi[a] = xsimd::max(ihi[a], xsimd::select(ok, *inv[a], ninf));
    }
    tmin_lo = xsimd::min(tmin_lo, xsimd::select(ok, lanes.tmin[c], pinf));
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
  float far_hi = lanes.far_max();
  const B padb(pad1);
  // A lane's own test of child j of `node` (leaves, popped subtrees).
  const auto lane_slabs = [&](const WideNode<N>& node, int j, int c, B& e, B& x) {
    if constexpr (kFused)
      lanes.fused_slabs(fused, node, j, np, c, lanes.tfar[c] * padb, e, x);
    else
      lanes.slabs(node, j, np, c, padb, e, x);
  };

  detail::FrustumItem<Arch> stack[detail::kWideStack];
  int size = 0;
  std::uint32_t finished = 0;
  std::uint32_t cur = bvh.root;
  std::uint32_t cur_lanes = valid;
  std::uint32_t cur_parent = wide_ref::kEmptyRef, cur_slot = 0;
  for (;;) {
    // The lanes that enter `cur` now (each against its own tfar, which hits since the push
    // may have lowered): none, skip it; few, the single-ray walk takes them from here.
    std::uint32_t live = cur_lanes & ~finished;
    if (detail::lanes_on_pop<Query>() && live != 0 && cur_parent != wide_ref::kEmptyRef) {
      const WideNode<N>& parent = wide_ref::node_at(bvh.nodes, cur_parent);
      std::uint32_t now = 0;
      for (int c = 0; c < C; ++c) {
        B e, x;
        lane_slabs(parent, static_cast<int>(cur_slot), c, e, x);
        now |= detail::bits_from_mask<Arch>(e <= x) << (c * L);
      }
      live &= now;
    }
    if (live == 0) {
      // Skipped: no lane reaches it any more.
    } else if (detail::lanes_on_pop<Query>() && std::popcount(live) <= kPacketSwitchLanes) {
      alignas(64) float far_lanes[K];
      for (int c = 0; c < C; ++c) lanes.tfar[c].store_aligned(far_lanes + c * L);
      for (std::uint32_t b = live; b != 0; b &= b - 1) {
        const int i = std::countr_zero(b);
        if (query.single(bvh, prep, setup, cur, i, far_lanes[i])) finished |= 1u << i;
      }
      for (int c = 0; c < C; ++c) lanes.tfar[c] = B::load_aligned(far_lanes + c * L);
      if (finished == valid) return finished;
      far_hi = lanes.far_max();
    } else if (!(cur & wide_ref::kLeafBit)) {
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
          std::uint32_t child_lanes = valid & ~finished;
          if (child & wide_ref::kLeafBit) {
            // A leaf: the oracle's box test per lane, against each lane's own tfar.
            child_lanes = 0;
            for (int c = 0; c < C; ++c) {
              B e, x;
              lane_slabs(node, j, c, e, x);
              child_lanes |= detail::bits_from_mask<Arch>(e <= x) << (c * L);
            }
            child_lanes &= valid & ~finished;
            if (child_lanes == 0) continue;
            wide_ref::request_leaf(bvh.blocks, child);
          } else {
            wide_ref::request_node(bvh.nodes, child);
          }
          int k = size++;
          for (; k > base && stack[k - 1].entry < dist[j]; --k) stack[k] = stack[k - 1];
          stack[k] = {child, dist[j], child_lanes, cur, static_cast<std::uint32_t>(j)};
        }
      }
    } else {
      // Leaf: its blocks to the query, for the lanes that enter its box.
      const std::uint32_t count = wide_ref::leaf_count(cur);
      if (count != 0) {
        const detail::LanesStep step = query.leaf(prep, bvh.blocks + wide_ref::leaf_first(cur), count, live, lanes.tfar);
        finished |= step.finished;
        if (step.finished != 0 && finished == valid) return finished;
        if (step.narrowed) far_hi = lanes.far_max();
      }
    }
    // Pop the next subtree some lane may still reach before its tfar.
    for (;;) {
      if (size == 0) return finished;
      --size;
      if (stack[size].entry <= far_hi * pad1) break;
    }
    cur = stack[size].ref;
    cur_lanes = stack[size].lanes;
    cur_parent = stack[size].parent;
    cur_slot = stack[size].slot;
  }
}

}  // namespace volley::simd
