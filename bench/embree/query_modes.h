// The query modes volley_vs_embree times: each the same query through Embree's call and
// volley's matching one (single rays, 16-ray packets, streams; closest hit and
// occlusion), on AoS rays in, AoS answers out, as `volley trace` does.
#pragma once
#include <embree3/rtcore.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "embree_scene.h"
#include "volley/accel.h"
#include "volley/packet.h"

namespace volley::bench {

/// Rays per stream call, as `volley trace --mode stream` chunks them.
inline constexpr std::size_t kStreamChunk = 1024;
/// Embree's tfar of an occluded ray.
inline constexpr float kNegInf = -std::numeric_limits<float>::infinity();

/// Calls trace(packet, b, n) for each run rays[b .. b + n) of up to 16 rays as a volley
/// packet (lanes past the end inactive), b = 0, 16, 32, ...
template <class Trace>
void for_each_packet16(const std::vector<Ray>& rays, Trace&& trace) {
  RayPacket<16> packet;
  for (std::size_t b = 0; b < rays.size(); b += 16) {
    const int n = int(std::min<std::size_t>(16, rays.size() - b));
    load(packet, rays.data() + b, n);
    trace(packet, b, n);
  }
}

/// Calls trace(rays, b, n) for each run rays[b .. b + n) of up to kStreamChunk rays as
/// Embree's AoS rays.
template <class Trace>
void for_each_embree_chunk(const std::vector<Ray>& rays, Trace&& trace) {
  std::vector<RTCRayHit> e(kStreamChunk);
  for (std::size_t b = 0; b < rays.size(); b += kStreamChunk) {
    const std::size_t n = std::min(kStreamChunk, rays.size() - b);
    for (std::size_t i = 0; i < n; ++i) to_embree(rays[b + i], e[i]);
    trace(e.data(), b, n);
  }
}

/// The answers of one pass: closest hits, one byte per ray for occlusion, or hits per ray
/// (the counting modes, count_modes.h).
struct Answers {
  std::vector<Hit> hits;
  std::vector<std::uint8_t> blocked;
  std::vector<std::uint32_t> counts;
};

/// One mode: the same query through each engine's matching call.
struct Mode {
  std::string name;
  std::string embree_call;
  std::string volley_call;
  bool occlusion = false;
  std::function<void(const std::vector<Ray>&, Answers&)> embree;
  std::function<void(const std::vector<Ray>&, Answers&)> volley;
  bool counting = false;  ///< answers are counts per ray
};

inline RTCIntersectContext make_context(bool coherent) {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = coherent ? RTC_INTERSECT_CONTEXT_FLAG_COHERENT : RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT;
  return context;
}

inline std::vector<Mode> all_modes(const EmbreeScene& embree, const Accel& accel, bool coherent) {
  const RTCScene scene = embree.scene();
  std::vector<Mode> modes;

  modes.push_back({"single", "rtcIntersect1", "intersect(Ray)", false,
                   [scene, coherent](const std::vector<Ray>& rays, Answers& out) {
                     RTCIntersectContext context = make_context(coherent);
                     for (std::size_t i = 0; i < rays.size(); ++i) {
                       RTCRayHit e;
                       to_embree(rays[i], e);
                       rtcIntersect1(scene, &context, &e);
                       out.hits[i] = from_embree(e);
                     }
                   },
                   [&accel](const std::vector<Ray>& rays, Answers& out) {
                     for (std::size_t i = 0; i < rays.size(); ++i) out.hits[i] = accel.intersect(rays[i]);
                   }});

  modes.push_back({"packet", "rtcIntersect16", "intersect(RayPacket<16>)", false,
                   [scene, coherent](const std::vector<Ray>& rays, Answers& out) {
                     RTCIntersectContext context = make_context(coherent);
                     for_each_embree16(rays, [&](RTCRayHit16& e, int* valid, std::size_t b, int n) {
                       rtcIntersect16(valid, scene, &context, &e);
                       for (int i = 0; i < n; ++i) out.hits[b + i] = from_embree(e, i);
                     });
                   },
                   [&accel](const std::vector<Ray>& rays, Answers& out) {
                     HitPacket<16> hits;
                     for_each_packet16(rays, [&](const RayPacket<16>& packet, std::size_t b, int n) {
                       reset(hits);
                       accel.intersect(packet, hits);
                       store(hits, out.hits.data() + b, n);
                     });
                   }});

  modes.push_back({"stream", "rtcIntersect1M", "intersect(Ray*, n, Hit*)", false,
                   [scene, coherent](const std::vector<Ray>& rays, Answers& out) {
                     RTCIntersectContext context = make_context(coherent);
                     for_each_embree_chunk(rays, [&](RTCRayHit* e, std::size_t b, std::size_t n) {
                       rtcIntersect1M(scene, &context, e, unsigned(n), sizeof(RTCRayHit));
                       for (std::size_t i = 0; i < n; ++i) out.hits[b + i] = from_embree(e[i]);
                     });
                   },
                   [&accel](const std::vector<Ray>& rays, Answers& out) {
                     for (std::size_t b = 0; b < rays.size(); b += kStreamChunk)
                       accel.intersect(rays.data() + b, std::min(kStreamChunk, rays.size() - b), out.hits.data() + b, 1);
                   }});

  modes.push_back({"occluded1", "rtcOccluded1", "occluded(Ray)", true,
                   [scene, coherent](const std::vector<Ray>& rays, Answers& out) {
                     RTCIntersectContext context = make_context(coherent);
                     for (std::size_t i = 0; i < rays.size(); ++i) {
                       RTCRayHit e;
                       to_embree(rays[i], e);
                       rtcOccluded1(scene, &context, &e.ray);
                       out.blocked[i] = e.ray.tfar == kNegInf ? 1 : 0;
                     }
                   },
                   [&accel](const std::vector<Ray>& rays, Answers& out) {
                     for (std::size_t i = 0; i < rays.size(); ++i) out.blocked[i] = accel.occluded(rays[i]) ? 1 : 0;
                   }});

  modes.push_back({"occluded16", "rtcOccluded16", "occluded(RayPacket<16>)", true,
                   [scene, coherent](const std::vector<Ray>& rays, Answers& out) {
                     RTCIntersectContext context = make_context(coherent);
                     for_each_embree16(rays, [&](RTCRayHit16& e, int* valid, std::size_t b, int n) {
                       rtcOccluded16(valid, scene, &context, &e.ray);
                       for (int i = 0; i < n; ++i) out.blocked[b + i] = e.ray.tfar[i] == kNegInf ? 1 : 0;
                     });
                   },
                   [&accel](const std::vector<Ray>& rays, Answers& out) {
                     for_each_packet16(rays, [&](const RayPacket<16>& packet, std::size_t b, int n) {
                       const std::uint32_t mask = accel.occluded(packet);
                       for (int i = 0; i < n; ++i) out.blocked[b + i] = std::uint8_t((mask >> i) & 1u);
                     });
                   }});

  modes.push_back({"occluded_stream", "rtcOccluded1M", "occluded(Ray*, n, uint8*)", true,
                   [scene, coherent](const std::vector<Ray>& rays, Answers& out) {
                     RTCIntersectContext context = make_context(coherent);
                     for_each_embree_chunk(rays, [&](RTCRayHit* e, std::size_t b, std::size_t n) {
                       rtcOccluded1M(scene, &context, &e[0].ray, unsigned(n), sizeof(RTCRayHit));
                       for (std::size_t i = 0; i < n; ++i) out.blocked[b + i] = e[i].ray.tfar == kNegInf ? 1 : 0;
                     });
                   },
                   [&accel](const std::vector<Ray>& rays, Answers& out) {
                     for (std::size_t b = 0; b < rays.size(); b += kStreamChunk)
                       accel.occluded(rays.data() + b, std::min(kStreamChunk, rays.size() - b), out.blocked.data() + b, 1);
                   }});
  return modes;
}

}  // namespace volley::bench
