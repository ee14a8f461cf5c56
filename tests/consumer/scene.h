/* The consumer's test scene and its exact answers, shared by the C++ and C checks
 * (C99 and C++17).
 *
 * Seen from above (rays go straight down, -z, from z = 5):
 *   prims 0, 1  the floor: the square [-2, 2]^2 at z = 0, split along y = x
 *   prims 2, 3  a table:   the square [0, 1]^2 at z = 1, split along y = x
 *   prim  4     a polygon: an L at z = 2 in [-1.5, -0.5]^2 (concave; six corners)
 * The ray grid keeps at least 0.02 from every edge and diagonal, so each ray's answer is
 * unambiguous whatever the test or ISA. */
#ifndef VOLLEY_CONSUMER_SCENE_H
#define VOLLEY_CONSUMER_SCENE_H

#include <math.h>
#include <stdint.h>

#include <volley/volley.h>

#define SCENE_GRID 50 /* rays per side: SCENE_GRID^2 rays */
#define SCENE_RAYS (SCENE_GRID * SCENE_GRID)

static const float kFloorXyz[] = {-2, -2, 0, 2, -2, 0, 2, 2, 0, -2, 2, 0};
static const uint32_t kFloorIndices[] = {0, 1, 2, 0, 2, 3};
static const float kTableXyz[] = {0, 0, 1, 1, 0, 1, 1, 1, 1, 0, 1, 1};
static const uint32_t kTableIndices[] = {0, 1, 2, 0, 2, 3};
static const float kPolygonXyz[] = {-1.5f, -1.5f, 2, -0.5f, -1.5f, 2, -0.5f, -1.0f, 2,
                                    -1.0f, -1.0f, 2, -1.0f, -0.5f, 2, -1.5f, -0.5f, 2};

/* Ray i of the grid: straight down from z = 5 over [-2.45, 2.55] x [-2.42, 2.58]. */
static inline volley_ray scene_ray(int i) {
  volley_ray r;
  r.org[0] = -2.45f + 0.1f * (float)(i % SCENE_GRID);
  r.org[1] = -2.42f + 0.1f * (float)(i / SCENE_GRID);
  r.org[2] = 5.0f;
  r.tmin = 0.0f;
  r.dir[0] = 0.0f;
  r.dir[1] = 0.0f;
  r.dir[2] = -1.0f;
  r.tmax = 100.0f;
  return r;
}

/* The prim ray i hits first and its t, from the geometry above. */
static inline uint32_t scene_expected_prim(const volley_ray* r, float* t) {
  const float x = r->org[0], y = r->org[1];
  const int in_l = x > -1.5f && y > -1.5f && ((x < -0.5f && y < -1.0f) || (x < -1.0f && y < -0.5f));
  if (in_l) {
    *t = 3.0f;
    return 4;
  }
  if (x > 0.0f && x < 1.0f && y > 0.0f && y < 1.0f) {
    *t = 4.0f;
    return y < x ? 2 : 3;
  }
  if (x > -2.0f && x < 2.0f && y > -2.0f && y < 2.0f) {
    *t = 5.0f;
    return y < x ? 0 : 1;
  }
  *t = INFINITY;
  return VOLLEY_INVALID_PRIM;
}

/* The geometry and the index within it of a scene_expected_prim number: the floor's
 * triangles are 0 and 1 (geometry 0), the table's 2 and 3 (geometry 1), the polygon 4
 * (geometry 2). */
static inline uint32_t scene_geometry(uint32_t id) { return id == VOLLEY_INVALID_PRIM ? VOLLEY_INVALID_ID : id / 2; }
static inline uint32_t scene_local(uint32_t id) { return id == VOLLEY_INVALID_PRIM ? id : id % 2; }

/* 1 when a hit's t is the exact `expected` within rounding (the tests compute t in
 * different ways, none of them exactly). */
static inline int scene_t_close(float t, float expected) {
  return isinf(expected) ? isinf(t) : fabsf(t - expected) <= 1e-5f * expected;
}

#endif /* VOLLEY_CONSUMER_SCENE_H */
