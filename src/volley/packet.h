// volley public API: SoA packets of K rays (K = 4, 8, 16) and their hits, and the
// conversions from and to the AoS volley::Ray / volley::Hit. Plain data, C++17, standard
// library only: the kernels (simd/), the renderer and embedders share these types. The
// library adds faster overloads of load() and store() for whole packets (declared below).
#pragma once
#include <cstdint>
#include <limits>

#include "volley/export.h"
#include "volley/ray.h"

namespace volley {

/// K rays in structure-of-arrays form, 64-byte aligned.
/// Lane i is active when bit i of `active` is set. Accel's packet queries ignore inactive
/// lanes whatever they hold; the internal kernels read all K lanes, so load() also makes
/// them inert (org = dir = 0, tmin = 0, tmax = -inf: no hit possible).
template <int K>
struct alignas(64) RayPacket {
  // (32: the library's own, for the double packets of its occlusion streams on AVX2.)
  static_assert(K == 4 || K == 8 || K == 16 || K == 32, "K rays per packet: 4, 8 or 16");
  float ox[K], oy[K], oz[K];  // 12K bytes: origins
  float dx[K], dy[K], dz[K];  // 12K bytes: directions (need not be normalized)
  float tmin[K], tmax[K];     //  8K bytes: search interval tmin <= t < tmax
  std::uint32_t active;       //  4 bytes (padded to 64): bit i = lane i is in use
};
static_assert(sizeof(RayPacket<4>) == 32 * 4 + 64, "RayPacket<4>: 128 B lanes + 64 B mask line");
static_assert(sizeof(RayPacket<8>) == 32 * 8 + 64, "RayPacket<8>: 256 B lanes + 64 B mask line");
static_assert(sizeof(RayPacket<16>) == 32 * 16 + 64, "RayPacket<16>: 512 B lanes + 64 B mask line");

/// Closest-hit answers of K rays in SoA form, 64-byte aligned, the fields of Hit per lane.
/// A lane with no hit yet has t = +inf, prim = kInvalidPrim, geom = inst = kInvalidId (see
/// reset). Only lanes that hit something nearer than the lane's current t are written.
template <int K>
struct alignas(64) HitPacket {
  static_assert(K == 4 || K == 8 || K == 16, "K rays per packet: 4, 8 or 16");
  float t[K];               // 4K bytes
  float u[K];               // 4K bytes
  float v[K];               // 4K bytes
  std::uint32_t prim[K];    // 4K bytes: primitive within its geometry
  std::uint32_t geom[K];    // 4K bytes: geometry id
  std::uint32_t inst[K];    // 4K bytes: instance id
};
static_assert(sizeof(HitPacket<4>) == 128, "HitPacket<4>: 24 B per lane, padded to 64 B");
static_assert(sizeof(HitPacket<8>) == 192, "HitPacket<8>: 24 B per lane");
static_assert(sizeof(HitPacket<16>) == 384, "HitPacket<16>: 24 B per lane");

/// Bits of the first `count` lanes (count in [0, 32]).
constexpr std::uint32_t lane_bits(int count) {
  return count >= 32 ? ~0u : (1u << count) - 1u;
}

/// Makes lane i of `packet` inert and inactive.
template <int K>
void make_inert(RayPacket<K>& packet, int i) {
  packet.ox[i] = packet.oy[i] = packet.oz[i] = 0.0f;
  packet.dx[i] = packet.dy[i] = packet.dz[i] = 0.0f;
  packet.tmin[i] = 0.0f;
  packet.tmax[i] = -std::numeric_limits<float>::infinity();
  packet.active &= ~(1u << i);
}

/// Loads rays[0 .. count) into lanes 0 .. count (0 <= count <= K); lanes count .. K are
/// made inert. All loaded lanes are active, NaN/Inf rays included (kernels never report
/// a hit for them).
template <int K>
void load(RayPacket<K>& packet, const Ray* rays, int count) {
  packet.active = 0;
  for (int i = 0; i < K; ++i) {
    if (i >= count) {
      make_inert(packet, i);
      continue;
    }
    const Ray& r = rays[i];
    packet.ox[i] = r.org[0], packet.oy[i] = r.org[1], packet.oz[i] = r.org[2];
    packet.dx[i] = r.dir[0], packet.dy[i] = r.dir[1], packet.dz[i] = r.dir[2];
    packet.tmin[i] = r.tmin;
    packet.tmax[i] = r.tmax;
    packet.active |= 1u << i;
  }
}

/// load() for packets of 16, 8 and 4, in the library: the same lanes, bit for bit, with
/// whole packets transposed by the CPU's widest vector instructions (several times fewer
/// instructions than the template's lane-by-lane copies, and whole-vector stores that the
/// queries' first loads of the packet forward from). Overload resolution picks these for
/// `load(packet, rays, count)`; `load<K>(...)` names the template.
VOLLEY_API void load(RayPacket<16>& packet, const Ray* rays, int count);
VOLLEY_API void load(RayPacket<8>& packet, const Ray* rays, int count);
VOLLEY_API void load(RayPacket<4>& packet, const Ray* rays, int count);

/// Lane i of a packet as an AoS ray.
template <int K>
Ray ray_of(const RayPacket<K>& packet, int i) {
  return Ray{{packet.ox[i], packet.oy[i], packet.oz[i]}, packet.tmin[i],
             {packet.dx[i], packet.dy[i], packet.dz[i]}, packet.tmax[i]};
}

/// Sets every lane to "no hit yet": t = +inf, u = v = 0, prim = kInvalidPrim,
/// geom = inst = kInvalidId.
template <int K>
void reset(HitPacket<K>& hits) {
  for (int i = 0; i < K; ++i) {
    hits.t[i] = std::numeric_limits<float>::infinity();
    hits.u[i] = hits.v[i] = 0.0f;
    hits.prim[i] = kInvalidPrim;
    hits.geom[i] = hits.inst[i] = kInvalidId;
  }
}

/// Lane i of a hit packet as an AoS hit.
template <int K>
Hit hit_of(const HitPacket<K>& hits, int i) {
  return Hit{hits.t[i], hits.u[i], hits.v[i], hits.prim[i], hits.geom[i], hits.inst[i]};
}

/// Writes `hit` into lane i of a hit packet.
template <int K>
void set_hit(HitPacket<K>& hits, int i, const Hit& hit) {
  hits.t[i] = hit.t, hits.u[i] = hit.u, hits.v[i] = hit.v;
  hits.prim[i] = hit.prim, hits.geom[i] = hit.geom, hits.inst[i] = hit.inst;
}

/// Stores lanes 0 .. count of `hits` to out[0 .. count).
template <int K>
void store(const HitPacket<K>& hits, Hit* out, int count) {
  for (int i = 0; i < count && i < K; ++i) out[i] = hit_of(hits, i);
}

/// store() for packets of 16, in the library: the same records, with a whole packet
/// transposed by AVX-512 where the CPU has it. Picked by overload resolution as load's.
VOLLEY_API void store(const HitPacket<16>& hits, Hit* out, int count);

}  // namespace volley
