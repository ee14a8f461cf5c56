// The C API of the excluding queries (volley/volley_excluding.h): arguments checked, then
// Accel's excluding forms, whose errors (an excluded hit naming nothing) become
// VOLLEY_ERROR_INVALID_ARGUMENT in guarded().
#include <cstring>
#include <string>

#include "capi/guard.h"
#include "capi/scene.h"
#include "volley/accel.h"
#include "volley/volley.h"

namespace volley::capi {
namespace {

const Ray* as_cpp(const volley_ray* r) { return reinterpret_cast<const Ray*>(r); }
const Hit* as_cpp(const volley_hit* h) { return reinterpret_cast<const Hit*>(h); }

/// The checks of the batch forms: a committed scene, the arrays present when count > 0, and
/// a thread count of 0 or more.
void require_excluding_batch(const volley_scene* scene, const volley_ray* rays, const volley_hit* excluded,
                             const void* out, const char* out_name, std::size_t count, int threads) {
  require_committed(scene);
  if (count > 0) {
    require_pointer(rays, "rays");
    require_pointer(excluded, "excluded");
    require_pointer(out, out_name);
  }
  if (threads < 0)
    fail(VOLLEY_ERROR_INVALID_ARGUMENT, "threads is " + std::to_string(threads) + " (0: the caller's arena, n >= 1: n threads)");
}

}  // namespace
}  // namespace volley::capi

using namespace volley::capi;

extern "C" {

volley_status volley_intersect1_excluding(const volley_scene* scene, const volley_ray* ray, const volley_hit* excluded,
                                          volley_hit* hit) {
  return guarded("volley_intersect1_excluding", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_committed(scene);
    require_pointer(ray, "ray");
    require_pointer(excluded, "excluded");
    require_pointer(hit, "hit");
    const volley::Hit h = scene->accel.intersect_excluding(*as_cpp(ray), *as_cpp(excluded));
    std::memcpy(hit, &h, sizeof h);
  });
}

volley_status volley_occluded1_excluding(const volley_scene* scene, const volley_ray* ray, const volley_hit* excluded,
                                         int* occluded) {
  return guarded("volley_occluded1_excluding", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_committed(scene);
    require_pointer(ray, "ray");
    require_pointer(excluded, "excluded");
    require_pointer(occluded, "occluded");
    *occluded = scene->accel.occluded_excluding(*as_cpp(ray), *as_cpp(excluded)) ? 1 : 0;
  });
}

volley_status volley_intersect_batch_excluding(const volley_scene* scene, const volley_ray* rays,
                                               const uint32_t* masks, const volley_hit* excluded, size_t count,
                                               volley_hit* hits, int threads) {
  return guarded("volley_intersect_batch_excluding", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_excluding_batch(scene, rays, excluded, hits, "hits", count, threads);
    scene->accel.intersect(as_cpp(rays), count, reinterpret_cast<volley::Hit*>(hits),
                           volley::QueryArguments{masks, as_cpp(excluded), threads});
  });
}

volley_status volley_occluded_batch_excluding(const volley_scene* scene, const volley_ray* rays,
                                              const uint32_t* masks, const volley_hit* excluded, size_t count,
                                              uint8_t* occluded, int threads) {
  return guarded("volley_occluded_batch_excluding", VOLLEY_ERROR_INVALID_ARGUMENT, [&] {
    require_excluding_batch(scene, rays, excluded, occluded, "occluded", count, threads);
    scene->accel.occluded(as_cpp(rays), count, occluded, volley::QueryArguments{masks, as_cpp(excluded), threads});
  });
}

}  // extern "C"
