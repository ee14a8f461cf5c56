/* volley C API: queries beyond the first hit (included by volley/volley.h; C99).
 * docs/crossings.md states the rules; the C++ twins are in volley/accel.h.
 *
 * Crossing queries count every surface a ray passes through exactly once: with the
 * watertight test (the default) a ray through an edge or vertex that closed meshes share
 * hits exactly one triangle there per crossing, and a ray grazing a silhouette an even
 * number. Point queries find the nearest surface point (triangles of the watertight or
 * Moller test, and polygons; not through instances).
 *
 * Batches: `threads` = 0 runs on the caller's oneTBB arena (all of its threads; the
 * process's default arena otherwise), n >= 1 on exactly n threads (1: the calling thread
 * only). Errors, besides those every query has (VOLLEY_ERROR_INVALID_ARGUMENT for a NULL
 * scene or array with count > 0, or threads < 0; VOLLEY_ERROR_NOT_COMMITTED): the point
 * queries answer VOLLEY_ERROR_INVALID_ARGUMENT for a scene with instances or built with
 * the plane test, and for max_distance < 0 or NaN. */
#ifndef VOLLEY_VOLLEY_QUERIES_H
#define VOLLEY_VOLLEY_QUERIES_H

#include "volley/volley.h"

#ifdef __cplusplus
extern "C" {
#endif

/** The nearest surface point to a query point (volley::ClosestPoint). 32 bytes. */
typedef struct volley_closest_point {
  float point[3]; /**< the nearest surface point */
  float distance; /**< to it; +inf when nothing lies within max_distance */
  float u, v;     /**< barycentric weights of the triangle's 2nd and 3rd vertex (0 for polygons) */
  uint32_t prim;  /**< primitive within its geometry; VOLLEY_INVALID_PRIM when none was found */
  uint32_t geom;  /**< geometry; VOLLEY_INVALID_ID when none was found */
} volley_closest_point;

/** Closest hits of `count` rays on `threads` threads (the batch rule above; 1: the calling
 *  thread, as volley_intersect_stream): hits[i] answers rays[i] (every entry written), with
 *  masks[i] its mask, or every object for masks = NULL. The same answers as
 *  volley_intersect_stream(_masked) for any thread count. */
VOLLEY_API volley_status volley_intersect_batch(const volley_scene* scene, const volley_ray* rays,
                                                const uint32_t* masks, size_t count, volley_hit* hits, int threads);

/** Occlusion of `count` rays on `threads` threads: occluded[i] = 1 when rays[i] is blocked,
 *  else 0. As volley_intersect_batch otherwise. */
VOLLEY_API volley_status volley_occluded_batch(const volley_scene* scene, const volley_ray* rays,
                                               const uint32_t* masks, size_t count, uint8_t* occluded, int threads);

/** The number of hits along each ray (tmin <= t < tmax): counts[i] for rays[i]. */
VOLLEY_API volley_status volley_count_intersections(const volley_scene* scene, const volley_ray* rays, size_t count,
                                                    uint32_t* counts, int threads);

/** Every hit along one ray, nearest first (ties by instance, geometry, primitive): writes
 *  the first min(*count, capacity) into hits (NULL allowed with capacity 0) and the number
 *  of hits into *count. */
VOLLEY_API volley_status volley_intersect_all1(const volley_scene* scene, const volley_ray* ray, volley_hit* hits,
                                               size_t capacity, size_t* count);

/** Every hit of `count` rays as one flat list (as Open3D's list_intersections): ray i's
 *  hits are hits[offsets[i] .. offsets[i + 1]), nearest first; offsets has count + 1
 *  entries and *total = offsets[count]. offsets and *total are always written; the hits
 *  only when capacity >= *total, else the call returns VOLLEY_ERROR_BUFFER_TOO_SMALL
 *  (call again with a buffer of *total hits). */
VOLLEY_API volley_status volley_intersect_all(const volley_scene* scene, const volley_ray* rays, size_t count,
                                              size_t* offsets, volley_hit* hits, size_t capacity, size_t* total,
                                              int threads);

/** Inside/outside of `count` points (xyz: 3 floats each) by the parity of one ray's
 *  crossings: inside[i] = 1 or 0. For geometry that is not closed the answer is that
 *  ray's parity; a point on the surface may go either way. */
VOLLEY_API volley_status volley_contains(const volley_scene* scene, const float* xyz, size_t count, uint8_t* inside,
                                         int threads);

/** The nearest surface point within max_distance (INFINITY: no limit) of each point. */
VOLLEY_API volley_status volley_closest_points(const volley_scene* scene, const float* xyz, size_t count,
                                               float max_distance, volley_closest_point* out, int threads);

/** The distance of each point to the surface; is_signed != 0: negative inside (the
 *  parity of volley_contains). +inf for a scene with nothing to find. */
VOLLEY_API volley_status volley_distances(const volley_scene* scene, const float* xyz, size_t count, int is_signed,
                                          float* out, int threads);

#ifdef __cplusplus
}
#endif

#endif /* VOLLEY_VOLLEY_QUERIES_H */
