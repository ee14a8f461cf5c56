// The crossing queries side by side: Embree 3 has no query that counts or lists every hit,
// so its users (Open3D's count_intersections, trimesh, ...) trace with an intersection
// filter that records each hit and rejects it, so the walk goes on to the next. Here
// that filter keeps distinct (geometry, primitive) pairs per ray (Embree may report one
// triangle twice: spatial splits put it in several leaves), against volley's
// count_intersections and intersect_all. The scene needs RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION
// (EmbreeConfig::context_filter).
#pragma once
#include <embree3/rtcore.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "query_modes.h"

namespace volley::bench {

/// An intersect context that records every distinct hit of up to 16 rays (lane = ray id).
struct CountingContext {
  RTCIntersectContext context;  // first: Embree hands the filter a pointer to it
  static constexpr unsigned kMaxHits = 256;
  struct Record {
    unsigned geom, prim;
    float t, u, v;
  };
  Record records[16][kMaxHits];
  unsigned count[16];
  bool keep_hits = false;  ///< store t, u, v too (all hits), not only the ids

  explicit CountingContext(bool coherent) {
    context = make_context(coherent);
    context.filter = &CountingContext::filter;
  }
  void reset() { std::fill(count, count + 16, 0u); }

  static void filter(const RTCFilterFunctionNArguments* args) {
    auto* c = reinterpret_cast<CountingContext*>(args->context);
    for (unsigned i = 0; i < args->N; ++i) {
      if (args->valid[i] != -1) continue;
      args->valid[i] = 0;  // rejected: the walk looks for the next hit
      const unsigned lane = RTCRayN_id(args->ray, args->N, i) & 15u;
      const unsigned geom = RTCHitN_geomID(args->hit, args->N, i), prim = RTCHitN_primID(args->hit, args->N, i);
      Record* r = c->records[lane];
      unsigned& n = c->count[lane];
      bool seen = false;
      for (unsigned k = 0; k < n && !seen; ++k) seen = r[k].geom == geom && r[k].prim == prim;
      if (seen || n == kMaxHits) continue;
      r[n].geom = geom, r[n].prim = prim;
      if (c->keep_hits)
        r[n].t = RTCRayN_tfar(args->ray, args->N, i), r[n].u = RTCHitN_u(args->hit, args->N, i),
        r[n].v = RTCHitN_v(args->hit, args->N, i);
      ++n;
    }
  }
};

/// Embree's count of every ray, one rtcIntersect1 each; keep_hits: every hit kept and
/// sorted by t too (what a list of all hits costs).
inline void embree_count1(RTCScene scene, bool coherent, bool keep_hits, const std::vector<Ray>& rays, Answers& out) {
  CountingContext c(coherent);
  c.keep_hits = keep_hits;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    RTCRayHit e;
    to_embree(rays[i], e);
    e.ray.id = 0;
    c.count[0] = 0;
    rtcIntersect1(scene, &c.context, &e);
    if (keep_hits)
      std::sort(c.records[0], c.records[0] + c.count[0], [](const auto& x, const auto& y) { return x.t < y.t; });
    out.counts[i] = c.count[0];
  }
}

/// count1 (one ray at a time on both sides), count16 (Embree's 16-wide packets; volley's
/// batch form, which packs runs of 16 rays by its stream policy) and all1 (every hit,
/// sorted by t).
inline void add_count_modes(std::vector<Mode>& modes, const EmbreeScene& embree, const Accel& accel, bool coherent) {
  const RTCScene scene = embree.scene();
  modes.push_back({"count1", "rtcIntersect1+filter", "count_intersections(Ray)", false,
                   [scene, coherent](const std::vector<Ray>& rays, Answers& out) {
                     embree_count1(scene, coherent, false, rays, out);
                   },
                   [&accel](const std::vector<Ray>& rays, Answers& out) {
                     for (std::size_t i = 0; i < rays.size(); ++i) out.counts[i] = accel.count_intersections(rays[i]);
                   },
                   true});
  modes.push_back({"count16", "rtcIntersect16+filter", "count_intersections(Ray*, n)", false,
                   [scene, coherent](const std::vector<Ray>& rays, Answers& out) {
                     CountingContext c(coherent);
                     for_each_embree16(rays, [&](RTCRayHit16& e, int* valid, std::size_t b, int n) {
                       c.reset();
                       rtcIntersect16(valid, scene, &c.context, &e);
                       for (int i = 0; i < n; ++i) out.counts[b + i] = c.count[i];
                     });
                   },
                   [&accel](const std::vector<Ray>& rays, Answers& out) {
                     // The batch form on the calling thread: runs of 16 as packets where the stream policy says so.
                     accel.count_intersections(rays.data(), rays.size(), out.counts.data(), 1);
                   },
                   true});
  modes.push_back({"all1", "rtcIntersect1+filter", "intersect_all(Ray, Hit*, n)", false,
                   [scene, coherent](const std::vector<Ray>& rays, Answers& out) {
                     embree_count1(scene, coherent, true, rays, out);
                   },
                   [&accel](const std::vector<Ray>& rays, Answers& out) {
                     Hit hits[CountingContext::kMaxHits];
                     for (std::size_t i = 0; i < rays.size(); ++i)
                       out.counts[i] = std::uint32_t(accel.intersect_all(rays[i], hits, CountingContext::kMaxHits));
                   },
                   true});
}

}  // namespace volley::bench
