/* Embedding volley from C: a square of two triangles and a stream of 8 rays. */
#include <stdio.h>
#include <volley/volley.h>

int main(void) {
  const float xyz[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0}; /* a unit square at z = 0 */
  const uint32_t indices[] = {0, 1, 2, 0, 2, 3};
  volley_scene* scene = NULL;
  volley_ray rays[8];
  volley_hit hits[8];
  int i, misses = 0;
  if (volley_scene_create(&scene) != VOLLEY_OK ||
      volley_scene_add_triangles(scene, xyz, 4, indices, 2, NULL) != VOLLEY_OK || /* copied */
      volley_scene_commit(scene, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AUTO) != VOLLEY_OK) {
    fprintf(stderr, "volley: %s\n", volley_last_error());
    return 1;
  }
  for (i = 0; i < 8; ++i) { /* org, tmin, dir, tmax: straight down from z = 2 */
    const volley_ray r = {{0.1f + 0.125f * (float)i, 0.3f, 2.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, 1e30f};
    rays[i] = r;
  }
  if (volley_intersect_stream(scene, rays, 8, hits) != VOLLEY_OK) {
    fprintf(stderr, "volley: %s\n", volley_last_error());
    return 1;
  }
  for (i = 0; i < 8; ++i) {
    printf("ray %d: t = %g, triangle %u\n", i, hits[i].t, hits[i].prim);
    misses += hits[i].prim == VOLLEY_INVALID_PRIM;
  }
  volley_scene_destroy(scene);
  return misses == 0 ? 0 : 1;
}
