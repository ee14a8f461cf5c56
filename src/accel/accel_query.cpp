// Accel::Impl's packet queries: the lanes through the layers their masks select, triangles
// then polygons in each, the answers attributed to their geometry, then the instances. A
// full packet without masks takes the scene's own form (Queries::intersect_full).
#include <cmath>
#include <cstring>

#include "accel/accel_impl.h"

namespace volley {
namespace {

/// Whether the engines may take the caller's packet as it is: 16 lanes, all active.
template <int K>
bool all_lanes_active(const RayPacket<K>& p) {
  return K == 16 && (p.active & lane_bits(K)) == lane_bits(K);
}

}  // namespace

template <int K>
void Accel::Impl::intersect(const RayPacket<K>& rays, HitPacket<K>& hits, const std::uint32_t* masks) const {
  // The lanes an engine writes (a nearer hit: t's bits change) get their geometry and
  // index; the others keep what the caller passed. Inactive lanes are not read.
  std::uint32_t before[K];
  if (!masks && all_lanes_active(rays) && built.one_geometry) {
    // Every lane ours and one geometry (prim needs no change): branch-free over all lanes.
    std::memcpy(before, hits.t, sizeof(before));
    trace_packet(rays, hits, nullptr);
    for (int i = 0; i < K; ++i) {
      std::uint32_t now;
      std::memcpy(&now, &hits.t[i], 4);
      const bool written = now != before[i];
      hits.geom[i] = written ? 0u : hits.geom[i];
      hits.inst[i] = written ? kInvalidId : hits.inst[i];
    }
    return;
  }
  const std::uint32_t active = rays.active & lane_bits(K);
  for (std::uint32_t b = active; b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    std::memcpy(&before[i], &hits.t[i], 4);
  }
  trace_packet(rays, hits, masks);
  for (std::uint32_t b = active; b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    if (std::memcmp(&before[i], &hits.t[i], 4) == 0) continue;
    attribute(hits.prim[i], hits.geom[i]);
    hits.inst[i] = kInvalidId;
  }
  if (!built.has_instances) return;
  if constexpr (K == 16) {
    if (built.isa != Isa::scalar) {  // the instances' top level walked by the packet
      RayPacket<16> p;
      accel::widen(rays, active, p);
      intersect_instances(p, masks, hits);
      return;
    }
  }
  // Instances lane by lane, bounded by what the lane has found.
  for (std::uint32_t b = active; b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    Hit hit = hit_of(hits, i);
    if (intersect_instances(accel::lane_ray(rays, i), masks ? masks[i] : kMaskAll, hit)) set_hit(hits, i, hit);
  }
}

template <int K>
void Accel::Impl::trace_packet(const RayPacket<K>& rays, HitPacket<K>& hits, const std::uint32_t* masks) const {
  const std::uint32_t active = rays.active & lane_bits(K);
  if constexpr (K == 16) {
    if (!masks && all_lanes_active(rays)) return built.queries.intersect_full(*this, rays, hits);
  }
  HitPacket<16> h;
  reset(h);
  for (std::uint32_t b = active; b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    set_hit(h, i, hit_of(hits, i));
  }
  RayPacket<16> p;
  for (const Layer& l : built.layers) {
    const std::uint32_t lanes = lanes_of(active, masks, l.mask);
    if (lanes == 0) continue;
    accel::widen(rays, lanes, p);
    for (const auto& engine : l.engines) engine->intersect(p, h);
  }
  for (std::uint32_t b = active; b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    set_hit(hits, i, hit_of(h, i));
  }
}

template <int K>
std::uint32_t Accel::Impl::occluded_by_layers(const RayPacket<K>& rays, const std::uint32_t* masks) const {
  if constexpr (K == 16)
    if (!masks && all_lanes_active(rays)) return built.queries.occluded_full(*this, rays);
  const std::uint32_t active = rays.active & lane_bits(K);
  std::uint32_t blocked = 0;
  RayPacket<16> p;
  for (const Layer& l : built.layers) {
    const std::uint32_t lanes = lanes_of(active, masks, l.mask) & ~blocked;
    if (lanes == 0) continue;
    accel::widen(rays, lanes, p);
    for (const auto& engine : l.engines)
      if ((lanes & ~blocked) != 0) blocked |= engine->occluded(p, lanes & ~blocked) & lanes;
  }
  return blocked;
}

template <int K>
std::uint32_t Accel::Impl::occluded(const RayPacket<K>& rays, const std::uint32_t* masks) const {
  const std::uint32_t active = rays.active & lane_bits(K);
  std::uint32_t blocked = occluded_by_layers(rays, masks);
  if (!built.has_instances || (active & ~blocked) == 0) return blocked;
  if constexpr (K == 16) {
    if (built.isa != Isa::scalar) {  // the instances' top level walked by the packet
      RayPacket<16> p;
      accel::widen(rays, active & ~blocked, p);
      return blocked | occluded_instances(p, masks);
    }
  }
  // Lane by lane (the scalar ISA, or a packet of 4 or 8).
  for (std::uint32_t b = active & ~blocked; b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    if (occluded_instances(accel::lane_ray(rays, i), masks ? masks[i] : kMaskAll)) blocked |= 1u << i;
  }
  return blocked;
}

template void Accel::Impl::intersect<4>(const RayPacket<4>&, HitPacket<4>&, const std::uint32_t*) const;
template void Accel::Impl::intersect<8>(const RayPacket<8>&, HitPacket<8>&, const std::uint32_t*) const;
template void Accel::Impl::intersect<16>(const RayPacket<16>&, HitPacket<16>&, const std::uint32_t*) const;
template std::uint32_t Accel::Impl::occluded<4>(const RayPacket<4>&, const std::uint32_t*) const;
template std::uint32_t Accel::Impl::occluded<8>(const RayPacket<8>&, const std::uint32_t*) const;
template std::uint32_t Accel::Impl::occluded<16>(const RayPacket<16>&, const std::uint32_t*) const;

}  // namespace volley
