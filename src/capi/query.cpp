// C API: closest-hit and occlusion queries for single rays, SoA packets (4, 8, 16 lanes)
// and streams, plus the ray check. The C structs have exactly the layout of the C++
// types (asserted below), so packets and streams are handed to volley::Accel in place;
// only a packet with a zero-direction lane, which the C API answers as a miss, is copied.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>

#include "capi/guard.h"
#include "capi/scene.h"
#include "volley/accel.h"
#include "volley/packet.h"
#include "volley/volley.h"

namespace volley::capi {
namespace {

// --- Layout: the C structs are the C++ types, field for field -----------------------
static_assert(sizeof(volley_ray) == sizeof(Ray) && offsetof(volley_ray, org) == offsetof(Ray, org) &&
                  offsetof(volley_ray, tmin) == offsetof(Ray, tmin) && offsetof(volley_ray, dir) == offsetof(Ray, dir) &&
                  offsetof(volley_ray, tmax) == offsetof(Ray, tmax),
              "volley_ray is volley::Ray");
static_assert(sizeof(volley_hit) == sizeof(Hit) && offsetof(volley_hit, t) == offsetof(Hit, t) &&
                  offsetof(volley_hit, u) == offsetof(Hit, u) && offsetof(volley_hit, v) == offsetof(Hit, v) &&
                  offsetof(volley_hit, prim) == offsetof(Hit, prim) && offsetof(volley_hit, geom) == offsetof(Hit, geom) &&
                  offsetof(volley_hit, inst) == offsetof(Hit, inst),
              "volley_hit is volley::Hit");
static_assert(std::is_trivially_copyable_v<Ray> && std::is_trivially_copyable_v<Hit>, "copied with memcpy");

/// The C packet types of width K.
template <int K>
struct CTypes;
template <>
struct CTypes<4> {
  using Rays = volley_ray_packet4;
  using Hits = volley_hit_packet4;
};
template <>
struct CTypes<8> {
  using Rays = volley_ray_packet8;
  using Hits = volley_hit_packet8;
};
template <>
struct CTypes<16> {
  using Rays = volley_ray_packet16;
  using Hits = volley_hit_packet16;
};

/// Compile-time proof that the C packets of width K are RayPacket<K> / HitPacket<K>.
template <int K>
constexpr bool same_layout() {
  using R = typename CTypes<K>::Rays;
  using H = typename CTypes<K>::Hits;
  return sizeof(R) == sizeof(RayPacket<K>) && alignof(R) == alignof(RayPacket<K>) &&
         offsetof(R, ox) == offsetof(RayPacket<K>, ox) && offsetof(R, oy) == offsetof(RayPacket<K>, oy) &&
         offsetof(R, oz) == offsetof(RayPacket<K>, oz) && offsetof(R, dx) == offsetof(RayPacket<K>, dx) &&
         offsetof(R, dy) == offsetof(RayPacket<K>, dy) && offsetof(R, dz) == offsetof(RayPacket<K>, dz) &&
         offsetof(R, tmin) == offsetof(RayPacket<K>, tmin) && offsetof(R, tmax) == offsetof(RayPacket<K>, tmax) &&
         offsetof(R, active) == offsetof(RayPacket<K>, active) && sizeof(H) == sizeof(HitPacket<K>) &&
         alignof(H) == alignof(HitPacket<K>) && offsetof(H, t) == offsetof(HitPacket<K>, t) &&
         offsetof(H, u) == offsetof(HitPacket<K>, u) && offsetof(H, v) == offsetof(HitPacket<K>, v) &&
         offsetof(H, prim) == offsetof(HitPacket<K>, prim) && offsetof(H, geom) == offsetof(HitPacket<K>, geom) &&
         offsetof(H, inst) == offsetof(HitPacket<K>, inst);
}
static_assert(same_layout<4>() && same_layout<8>() && same_layout<16>(), "C packets are RayPacket<K>/HitPacket<K>");

// The C objects are read and written through the C++ types. They are the same bytes
// (above); the caller's objects were made in another translation unit, behind a library
// boundary that type-based alias analysis does not cross (libvolley is not built for
// link-time optimisation). Embree's API hands its RTCRay structs to its kernels the same way.
const Ray* as_cpp(const volley_ray* r) { return reinterpret_cast<const Ray*>(r); }
Hit* as_cpp(volley_hit* h) { return reinterpret_cast<Hit*>(h); }
const Hit* as_cpp(const volley_hit* h) { return reinterpret_cast<const Hit*>(h); }
template <int K>
const RayPacket<K>& as_cpp(const typename CTypes<K>::Rays* p) {
  return *reinterpret_cast<const RayPacket<K>*>(p);
}
template <int K>
HitPacket<K>& as_cpp(typename CTypes<K>::Hits* p) {
  return *reinterpret_cast<HitPacket<K>*>(p);
}

constexpr std::size_t kPacketAlignment = 64;

/// Fails with VOLLEY_ERROR_MISALIGNED unless p is 64-byte aligned (the packet kernels
/// load and store whole aligned vectors).
void require_aligned(const void* p, const char* name) {
  if (reinterpret_cast<std::uintptr_t>(p) % kPacketAlignment != 0)
    fail(VOLLEY_ERROR_MISALIGNED, std::string(name) + " is not 64-byte aligned (address % 64 = " +
                                      std::to_string(reinterpret_cast<std::uintptr_t>(p) % kPacketAlignment) +
                                      "); use aligned_alloc(64, ...) or a variable of the packet type");
}

/// True when d is the zero vector.
bool zero_direction(const float* d) { return std::fabs(d[0]) + std::fabs(d[1]) + std::fabs(d[2]) == 0.0f; }

/// A packet's closest hits (AnyHit false, into the hit packet) or occlusion bits (into a
/// uint32_t); `masks`: the form with a mask per lane (masks must not be NULL).
template <int K, bool AnyHit, class Out>
volley_status query_packet(const char* function, const volley_scene* scene, const typename CTypes<K>::Rays* rays,
                           Out* out, bool masked = false, const std::uint32_t* masks = nullptr) {
  return guarded(function, VOLLEY_ERROR_INTERNAL, [&] {
    require_committed(scene);
    require_pointer(rays, "rays");
    if (masked) require_pointer(masks, "masks");
    require_pointer(out, AnyHit ? "occluded" : "hits");
    require_aligned(rays, "rays");
    if constexpr (AnyHit) {
      const RayPacket<K>& p = as_cpp<K>(rays);
      *out = masked ? scene->accel.occluded(p, masks) : scene->accel.occluded(p);
    } else {
      require_aligned(out, "hits");
      HitPacket<K>& hits = as_cpp<K>(out);
      const RayPacket<K>& p = as_cpp<K>(rays);
      masked ? scene->accel.intersect(p, hits, masks) : scene->accel.intersect(p, hits);
    }
  });
}

template <class Hits>
void reset_hits(Hits* hits) {
  if (!hits) return;
  constexpr int k = int(sizeof(hits->t) / sizeof(hits->t[0]));
  for (int i = 0; i < k; ++i) {
    hits->t[i] = std::numeric_limits<float>::infinity();
    hits->u[i] = hits->v[i] = 0.0f;
    hits->prim[i] = VOLLEY_INVALID_PRIM;
    hits->geom[i] = hits->inst[i] = VOLLEY_INVALID_ID;
  }
}

/// Why a ray always misses, or nullptr when it may hit.
const char* why_invalid(const volley_ray& r) {
  if (!std::isfinite(r.org[0]) || !std::isfinite(r.org[1]) || !std::isfinite(r.org[2]))
    return "its origin is not finite";
  if (!std::isfinite(r.dir[0]) || !std::isfinite(r.dir[1]) || !std::isfinite(r.dir[2]))
    return "its direction is not finite";
  if (std::isnan(r.tmin) || std::isnan(r.tmax)) return "tmin or tmax is NaN";
  if (!(r.tmin < r.tmax)) return "tmin >= tmax (an empty interval)";
  if (zero_direction(r.dir)) return "its direction is zero";
  return nullptr;
}

/// A stream query: the checks (nothing to do for count 0; the masks only when Masked), then
/// trace().
template <bool Masked, class Out, class Trace>
volley_status stream_query(const char* function, const volley_scene* scene, const volley_ray* rays,
                           const std::uint32_t* masks, std::size_t count, Out* out, const char* out_name,
                           Trace&& trace) {
  return guarded(function, VOLLEY_ERROR_INTERNAL, [&] {
    require_committed(scene);
    if (count == 0) return;
    require_pointer(rays, "rays");
    if constexpr (Masked) require_pointer(masks, "masks");
    require_pointer(out, out_name);
    trace();
  });
}

}  // namespace

/// One ray's closest hit (AnyHit false, into a volley_hit) or occlusion (into an int),
/// through the mask when one is given (a zero direction misses there, as every bad ray does:
/// volley/accel.h).
template <bool AnyHit, class Out>
volley_status query_one(const char* function, const volley_scene* scene, const volley_ray* ray,
                        const std::uint32_t* mask, Out* out) {
  return guarded(function, VOLLEY_ERROR_INTERNAL, [&] {
    require_committed(scene);
    require_pointer(ray, "ray");
    require_pointer(out, AnyHit ? "occluded" : "hit");
    volley::Ray r;
    std::memcpy(&r, ray, sizeof r);
    if constexpr (AnyHit) {
      *out = (mask ? scene->accel.occluded(r, *mask) : scene->accel.occluded(r)) ? 1 : 0;
    } else {
      const volley::Hit h = mask ? scene->accel.intersect(r, *mask) : scene->accel.intersect(r);
      std::memcpy(out, &h, sizeof h);
    }
  });
}

}  // namespace volley::capi

using namespace volley::capi;

extern "C" {

volley_status volley_intersect1(const volley_scene* scene, const volley_ray* ray, volley_hit* hit) {
  return query_one<false>("volley_intersect1", scene, ray, nullptr, hit);
}

volley_status volley_occluded1(const volley_scene* scene, const volley_ray* ray, int* occluded) {
  return query_one<true>("volley_occluded1", scene, ray, nullptr, occluded);
}

// The packet entry points of one width: C spells each width out in the names, one template
// per query answers them all.
#define VOLLEY_PACKET_ENTRIES(K)                                                                                      \
  volley_status volley_intersect##K(const volley_scene* scene, const volley_ray_packet##K* rays,                      \
                                    volley_hit_packet##K* hits) {                                                     \
    return query_packet<K, false>("volley_intersect" #K, scene, rays, hits);                                          \
  }                                                                                                                   \
  volley_status volley_occluded##K(const volley_scene* scene, const volley_ray_packet##K* rays, uint32_t* occluded) { \
    return query_packet<K, true>("volley_occluded" #K, scene, rays, occluded);                                        \
  }                                                                                                                   \
  void volley_reset_hits##K(volley_hit_packet##K* hits) { reset_hits(hits); }                                         \
  volley_status volley_intersect##K##_masked(const volley_scene* scene, const volley_ray_packet##K* rays,             \
                                             const uint32_t* masks, volley_hit_packet##K* hits) {                     \
    return query_packet<K, false>("volley_intersect" #K "_masked", scene, rays, hits, true, masks);                   \
  }                                                                                                                   \
  volley_status volley_occluded##K##_masked(const volley_scene* scene, const volley_ray_packet##K* rays,              \
                                            const uint32_t* masks, uint32_t* occluded) {                              \
    return query_packet<K, true>("volley_occluded" #K "_masked", scene, rays, occluded, true, masks);                 \
  }

VOLLEY_PACKET_ENTRIES(4)
VOLLEY_PACKET_ENTRIES(8)
VOLLEY_PACKET_ENTRIES(16)

volley_status volley_intersect_stream(const volley_scene* scene, const volley_ray* rays, size_t count,
                                      volley_hit* hits) {
  return stream_query<false>("volley_intersect_stream", scene, rays, nullptr, count, hits, "hits",
                             [&] { scene->accel.intersect(as_cpp(rays), count, as_cpp(hits)); });
}

volley_status volley_occluded_stream(const volley_scene* scene, const volley_ray* rays, size_t count,
                                     uint8_t* occluded) {
  return stream_query<false>("volley_occluded_stream", scene, rays, nullptr, count, occluded, "occluded",
                             [&] { scene->accel.occluded(as_cpp(rays), count, occluded); });
}

volley_status volley_intersect1_masked(const volley_scene* scene, const volley_ray* ray, uint32_t mask,
                                       volley_hit* hit) {
  return query_one<false>("volley_intersect1_masked", scene, ray, &mask, hit);
}

volley_status volley_occluded1_masked(const volley_scene* scene, const volley_ray* ray, uint32_t mask, int* occluded) {
  return query_one<true>("volley_occluded1_masked", scene, ray, &mask, occluded);
}

volley_status volley_intersect_stream_masked(const volley_scene* scene, const volley_ray* rays, const uint32_t* masks,
                                             size_t count, volley_hit* hits) {
  return stream_query<true>("volley_intersect_stream_masked", scene, rays, masks, count, hits, "hits",
                            [&] { scene->accel.intersect(as_cpp(rays), masks, count, as_cpp(hits)); });
}

volley_status volley_occluded_stream_masked(const volley_scene* scene, const volley_ray* rays, const uint32_t* masks,
                                            size_t count, uint8_t* occluded) {
  return stream_query<true>("volley_occluded_stream_masked", scene, rays, masks, count, occluded, "occluded",
                            [&] { scene->accel.occluded(as_cpp(rays), masks, count, occluded); });
}

volley_status volley_geometric_normal(const volley_scene* scene, const volley_hit* hit, float normal[3]) {
  return guarded("volley_geometric_normal", VOLLEY_ERROR_INTERNAL, [&] {
    require_committed(scene);
    require_pointer(hit, "hit");
    require_pointer(normal, "normal");
    const std::array<float, 3> n = scene->accel.geometric_normal(*reinterpret_cast<const volley::Hit*>(hit));
    normal[0] = n[0], normal[1] = n[1], normal[2] = n[2];
  });
}

volley_status volley_geometric_normals(const volley_scene* scene, const volley_hit* hits, size_t count,
                                       float* normals) {
  return guarded("volley_geometric_normals", VOLLEY_ERROR_INTERNAL, [&] {
    require_committed(scene);
    if (count == 0) return;
    require_pointer(hits, "hits");
    require_pointer(normals, "normals");
    scene->accel.geometric_normals(as_cpp(hits), count, normals);
  });
}

volley_status volley_validate_rays(const volley_ray* rays, size_t count, size_t* first_invalid) {
  for (size_t i = 0; i < count; ++i) {
    if (rays == nullptr) return set_error(VOLLEY_ERROR_INVALID_ARGUMENT, "volley_validate_rays", "rays is NULL");
    if (const char* why = why_invalid(rays[i])) {
      if (first_invalid) *first_invalid = i;
      char message[128];
      std::snprintf(message, sizeof message, "ray %zu always misses: %s", i, why);
      return set_error(VOLLEY_ERROR_INVALID_RAY, "volley_validate_rays", message);
    }
  }
  return VOLLEY_OK;
}

}  // extern "C"
