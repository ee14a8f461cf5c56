#include "accel/engine.h"

namespace volley::accel {

void Engine::intersect(const RayPacket<16>& rays, HitPacket<16>& hits) const {
  for (std::uint32_t b = rays.active & lane_bits(16); b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    Hit h{hits.t[i], hits.u[i], hits.v[i], hits.prim[i]};
    if (intersect(lane_ray(rays, i), h)) hits.t[i] = h.t, hits.u[i] = h.u, hits.v[i] = h.v, hits.prim[i] = h.prim;
  }
}

void Engine::all_hits(const RayPacket<16>& rays, std::vector<Hit>* out) const {
  for (std::uint32_t b = rays.active & lane_bits(16); b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    all_hits(lane_ray(rays, i), out[i]);
  }
}

std::uint32_t Engine::occluded(const RayPacket<16>& rays, std::uint32_t lanes) const {
  std::uint32_t blocked = 0;
  for (std::uint32_t b = lanes & rays.active & lane_bits(16); b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    if (occluded(lane_ray(rays, i))) blocked |= 1u << i;
  }
  return blocked;
}

}  // namespace volley::accel
