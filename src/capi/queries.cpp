// The C API of the queries beyond the first hit (volley/volley_queries.h): arguments
// checked, then the C++ forms of Accel, whose errors become statuses in guarded().
#include <cstddef>
#include <cstring>
#include <string>
#include <type_traits>

#include "capi/guard.h"
#include "capi/scene.h"
#include "volley/accel.h"
#include "volley/volley.h"

namespace volley::capi {
namespace {

static_assert(sizeof(volley_closest_point) == sizeof(ClosestPoint) &&
                  offsetof(volley_closest_point, point) == offsetof(ClosestPoint, point) &&
                  offsetof(volley_closest_point, distance) == offsetof(ClosestPoint, distance) &&
                  offsetof(volley_closest_point, u) == offsetof(ClosestPoint, u) &&
                  offsetof(volley_closest_point, v) == offsetof(ClosestPoint, v) &&
                  offsetof(volley_closest_point, prim) == offsetof(ClosestPoint, prim) &&
                  offsetof(volley_closest_point, geom) == offsetof(ClosestPoint, geom) &&
                  std::is_trivially_copyable_v<ClosestPoint>,
              "volley_closest_point is volley::ClosestPoint");

const Ray* as_cpp(const volley_ray* r) { return reinterpret_cast<const Ray*>(r); }

/// The checks every batch shares: a committed scene, arrays present when count > 0, and a
/// thread count of 0 or more.
void require_batch(const volley_scene* scene, const void* in, const char* in_name, const void* out,
                   const char* out_name, std::size_t count, int threads) {
  require_committed(scene);
  if (count > 0) {
    require_pointer(in, in_name);
    require_pointer(out, out_name);
  }
  if (threads < 0) fail(VOLLEY_ERROR_INVALID_ARGUMENT, "threads is " + std::to_string(threads) + " (0: the caller's arena, n >= 1: n threads)");
}

}  // namespace
}  // namespace volley::capi

using namespace volley::capi;

extern "C" {

volley_status volley_intersect_batch(const volley_scene* scene, const volley_ray* rays, const uint32_t* masks,
                                     size_t count, volley_hit* hits, int threads) {
  return guarded("volley_intersect_batch", VOLLEY_ERROR_INTERNAL, [&] {
    require_batch(scene, rays, "rays", hits, "hits", count, threads);
    volley::Hit* out = reinterpret_cast<volley::Hit*>(hits);
    masks ? scene->accel.intersect(as_cpp(rays), masks, count, out, threads)
          : scene->accel.intersect(as_cpp(rays), count, out, threads);
  });
}

volley_status volley_occluded_batch(const volley_scene* scene, const volley_ray* rays, const uint32_t* masks,
                                    size_t count, uint8_t* occluded, int threads) {
  return guarded("volley_occluded_batch", VOLLEY_ERROR_INTERNAL, [&] {
    require_batch(scene, rays, "rays", occluded, "occluded", count, threads);
    masks ? scene->accel.occluded(as_cpp(rays), masks, count, occluded, threads)
          : scene->accel.occluded(as_cpp(rays), count, occluded, threads);
  });
}

volley_status volley_count_intersections(const volley_scene* scene, const volley_ray* rays, size_t count,
                                         uint32_t* counts, int threads) {
  return guarded("volley_count_intersections", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_batch(scene, rays, "rays", counts, "counts", count, threads);
    scene->accel.count_intersections(as_cpp(rays), count, counts, threads);
  });
}

volley_status volley_intersect_all1(const volley_scene* scene, const volley_ray* ray, volley_hit* hits,
                                    size_t capacity, size_t* count) {
  return guarded("volley_intersect_all1", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_committed(scene);
    require_pointer(ray, "ray");
    require_pointer(count, "count");
    if (capacity > 0) require_pointer(hits, "hits");
    *count = scene->accel.intersect_all(*as_cpp(ray), reinterpret_cast<volley::Hit*>(hits), capacity);
  });
}

volley_status volley_intersect_all(const volley_scene* scene, const volley_ray* rays, size_t count, size_t* offsets,
                                   volley_hit* hits, size_t capacity, size_t* total, int threads) {
  volley_status status = VOLLEY_OK;
  const volley_status run = guarded("volley_intersect_all", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_batch(scene, rays, "rays", offsets, "offsets", count, threads);
    require_pointer(offsets, "offsets");
    require_pointer(total, "total");
    if (capacity > 0) require_pointer(hits, "hits");
    const volley::HitLists lists = scene->accel.intersect_all(as_cpp(rays), count, threads);
    std::memcpy(offsets, lists.offsets.data(), lists.offsets.size() * sizeof(size_t));
    *total = lists.hits.size();
    if (lists.hits.size() > capacity) {
      status = set_error(VOLLEY_ERROR_BUFFER_TOO_SMALL, "volley_intersect_all",
                         ("the rays have " + std::to_string(lists.hits.size()) + " hits, the buffer holds " +
                          std::to_string(capacity) + " (offsets and total written: call again with a buffer of total hits)")
                             .c_str());
      return;
    }
    if (!lists.hits.empty()) std::memcpy(hits, lists.hits.data(), lists.hits.size() * sizeof(volley_hit));
  });
  return run != VOLLEY_OK ? run : status;
}

volley_status volley_contains(const volley_scene* scene, const float* xyz, size_t count, uint8_t* inside, int threads) {
  return guarded("volley_contains", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_batch(scene, xyz, "xyz", inside, "inside", count, threads);
    scene->accel.contains(xyz, count, inside, threads);
  });
}

volley_status volley_closest_points(const volley_scene* scene, const float* xyz, size_t count, float max_distance,
                                    volley_closest_point* out, int threads) {
  return guarded("volley_closest_points", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_batch(scene, xyz, "xyz", out, "out", count, threads);
    if (!(max_distance >= 0.0f)) fail(VOLLEY_ERROR_INVALID_ARGUMENT, "max_distance must be >= 0 (INFINITY: no limit)");
    scene->accel.closest_points(xyz, count, reinterpret_cast<volley::ClosestPoint*>(out), max_distance, threads);
  });
}

volley_status volley_distances(const volley_scene* scene, const float* xyz, size_t count, int is_signed, float* out,
                               int threads) {
  return guarded("volley_distances", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_batch(scene, xyz, "xyz", out, "out", count, threads);
    scene->accel.distances(xyz, count, out, is_signed != 0, threads);
  });
}

}  // extern "C"
