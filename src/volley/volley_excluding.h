/* volley C API: the excluding queries (included by volley/volley.h; C99).
 *
 * A ray spawned at a hit point (a shadow, reflected or bounce ray with tmin = 0) would hit
 * the triangle it leaves again at t ~ 0; the usual cure is an offset of its origin, an
 * epsilon too small for far scenes and too large for thin features. These forms instead
 * pass over one primitive by its id: `excluded` is the hit the ray leaves (its geom, prim
 * and inst; t, u, v are not read), and the answer is the one the scene would give without
 * that primitive (in an instance: without it in that instance only). A miss as `excluded`
 * leaves nothing out. The C++ twins: volley::Accel::intersect_excluding, occluded_excluding.
 *
 * Errors, besides those every query has (VOLLEY_ERROR_NOT_COMMITTED; VOLLEY_ERROR_INVALID_ARGUMENT
 * for a NULL scene or pointer, or threads < 0): VOLLEY_ERROR_INVALID_ARGUMENT when an
 * excluded hit names no primitive of the scene (no such geometry, instance or primitive
 * index), with a message naming it; the batches check every excluded hit before writing
 * any answer. */
#ifndef VOLLEY_VOLLEY_EXCLUDING_H
#define VOLLEY_VOLLEY_EXCLUDING_H

#include "volley/volley.h"

#ifdef __cplusplus
extern "C" {
#endif

/** volley_intersect1 with the primitive *excluded names left out. */
VOLLEY_API volley_status volley_intersect1_excluding(const volley_scene* scene, const volley_ray* ray,
                                                     const volley_hit* excluded, volley_hit* hit);
/** volley_occluded1 with the primitive *excluded names left out. */
VOLLEY_API volley_status volley_occluded1_excluding(const volley_scene* scene, const volley_ray* ray,
                                                    const volley_hit* excluded, int* occluded);
/** Closest hits of `count` rays, excluded[i] left out for rays[i], masks[i] its mask (or
 *  every object for masks = NULL), on `threads` threads (the batch rule of
 *  volley_queries.h: 0 the caller's arena, n >= 1 exactly n). */
VOLLEY_API volley_status volley_intersect_batch_excluding(const volley_scene* scene, const volley_ray* rays,
                                                          const uint32_t* masks, const volley_hit* excluded,
                                                          size_t count, volley_hit* hits, int threads);
/** Occlusion of `count` rays, excluded[i] left out for rays[i]: occluded[i] = 1 when
 *  blocked, else 0. As volley_intersect_batch_excluding otherwise. */
VOLLEY_API volley_status volley_occluded_batch_excluding(const volley_scene* scene, const volley_ray* rays,
                                                         const uint32_t* masks, const volley_hit* excluded,
                                                         size_t count, uint8_t* occluded, int threads);

#ifdef __cplusplus
}
#endif

#endif /* VOLLEY_VOLLEY_EXCLUDING_H */
