/* The C side of the consumer, the queries beyond the first hit: hit lists, counts,
 * inside/outside and closest points through volley/volley_queries.h. C99. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <volley/volley.h>

#include "consumer_c.h"
#include "scene.h"

/* Straight down through the table's diagonal y = x (shared by prims 2 and 3) and the floor's:
 * one hit on each, the table first. */
static void check_hit_lists(const volley_scene* scene) {
  volley_ray r = scene_ray(0);
  volley_ray rays[2];
  volley_hit hits[4];
  size_t count = 0, offsets[3], total = 0;
  uint32_t counts[2];
  r.org[0] = 0.5f, r.org[1] = 0.5f;
  expect(volley_intersect_all1(scene, &r, hits, 4, &count), VOLLEY_OK, "volley_intersect_all1");
  check(count == 2, "all hits through the shared diagonals: one per surface", 0);
  check(count == 2 && hits[0].t == 4.0f && hits[0].geom == 1 && hits[1].t == 5.0f && hits[1].geom == 0,
        "all hits in t order with their geometries", 0);
  expect(volley_intersect_all1(scene, &r, NULL, 0, &count), VOLLEY_OK, "volley_intersect_all1");
  check(count == 2, "a count without a buffer", 0);
  expect(volley_intersect_all1(scene, &r, NULL, 1, &count), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_intersect_all1");

  rays[0] = r;
  rays[1] = scene_ray(0); /* over nothing */
  expect(volley_count_intersections(scene, rays, 2, counts, 0), VOLLEY_OK, "volley_count_intersections");
  check(counts[0] == 2 && counts[1] == 0, "counts per ray", 0);
  expect(volley_count_intersections(scene, rays, 2, counts, -1), VOLLEY_ERROR_INVALID_ARGUMENT,
         "volley_count_intersections");
  expect(volley_intersect_all(scene, rays, 2, offsets, hits, 1, &total, 1), VOLLEY_ERROR_BUFFER_TOO_SMALL,
         "volley_intersect_all");
  check(total == 2 && offsets[0] == 0 && offsets[1] == 2 && offsets[2] == 2, "offsets and total before the hits", 0);
  expect(volley_intersect_all(scene, rays, 2, offsets, hits, 4, &total, 2), VOLLEY_OK, "volley_intersect_all");
  check(hits[0].geom == 1 && hits[1].geom == 0, "the flat list", 0);
}

/* The first-hit batches on several threads: the stream's answers. */
static void check_batches(const volley_scene* scene) {
  volley_ray rays[40];
  volley_hit hits[40], stream[40];
  uint8_t blocked[40], stream_blocked[40];
  uint32_t masks[40];
  for (int i = 0; i < 40; ++i) {
    rays[i] = scene_ray(0);
    rays[i].org[0] = -0.5f + 0.1f * (float)i;
    rays[i].org[1] = 0.5f;
    masks[i] = 0xffffffffu;
  }
  expect(volley_intersect_stream(scene, rays, 40, stream), VOLLEY_OK, "volley_intersect_stream");
  expect(volley_intersect_batch(scene, rays, NULL, 40, hits, 2), VOLLEY_OK, "volley_intersect_batch");
  for (int i = 0; i < 40; ++i)
    check(hits[i].t == stream[i].t && hits[i].prim == stream[i].prim && hits[i].geom == stream[i].geom,
          "a batch on 2 threads answers as the stream", i);
  expect(volley_intersect_batch(scene, rays, masks, 40, hits, 0), VOLLEY_OK, "volley_intersect_batch");
  for (int i = 0; i < 40; ++i) check(hits[i].t == stream[i].t, "a masked batch on the caller's arena", i);
  expect(volley_occluded_stream(scene, rays, 40, stream_blocked), VOLLEY_OK, "volley_occluded_stream");
  expect(volley_occluded_batch(scene, rays, NULL, 40, blocked, 3), VOLLEY_OK, "volley_occluded_batch");
  for (int i = 0; i < 40; ++i) check(blocked[i] == stream_blocked[i], "occlusion on 3 threads answers as the stream", i);
  for (int i = 0; i < 40; ++i) {
    float n[3];
    expect(volley_geometric_normal(scene, &hits[i], n), VOLLEY_OK, "volley_geometric_normal");
    /* Straight-down rays meet horizontal surfaces only; a miss gives NaN. */
    check(hits[i].prim == VOLLEY_INVALID_PRIM ? isnan(n[0]) : (n[0] == 0.0f && n[1] == 0.0f && fabsf(n[2]) == 1.0f),
          "the geometric normal of a hit", i);
  }
  expect(volley_geometric_normal(scene, NULL, NULL), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_geometric_normal");
  {
    float batch[3 * 40];
    expect(volley_geometric_normals(scene, hits, 40, batch), VOLLEY_OK, "volley_geometric_normals");
    for (int i = 0; i < 40; ++i) {
      float n[3];
      volley_geometric_normal(scene, &hits[i], n);
      check(memcmp(n, batch + 3 * i, sizeof n) == 0, "the batch of normals answers as one hit at a time", i);
    }
    expect(volley_geometric_normals(scene, hits, 40, NULL), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_geometric_normals");
    expect(volley_geometric_normals(scene, NULL, 0, NULL), VOLLEY_OK, "volley_geometric_normals");
  }
  expect(volley_intersect_batch(scene, rays, NULL, 40, hits, -1), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_intersect_batch");
  expect(volley_occluded_batch(scene, rays, NULL, 40, NULL, 1), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_occluded_batch");
  expect(volley_occluded_batch(scene, NULL, NULL, 0, NULL, 1), VOLLEY_OK, "volley_occluded_batch");
}

/* A closed box [0, 2]^3 of 12 triangles: inside/outside, distances and closest points. */
static void check_points(void) {
  static const float box[] = {0, 0, 0, 2, 0, 0, 2, 2, 0, 0, 2, 0, 0, 0, 2, 2, 0, 2, 2, 2, 2, 0, 2, 2};
  static const uint32_t idx[] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
  static const float points[] = {1, 1, 1, 3, 1, 1, 0.5f, 1, 1};
  volley_scene* scene = NULL;
  uint8_t inside[3];
  float d[3];
  volley_closest_point c[3];
  expect(volley_scene_create(&scene), VOLLEY_OK, "volley_scene_create");
  expect(volley_scene_add_triangles(scene, box, 8, idx, 12, NULL), VOLLEY_OK, "volley_scene_add_triangles");
  expect(volley_contains(scene, points, 3, inside, 0), VOLLEY_ERROR_NOT_COMMITTED, "volley_contains");
  expect(volley_scene_commit(scene, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AUTO), VOLLEY_OK, "volley_scene_commit");
  expect(volley_contains(scene, points, 3, inside, 0), VOLLEY_OK, "volley_contains");
  check(inside[0] == 1 && inside[1] == 0 && inside[2] == 1, "contains", 0);
  expect(volley_distances(scene, points, 3, 1, d, 0), VOLLEY_OK, "volley_distances");
  check(d[0] == -1.0f && d[1] == 1.0f && d[2] == -0.5f, "signed distances", 0);
  expect(volley_closest_points(scene, points, 3, INFINITY, c, 1), VOLLEY_OK, "volley_closest_points");
  check(c[1].point[0] == 2.0f && c[1].point[1] == 1.0f && c[1].point[2] == 1.0f && c[1].distance == 1.0f &&
            c[1].geom == 0 && c[1].prim < 12,
        "closest point", 1);
  expect(volley_closest_points(scene, points, 3, 0.75f, c, 1), VOLLEY_OK, "volley_closest_points");
  check(c[0].prim == VOLLEY_INVALID_PRIM && isinf(c[0].distance) && c[2].distance == 0.5f, "max_distance", 0);
  expect(volley_closest_points(scene, points, 3, -1.0f, c, 1), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_closest_points");
  expect(volley_distances(scene, NULL, 3, 0, d, 0), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_distances");
  volley_scene_destroy(scene);
}

void check_queries(void) {
  volley_scene* scene = make_scene();
  expect(volley_scene_commit(scene, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AUTO), VOLLEY_OK, "volley_scene_commit");
  check_hit_lists(scene);
  check_batches(scene);
  volley_scene_destroy(scene);
  check_points();
}
