/* volley C API: the query forms with a ray mask (included by volley/volley.h; C99).
 *
 * Ray masks (as Embree's): a geometry has a 32-bit mask (volley_scene_set_geometry_mask,
 * default VOLLEY_MASK_ALL); a query with a mask sees only the geometries whose mask shares
 * a bit with it (mask 0: nothing). The queries of volley.h, without a mask, see every
 * geometry whose mask is not 0. Each masked form answers as its unmasked twin would on
 * the scene without the geometries the mask hides; its errors are the twin's, plus
 * VOLLEY_ERROR_INVALID_ARGUMENT for masks = NULL. Packets take one mask per lane, streams
 * one per ray (masks need no alignment). */
#ifndef VOLLEY_VOLLEY_MASKED_H
#define VOLLEY_VOLLEY_MASKED_H

#include "volley/volley.h"

#ifdef __cplusplus
extern "C" {
#endif

/** volley_intersect1 for a ray with a mask. */
VOLLEY_API volley_status volley_intersect1_masked(const volley_scene* scene, const volley_ray* ray, uint32_t mask,
                                                  volley_hit* hit);
/** volley_occluded1 for a ray with a mask. */
VOLLEY_API volley_status volley_occluded1_masked(const volley_scene* scene, const volley_ray* ray, uint32_t mask,
                                                 int* occluded);
/** volley_intersect4 with masks[i] the mask of lane i (4 masks; no alignment needed). */
VOLLEY_API volley_status volley_intersect4_masked(const volley_scene* scene, const volley_ray_packet4* rays,
                                                  const uint32_t* masks, volley_hit_packet4* hits);
/** volley_intersect8 with a mask per lane. */
VOLLEY_API volley_status volley_intersect8_masked(const volley_scene* scene, const volley_ray_packet8* rays,
                                                  const uint32_t* masks, volley_hit_packet8* hits);
/** volley_intersect16 with a mask per lane. */
VOLLEY_API volley_status volley_intersect16_masked(const volley_scene* scene, const volley_ray_packet16* rays,
                                                   const uint32_t* masks, volley_hit_packet16* hits);
/** volley_occluded4 with a mask per lane. */
VOLLEY_API volley_status volley_occluded4_masked(const volley_scene* scene, const volley_ray_packet4* rays,
                                                 const uint32_t* masks, uint32_t* occluded);
/** volley_occluded8 with a mask per lane. */
VOLLEY_API volley_status volley_occluded8_masked(const volley_scene* scene, const volley_ray_packet8* rays,
                                                 const uint32_t* masks, uint32_t* occluded);
/** volley_occluded16 with a mask per lane. */
VOLLEY_API volley_status volley_occluded16_masked(const volley_scene* scene, const volley_ray_packet16* rays,
                                                  const uint32_t* masks, uint32_t* occluded);
/** volley_intersect_stream with masks[i] the mask of rays[i]. */
VOLLEY_API volley_status volley_intersect_stream_masked(const volley_scene* scene, const volley_ray* rays,
                                                        const uint32_t* masks, size_t count, volley_hit* hits);
/** volley_occluded_stream with masks[i] the mask of rays[i]. */
VOLLEY_API volley_status volley_occluded_stream_masked(const volley_scene* scene, const volley_ray* rays,
                                                       const uint32_t* masks, size_t count, uint8_t* occluded);

#ifdef __cplusplus
}
#endif

#endif /* VOLLEY_VOLLEY_MASKED_H */
