// Accel's stream queries: runs of 16 rays traced as one packet where that pays (see
// volley/accel.h), the rest one by one.
#include <algorithm>
#include <cmath>
#include <vector>

#include "accel/accel_impl.h"

namespace volley {
namespace {

/// True when the directions of rays[0 .. n) share one octant (sign bits; -0 negative):
/// the stream policy's test for tracing them as one packet below AVX-512.
bool same_octant(const Ray* rays, std::size_t n) {
  std::uint32_t all = 7, any = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t oct = (std::signbit(rays[i].dir[0]) ? 1u : 0u) | (std::signbit(rays[i].dir[1]) ? 2u : 0u) |
                              (std::signbit(rays[i].dir[2]) ? 4u : 0u);
    all &= oct;
    any |= oct;
  }
  return all == any;
}

/// Whether rays[0 .. n) go as one packet: 16 of them, a scene whose streams go as packets
/// (Accel::Impl::stream_packets), and one octant, or on AVX-512 any octants where the walk
/// needs no order (occlusion, every hit): closest-hit runs of mixed octants (diffuse rays)
/// went faster ray by ray there too, occlusion runs straddling an axis plane (shadow rays)
/// as packets (perf/rays.md). Scenes with instances: any octants, since the packet shares
/// the top level's walk (perf/instances.md).
template <class Impl>
bool as_packet(const Impl& impl, const Ray* rays, std::size_t n, bool ordered) {
  return n == 16 && impl.stream_packets &&
         (impl.has_instances || (impl.isa == Isa::avx512 && !ordered) || same_octant(rays, n));
}

/// The rays of a stream left to the stream walk, copied together (thread_local, reused).
struct Leftover {
  std::vector<std::uint32_t> index;  ///< their places in the caller's stream
  std::vector<Ray> rays;
  std::vector<Hit> hits;
  std::vector<std::uint8_t> blocked;
};

Leftover& leftover() {
  static thread_local Leftover left;
  return left;
}

}  // namespace

bool Accel::Impl::stream_walk_for(std::size_t rays_left) const {
  return wide_only != nullptr && rays_left >= kStreamWalkRays;
}

void Accel::Impl::intersect(const Ray* rays, const std::uint32_t* masks, std::size_t count, Hit* hits) const {
  Leftover& left = leftover();
  left.index.clear();
  for (std::size_t first = 0; first < count; first += 16) {
    const std::size_t n = std::min<std::size_t>(16, count - first);
    const std::uint32_t* m = masks ? masks + first : nullptr;
    if (as_packet(*this, rays + first, n, true)) {
      RayPacket<16> p;
      volley::load(p, rays + first, 16);
      HitPacket<16> h;
      reset(h);
      intersect(p, h, m);
      store(h, hits + first, 16);
    } else {
      for (std::size_t i = 0; i < n; ++i) left.index.push_back(static_cast<std::uint32_t>(first + i));
    }
  }
  if (!stream_walk_for(left.index.size())) {
    for (std::uint32_t i : left.index) hits[i] = intersect(rays[i], masks ? masks[i] : kMaskAll);
    return;
  }
  // The stream walk, for the rays whose mask meets the scene's (the others miss).
  left.rays.clear();
  std::size_t kept = 0;
  for (std::uint32_t i : left.index) {
    hits[i] = Hit{};
    if (masks && !(masks[i] & simple_mask)) continue;
    left.index[kept++] = i;
    left.rays.push_back(rays[i]);
  }
  left.hits.assign(kept, Hit{});
  wide_only->intersect(left.rays.data(), kept, left.hits.data());
  for (std::size_t k = 0; k < kept; ++k) {
    Hit& h = hits[left.index[k]];
    h = left.hits[k];
    attribute(h.prim, h.geom);
  }
}

void Accel::Impl::occluded(const Ray* rays, const std::uint32_t* masks, std::size_t count, std::uint8_t* blocked) const {
  Leftover& left = leftover();
  left.index.clear();
  for (std::size_t first = 0; first < count; first += 16) {
    const std::size_t n = std::min<std::size_t>(16, count - first);
    const std::uint32_t* m = masks ? masks + first : nullptr;
    if (as_packet(*this, rays + first, n, false)) {
      RayPacket<16> p;
      volley::load(p, rays + first, 16);
      const std::uint32_t mask = occluded(p, m);
      for (std::size_t i = 0; i < 16; ++i) blocked[first + i] = static_cast<std::uint8_t>((mask >> i) & 1u);
    } else {
      for (std::size_t i = 0; i < n; ++i) left.index.push_back(static_cast<std::uint32_t>(first + i));
    }
  }
  if (!stream_walk_for(left.index.size())) {
    for (std::uint32_t i : left.index) blocked[i] = occluded(rays[i], masks ? masks[i] : kMaskAll) ? 1 : 0;
    return;
  }
  left.rays.clear();
  std::size_t kept = 0;
  for (std::uint32_t i : left.index) {
    blocked[i] = 0;
    if (masks && !(masks[i] & simple_mask)) continue;
    left.index[kept++] = i;
    left.rays.push_back(rays[i]);
  }
  left.blocked.resize(kept);
  wide_only->occluded(left.rays.data(), kept, left.blocked.data());
  for (std::size_t k = 0; k < kept; ++k) blocked[left.index[k]] = left.blocked[k];
}

void Accel::Impl::all_hits(const Ray* rays, std::size_t count, std::vector<Hit>* out) const {
  for (std::size_t first = 0; first < count; first += 16) {
    const std::size_t n = std::min<std::size_t>(16, count - first);
    std::vector<Hit>* lanes = out + first;
    if (has_instances || !as_packet(*this, rays + first, n, false)) {
      for (std::size_t i = 0; i < n; ++i) all_hits(rays[first + i], kMaskAll, lanes[i]);
      continue;
    }
    RayPacket<16> p;
    volley::load(p, rays + first, 16);
    std::size_t before[16];
    for (int i = 0; i < 16; ++i) before[i] = lanes[i].size();
    for (const Layer& l : layers) {
      for (int i = 0; i < 16; ++i) before[i] = lanes[i].size();
      if (l.triangle_engine) l.triangle_engine->all_hits(p, lanes);
      if (quality == BuildQuality::high)
        for (int i = 0; i < 16; ++i) drop_repeated_hits(lanes[i], before[i]);
      if (l.polygon_engine) l.polygon_engine->all_hits(p, lanes);
      for (int i = 0; i < 16; ++i)
        for (std::size_t k = before[i]; k < lanes[i].size(); ++k) attribute(lanes[i][k].prim, lanes[i][k].geom);
    }
  }
}

}  // namespace volley
