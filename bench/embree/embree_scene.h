// Embree 3 on volley's triangles, for the side-by-side benchmark (volley_vs_embree) and
// the agreement test (tests/embree): one device, one scene holding one triangle geometry
// built from a merged indexed mesh (triangle i is Embree primID i, as it is volley's prim
// id i), and the conversions between volley's rays/hits and Embree's.
//
// Interval semantics differ: volley searches tmin <= t < tmax (half-open), Embree's
// kernels accept tnear < t <= tfar (its documentation says [tnear, tfar]). to_embree()
// sets tfar to the float just below a finite tmax, which makes the upper ends agree
// exactly; at the lower end the two differ only for t == tmin exactly (a hit at the ray
// origin), which offset origins and tmin = 0 camera rays never produce.
#pragma once
#include <embree3/rtcore.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "volley/ray.h"

namespace volley::bench {

/// How the Embree scene is built.
struct EmbreeConfig {
  RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM;  ///< Embree's default; HIGH = spatial splits
  bool robust = false;                                 ///< RTC_SCENE_FLAG_ROBUST (else NONE)
  bool context_filter = false;                         ///< RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION (count_modes.h)
  std::string device_config;                           ///< rtcNewDevice string, e.g. "threads=1"
};

/// Names as volley_vs_embree prints them ("low", "medium", "high", "refit").
inline const char* to_string(RTCBuildQuality q) {
  switch (q) {
    case RTC_BUILD_QUALITY_LOW: return "low";
    case RTC_BUILD_QUALITY_MEDIUM: return "medium";
    case RTC_BUILD_QUALITY_HIGH: return "high";
    default: return "refit";
  }
}

/// A triangle mesh for Embree: 3 * vertex_count floats, 3 * triangle_count indices.
struct EmbreeMesh {
  const float* xyz;
  std::size_t vertex_count;
  const std::uint32_t* indices;
  std::size_t triangle_count;
};

/// A placed copy of a prototype mesh (RTC_GEOMETRY_TYPE_INSTANCE): the 3x4 transform
/// [A | t] row by row, attached with geometry id `id` (its instID in hits).
struct EmbreeInstance {
  std::size_t prototype;
  float transform[12];
  unsigned id;
};

/// An Embree device and a committed scene of one triangle mesh (geometry 0) and any
/// instances of prototype meshes (each its own committed scene). Not copyable. Queries
/// through scene() are thread-safe (Embree's rule for committed scenes).
class EmbreeScene {
 public:
  /// `xyz`: 3 * vertex_count floats; `indices`: 3 * triangle_count vertex indices. The
  /// data is copied into Embree's own buffers. Throws std::runtime_error on an Embree error.
  EmbreeScene(const float* xyz, std::size_t vertex_count, const std::uint32_t* indices,
              std::size_t triangle_count, const EmbreeConfig& config = {})
      : EmbreeScene({xyz, vertex_count, indices, triangle_count}, {}, {}, config) {}

  /// The mesh `main` plus instances of `prototypes` (Embree's two-level scene).
  EmbreeScene(const EmbreeMesh& main, const std::vector<EmbreeMesh>& prototypes,
              const std::vector<EmbreeInstance>& instances, const EmbreeConfig& config = {}) {
    device_ = rtcNewDevice(config.device_config.empty() ? nullptr : config.device_config.c_str());
    if (!device_) throw std::runtime_error("embree: rtcNewDevice failed (" + error_name(rtcGetDeviceError(nullptr)) + ")");
    rtcSetDeviceErrorFunction(device_, &EmbreeScene::on_error, nullptr);
    const auto start = std::chrono::steady_clock::now();
    for (const EmbreeMesh& m : prototypes) {
      prototypes_.push_back(new_scene(config));
      attach_mesh(prototypes_.back(), m, config);
      rtcCommitScene(prototypes_.back());
    }
    scene_ = new_scene(config);
    if (main.triangle_count != 0) attach_mesh(scene_, main, config);
    for (const EmbreeInstance& in : instances) {
      RTCGeometry g = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_INSTANCE);
      rtcSetGeometryInstancedScene(g, prototypes_.at(in.prototype));
      rtcSetGeometryTransform(g, 0, RTC_FORMAT_FLOAT3X4_ROW_MAJOR, in.transform);
      rtcCommitGeometry(g);
      rtcAttachGeometryByID(scene_, g, in.id);
      rtcReleaseGeometry(g);
    }
    rtcCommitScene(scene_);
    build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (const RTCError e = rtcGetDeviceError(device_); e != RTC_ERROR_NONE)
      throw std::runtime_error("embree: scene build failed (" + error_name(e) + ")");
  }
  ~EmbreeScene() {
    if (scene_) rtcReleaseScene(scene_);
    for (RTCScene p : prototypes_) rtcReleaseScene(p);
    if (device_) rtcReleaseDevice(device_);
  }
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  /// The committed scene (owned; valid while this object lives).
  RTCScene scene() const { return scene_; }
  /// The device the scene lives on (owned).
  RTCDevice device() const { return device_; }
  /// Wall time of geometry upload and rtcCommitScene.
  double build_seconds() const { return build_seconds_; }

  /// Closest hit of one ray with rtcIntersect1, as a volley Hit (slow path for tests).
  Hit intersect(const Ray& ray) const;
  /// rtcOccluded1 on one ray.
  bool occluded(const Ray& ray) const;

  /// A readable name of an Embree error code.
  static std::string error_name(RTCError e) {
    switch (e) {
      case RTC_ERROR_NONE: return "no error";
      case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
      case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
      case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
      case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
      case RTC_ERROR_CANCELLED: return "cancelled";
      default: return "unknown error";
    }
  }

 private:
  RTCScene new_scene(const EmbreeConfig& config) const {
    RTCScene scene = rtcNewScene(device_);
    rtcSetSceneFlags(scene, RTCSceneFlags((config.robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE) |
                                          (config.context_filter ? RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION : 0)));
    rtcSetSceneBuildQuality(scene, config.quality);
    return scene;
  }
  /// One triangle geometry of `m`, attached to `scene` as geometry 0.
  void attach_mesh(RTCScene scene, const EmbreeMesh& m, const EmbreeConfig& config) const {
    RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geometry, config.quality);
    // rtcSetNewGeometryBuffer pads the allocation as Embree's SIMD loads require.
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), m.vertex_count));
    auto* t = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0,
                                                                  RTC_FORMAT_UINT3, 3 * sizeof(std::uint32_t),
                                                                  m.triangle_count));
    if (!v || !t) throw std::runtime_error("embree: cannot allocate geometry buffers");
    for (std::size_t i = 0; i < 3 * m.vertex_count; ++i) v[i] = m.xyz[i];
    for (std::size_t i = 0; i < 3 * m.triangle_count; ++i) t[i] = m.indices[i];
    rtcCommitGeometry(geometry);
    rtcAttachGeometryByID(scene, geometry, 0);
    rtcReleaseGeometry(geometry);
  }

  static void on_error(void*, RTCError code, const char* message) {
    std::fprintf(stderr, "embree error: %s: %s\n", error_name(code).c_str(), message ? message : "");
  }

  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::vector<RTCScene> prototypes_;
  double build_seconds_ = 0.0;
};

/// Embree's tfar for a volley tmax: the float below a finite tmax, so that Embree's
/// t <= tfar means t < tmax (see the top of this file). NaN stays NaN.
inline float embree_tfar(float tmax) {
  return std::isfinite(tmax) ? std::nextafter(tmax, -std::numeric_limits<float>::infinity()) : tmax;
}

/// A volley ray as an Embree ray (mask = all, time 0, no hit yet).
inline void to_embree(const Ray& r, RTCRayHit& e) {
  e.ray.org_x = r.org[0], e.ray.org_y = r.org[1], e.ray.org_z = r.org[2];
  e.ray.tnear = r.tmin;
  e.ray.dir_x = r.dir[0], e.ray.dir_y = r.dir[1], e.ray.dir_z = r.dir[2];
  e.ray.time = 0.0f;
  e.ray.tfar = embree_tfar(r.tmax);
  e.ray.mask = 0xffffffffu;
  e.ray.id = 0;
  e.ray.flags = 0;
  e.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  e.hit.primID = RTC_INVALID_GEOMETRY_ID;
  e.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

/// An Embree closest-hit answer as a volley Hit (same barycentric convention:
/// p = (1-u-v) p0 + u p1 + v p2).
inline Hit from_embree(const RTCRayHit& e) {
  if (e.hit.geomID == RTC_INVALID_GEOMETRY_ID) return Hit{};
  return Hit{e.ray.tfar, e.hit.u, e.hit.v, e.hit.primID, e.hit.geomID, e.hit.instID[0]};
}

/// Lane i of an Embree 16-ray packet from a volley ray.
inline void to_embree(const Ray& r, RTCRayHit16& e, int i) {
  e.ray.org_x[i] = r.org[0], e.ray.org_y[i] = r.org[1], e.ray.org_z[i] = r.org[2];
  e.ray.tnear[i] = r.tmin;
  e.ray.dir_x[i] = r.dir[0], e.ray.dir_y[i] = r.dir[1], e.ray.dir_z[i] = r.dir[2];
  e.ray.time[i] = 0.0f;
  e.ray.tfar[i] = embree_tfar(r.tmax);
  e.ray.mask[i] = 0xffffffffu;
  e.ray.id[i] = unsigned(i);
  e.ray.flags[i] = 0;
  e.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
  e.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
  e.hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
}

/// Calls trace(packet, valid, b, n) for each run rays[b .. b + n) of up to 16 rays as an
/// Embree 16-ray packet (lanes past the end invalid), b = 0, 16, 32, ...
template <class Trace>
void for_each_embree16(const std::vector<Ray>& rays, Trace&& trace) {
  alignas(64) RTCRayHit16 e;
  alignas(64) int valid[16];
  for (std::size_t b = 0; b < rays.size(); b += 16) {
    const int n = int(std::min<std::size_t>(16, rays.size() - b));
    for (int i = 0; i < 16; ++i) {
      valid[i] = i < n ? -1 : 0;
      if (i < n) to_embree(rays[b + i], e, i);
    }
    trace(e, valid, b, n);
  }
}

/// Lane i of an Embree 16-ray packet answer as a volley Hit.
inline Hit from_embree(const RTCRayHit16& e, int i) {
  if (e.hit.geomID[i] == RTC_INVALID_GEOMETRY_ID) return Hit{};
  return Hit{e.ray.tfar[i], e.hit.u[i], e.hit.v[i], e.hit.primID[i], e.hit.geomID[i], e.hit.instID[0][i]};
}

inline Hit EmbreeScene::intersect(const Ray& ray) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit e;
  to_embree(ray, e);
  rtcIntersect1(scene_, &context, &e);
  return from_embree(e);
}

inline bool EmbreeScene::occluded(const Ray& ray) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit e;
  to_embree(ray, e);
  rtcOccluded1(scene_, &context, &e.ray);
  return e.ray.tfar == -std::numeric_limits<float>::infinity();
}

}  // namespace volley::bench
