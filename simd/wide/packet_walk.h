// The per-lane packet walk: each node tested per lane, subtrees with few active lanes
// handed to the single-ray walk.
#pragma once
#include <bit>
#include <cstdint>
#include <limits>

#include "simd/wide/node_lanes.h"
#include "simd/wide/stack.h"

namespace volley::simd {

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

}  // namespace volley::simd
