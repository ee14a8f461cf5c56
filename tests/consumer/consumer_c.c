/* The C side of the consumer: builds tests/consumer/scene.h through the C API for every
 * test and every ISA this CPU has, and checks single rays, packets of 4, 8 and 16,
 * streams and occlusion against the exact answers; then the validation at the boundary:
 * NULL pointers, NaN vertices, indices out of range, bad polygons, enums out of range,
 * queries before commit, misaligned packets, zero-direction and NaN rays, garbage in
 * inactive lanes. C99. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <volley/volley.h>

#include "consumer_c.h"
#include "scene.h"

int failures = 0;

void check(int ok, const char* what, int index) {
  if (!ok) {
    ++failures;
    if (failures <= 20) printf("FAIL: %s (%d)\n", what, index);
  }
}

/* Checks status == expected and, on failure, that the message names the function. */
void expect(volley_status status, volley_status expected, const char* function) {
  if (status != expected) {
    ++failures;
    printf("FAIL: %s returned %s, expected %s (%s)\n", function, volley_status_string(status),
           volley_status_string(expected), volley_last_error());
  } else if (expected != VOLLEY_OK && strstr(volley_last_error(), function) != volley_last_error()) {
    ++failures;
    printf("FAIL: the message of %s does not start with its name: \"%s\"\n", function, volley_last_error());
  }
}

/* Adds a 4-vertex mesh of `triangles` triangles, expected to succeed; returns its geometry id. */
static uint32_t add_mesh(volley_scene* scene, const float* xyz, const uint32_t* indices, size_t triangles) {
  uint32_t id = 99;
  expect(volley_scene_add_triangles(scene, xyz, 4, indices, triangles, &id), VOLLEY_OK, "volley_scene_add_triangles");
  return id;
}

volley_scene* make_scene(void) {
  volley_scene* scene = NULL;
  uint32_t first = 99, polygon = 99;
  expect(volley_scene_create(&scene), VOLLEY_OK, "volley_scene_create");
  first = add_mesh(scene, kFloorXyz, kFloorIndices, 2);
  check(first == 0, "floor geometry id", (int)first);
  first = add_mesh(scene, kTableXyz, kTableIndices, 2);
  check(first == 1, "table geometry id", (int)first);
  expect(volley_scene_add_polygon(scene, kPolygonXyz, 6, &polygon), VOLLEY_OK, "volley_scene_add_polygon");
  check(polygon == 2, "polygon geometry id", (int)polygon);
  return scene;
}

static int same_hit(const volley_hit* a, float t, float u, float v, uint32_t prim, uint32_t geom, uint32_t inst) {
  return memcmp(&a->t, &t, 4) == 0 && memcmp(&a->u, &u, 4) == 0 && memcmp(&a->v, &v, 4) == 0 && a->prim == prim &&
         a->geom == geom && a->inst == inst;
}

/* Packets of width K (4, 8, 16) in runs of `count` lanes, against the single-ray answers.
 * A macro: C has no templates, and the three packet types differ only in K. */
#define CHECK_PACKETS(K)                                                                          \
  static void check_packets##K(const volley_scene* scene, const volley_hit* single) {            \
    volley_ray_packet##K packet;                                                                  \
    volley_hit_packet##K hits;                                                                    \
    int count, i, l;                                                                              \
    for (count = K - 1; count <= K; ++count) {                                                   \
      for (i = 0; i < SCENE_RAYS; i += count) {                                                  \
        const int n = SCENE_RAYS - i < count ? SCENE_RAYS - i : count;                           \
        uint32_t blocked = 0;                                                                     \
        packet.active = 0;                                                                        \
        for (l = 0; l < K; ++l) {                                                                 \
          const volley_ray r = scene_ray(l < n ? i + l : 0);                                      \
          packet.ox[l] = l < n ? r.org[0] : NAN; /* garbage in inactive lanes is ignored */       \
          packet.oy[l] = r.org[1], packet.oz[l] = r.org[2];                                       \
          packet.dx[l] = r.dir[0], packet.dy[l] = r.dir[1], packet.dz[l] = r.dir[2];              \
          packet.tmin[l] = r.tmin, packet.tmax[l] = r.tmax;                                       \
          if (l < n) packet.active |= 1u << l;                                                    \
        }                                                                                         \
        volley_reset_hits##K(&hits);                                                              \
        expect(volley_intersect##K(scene, &packet, &hits), VOLLEY_OK, "volley_intersect" #K);     \
        expect(volley_occluded##K(scene, &packet, &blocked), VOLLEY_OK, "volley_occluded" #K);    \
        for (l = 0; l < K; ++l) {                                                                 \
          if (l < n) {                                                                            \
            const volley_hit* s = &single[i + l];                                                 \
            check(same_hit(s, hits.t[l], hits.u[l], hits.v[l], hits.prim[l], hits.geom[l], hits.inst[l]), \
                  "packet" #K, i + l);                                                            \
            check(((blocked >> l) & 1u) == (s->prim != VOLLEY_INVALID_PRIM), "occluded" #K, i + l); \
          } else {                                                                                \
            check(hits.prim[l] == VOLLEY_INVALID_PRIM && isinf(hits.t[l]), "inactive lane", l);   \
            check(((blocked >> l) & 1u) == 0, "inactive lane occluded", l);                       \
          }                                                                                       \
        }                                                                                         \
      }                                                                                           \
    }                                                                                             \
  }
CHECK_PACKETS(4)
CHECK_PACKETS(8)
CHECK_PACKETS(16)

/* Rays that can never hit, every query mode: 32 rays down onto the table, every third
 * with a zero direction (its origin on the floor, the table or the polygon: the worst
 * case, t = 0 / 0) and ray 8 with a NaN origin. They must all miss; the others hit. */
static void check_misses(const volley_scene* scene) {
  volley_ray rays[32];
  volley_hit hits[32];
  uint8_t blocked[32];
  volley_ray_packet16 packet;
  volley_hit_packet16 hits16;
  int i, l, occluded;
  uint32_t mask;
  for (i = 0; i < 32; ++i) {
    const int zero = i % 3 == 0;
    rays[i].org[0] = 0.02f + 0.03f * (float)i, rays[i].org[1] = 0.9f, rays[i].org[2] = zero ? 1.0f : 5.0f;
    if (zero && i % 2) rays[i].org[0] = -1.2f, rays[i].org[1] = -1.3f, rays[i].org[2] = i % 4 == 1 ? 2.0f : 0.0f;
    rays[i].dir[0] = 0.0f, rays[i].dir[1] = 0.0f, rays[i].dir[2] = zero ? (i % 4 == 0 ? -0.0f : 0.0f) : -1.0f;
    rays[i].tmin = 0.0f, rays[i].tmax = 100.0f;
  }
  rays[8].org[1] = NAN;
  for (i = 0; i < 32; ++i) {
    const int hit_expected = i % 3 != 0 && i != 8;
    volley_hit h;
    expect(volley_intersect1(scene, &rays[i], &h), VOLLEY_OK, "volley_intersect1");
    expect(volley_occluded1(scene, &rays[i], &occluded), VOLLEY_OK, "volley_occluded1");
    check((h.prim != VOLLEY_INVALID_PRIM) == hit_expected && occluded == hit_expected, "single: zero/NaN rays miss", i);
  }
  for (i = 0; i < 32; i += 16) {
    for (l = 0; l < 16; ++l) {
      const volley_ray* r = &rays[i + l];
      packet.ox[l] = r->org[0], packet.oy[l] = r->org[1], packet.oz[l] = r->org[2];
      packet.dx[l] = r->dir[0], packet.dy[l] = r->dir[1], packet.dz[l] = r->dir[2];
      packet.tmin[l] = r->tmin, packet.tmax[l] = r->tmax;
    }
    packet.active = 0xffffu;
    volley_reset_hits16(&hits16);
    expect(volley_intersect16(scene, &packet, &hits16), VOLLEY_OK, "volley_intersect16");
    expect(volley_occluded16(scene, &packet, &mask), VOLLEY_OK, "volley_occluded16");
    for (l = 0; l < 16; ++l) {
      const int hit_expected = (i + l) % 3 != 0 && i + l != 8;
      check((hits16.prim[l] != VOLLEY_INVALID_PRIM) == hit_expected && (int)((mask >> l) & 1u) == hit_expected,
            "packet: zero/NaN rays miss", i + l);
    }
  }
  expect(volley_intersect_stream(scene, rays, 32, hits), VOLLEY_OK, "volley_intersect_stream");
  expect(volley_occluded_stream(scene, rays, 32, blocked), VOLLEY_OK, "volley_occluded_stream");
  for (i = 0; i < 32; ++i) {
    const int hit_expected = i % 3 != 0 && i != 8;
    check((hits[i].prim != VOLLEY_INVALID_PRIM) == hit_expected && blocked[i] == hit_expected,
          "stream: zero/NaN rays miss", i);
  }
}

static void check_scene(const volley_commit_options* options) {
  const volley_triangle_test test = options->test;
  const volley_isa isa = options->isa;
  volley_scene* scene;
  volley_scene_info info;
  volley_ray rays[SCENE_RAYS];
  volley_hit single[SCENE_RAYS], stream[SCENE_RAYS];
  uint8_t blocked[SCENE_RAYS];
  int i, occluded;
  if (!volley_isa_supported(isa)) {
    printf("skip test %d ISA %d: not supported by this CPU\n", (int)test, (int)isa);
    return;
  }
  scene = make_scene();
  expect(volley_scene_commit_ex(scene, options), VOLLEY_OK, "volley_scene_commit_ex");
  expect(volley_scene_get_info(scene, &info), VOLLEY_OK, "volley_scene_get_info");
  check(info.triangles == 4 && info.polygons == 1 && info.test == test, "info", 0);
  check(isa == VOLLEY_ISA_AUTO ? info.isa != VOLLEY_ISA_AUTO : info.isa == isa, "info.isa", (int)info.isa);

  for (i = 0; i < SCENE_RAYS; ++i) {
    float t;
    uint32_t prim;
    rays[i] = scene_ray(i);
    prim = scene_expected_prim(&rays[i], &t);
    expect(volley_intersect1(scene, &rays[i], &single[i]), VOLLEY_OK, "volley_intersect1");
    check(single[i].prim == scene_local(prim) && single[i].geom == scene_geometry(prim) &&
              single[i].inst == VOLLEY_INVALID_ID && scene_t_close(single[i].t, t),
          "single", i);
    expect(volley_occluded1(scene, &rays[i], &occluded), VOLLEY_OK, "volley_occluded1");
    check(occluded == (prim != VOLLEY_INVALID_PRIM), "occluded1", i);
  }
  check_packets4(scene, single);
  check_packets8(scene, single);
  check_packets16(scene, single);
  check_misses(scene);

  expect(volley_intersect_stream(scene, rays, SCENE_RAYS, stream), VOLLEY_OK, "volley_intersect_stream");
  expect(volley_occluded_stream(scene, rays, SCENE_RAYS, blocked), VOLLEY_OK, "volley_occluded_stream");
  for (i = 0; i < SCENE_RAYS; ++i) {
    check(memcmp(&stream[i], &single[i], sizeof stream[i]) == 0, "stream", i);
    check(blocked[i] == (single[i].prim != VOLLEY_INVALID_PRIM), "occluded stream", i);
  }
  volley_scene_destroy(scene);
}

static void check_validation(void) {
  const float nan_xyz[] = {0, 0, 0, 1, 0, 0, 0, NAN, 0};
  const float inf_xyz[] = {0, 0, 0, INFINITY, 0, 0, 0, 1, 0};
  const float line[] = {0, 0, 0, 1, 0, 0};
  const float skew[] = {0, 0, 0, 1, 0, 0, 1, 1, 0.5f, 0, 1, 0};
  const uint32_t tri[] = {0, 1, 2}, two_tris_bad[] = {0, 1, 2, 0, 2, 4};
  volley_scene* scene = NULL;
  volley_scene_info info;
  volley_hit hit;
  volley_commit_options options;
  int occluded = 7;
  uint32_t first = 0, mask = 0;
  size_t bad = 0;
  struct {
    volley_ray_packet16 packet;
    volley_hit_packet16 hits;
    unsigned char spare[64];
  } memory; /* 64-byte aligned, as its first member */
  unsigned char* buffer = (unsigned char*)&memory;
  volley_ray rays[40];
  volley_hit hits[40];
  uint8_t blocked[40];
  int i;

  check(strcmp(volley_version(), "0.1.0") == 0 && VOLLEY_VERSION_MINOR == 1, "version", 0);
  check(strcmp(volley_status_string(VOLLEY_ERROR_MISALIGNED), "VOLLEY_ERROR_MISALIGNED") == 0, "status name", 0);
  check(volley_isa_supported(VOLLEY_ISA_SCALAR) && !volley_isa_supported((volley_isa)42), "isa_supported", 0);

  expect(volley_scene_create(NULL), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_create");
  expect(volley_scene_create(&scene), VOLLEY_OK, "volley_scene_create");
  expect(volley_intersect1(scene, &rays[0], &hit), VOLLEY_ERROR_NOT_COMMITTED, "volley_intersect1");
  expect(volley_scene_add_triangles(NULL, kFloorXyz, 4, kFloorIndices, 2, NULL), VOLLEY_ERROR_INVALID_ARGUMENT,
         "volley_scene_add_triangles");
  expect(volley_scene_add_triangles(scene, NULL, 4, kFloorIndices, 2, NULL), VOLLEY_ERROR_INVALID_ARGUMENT,
         "volley_scene_add_triangles");
  expect(volley_scene_add_triangles(scene, kFloorXyz, 4, NULL, 2, NULL), VOLLEY_ERROR_INVALID_ARGUMENT,
         "volley_scene_add_triangles");
  expect(volley_scene_add_triangles(scene, nan_xyz, 3, tri, 1, NULL), VOLLEY_ERROR_INVALID_GEOMETRY,
         "volley_scene_add_triangles");
  check(strstr(volley_last_error(), "vertex 2") != NULL, "the NaN message names the vertex", 0);
  expect(volley_scene_add_triangles(scene, inf_xyz, 3, tri, 1, NULL), VOLLEY_ERROR_INVALID_GEOMETRY,
         "volley_scene_add_triangles");
  /* The first triangle is fine, the second is not: nothing may be added. */
  expect(volley_scene_add_triangles(scene, kFloorXyz, 4, two_tris_bad, 2, NULL), VOLLEY_ERROR_INVALID_GEOMETRY,
         "volley_scene_add_triangles");
  check(strstr(volley_last_error(), "index 4") != NULL, "the index message names the index", 0);
  expect(volley_scene_add_polygon(scene, line, 2, NULL), VOLLEY_ERROR_INVALID_GEOMETRY, "volley_scene_add_polygon");
  expect(volley_scene_add_polygon(scene, skew, 4, NULL), VOLLEY_ERROR_INVALID_GEOMETRY, "volley_scene_add_polygon");
  expect(volley_scene_add_polygon(scene, NULL, 4, NULL), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_add_polygon");
  /* After all that, the scene is empty: the next triangles are geometry 0. */
  first = add_mesh(scene, kFloorXyz, kFloorIndices, 2);
  check(first == 0, "failed calls added nothing", (int)first);
  first = add_mesh(scene, kFloorXyz, kFloorIndices, 0);
  check(first == 1, "an empty mesh is a geometry too, the next id", (int)first);

  expect(volley_scene_commit(scene, (volley_triangle_test)7, VOLLEY_ISA_AUTO), VOLLEY_ERROR_INVALID_ARGUMENT,
         "volley_scene_commit");
  expect(volley_scene_commit(scene, VOLLEY_TEST_WATERTIGHT, (volley_isa)-1), VOLLEY_ERROR_INVALID_ARGUMENT,
         "volley_scene_commit");
  if (!volley_isa_supported(VOLLEY_ISA_AVX512))
    expect(volley_scene_commit(scene, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AVX512), VOLLEY_ERROR_UNSUPPORTED_ISA,
           "volley_scene_commit");
  expect(volley_scene_commit_ex(scene, NULL), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_commit_ex");
  volley_commit_options_default(&options);
  options.reference_double = 1; /* the double reference runs on the scalar oracle only */
  expect(volley_scene_commit_ex(scene, &options), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_commit_ex");
  options.isa = VOLLEY_ISA_SCALAR, options.robust = 0;
  expect(volley_scene_commit_ex(scene, &options), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_commit_ex");
  expect(volley_scene_get_info(scene, &info), VOLLEY_ERROR_NOT_COMMITTED, "volley_scene_get_info");
  volley_commit_options_default(&options);
  check(options.quality == VOLLEY_BUILD_QUALITY_MEDIUM, "medium quality is the default", (int)options.quality);
  options.quality = (volley_build_quality)0; /* Embree's LOW: not offered */
  expect(volley_scene_commit_ex(scene, &options), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_commit_ex");
  check(strstr(volley_last_error(), "build quality") != NULL, "the message names the build quality", 0);
  options.quality = (volley_build_quality)3;
  expect(volley_scene_commit_ex(scene, &options), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_commit_ex");
  options.quality = VOLLEY_BUILD_QUALITY_HIGH;
  expect(volley_scene_commit_ex(scene, &options), VOLLEY_OK, "volley_scene_commit_ex");
  expect(volley_scene_get_info(scene, &info), VOLLEY_OK, "volley_scene_get_info");
  check(info.quality == VOLLEY_BUILD_QUALITY_HIGH && info.references >= 2, "info reports the quality and references",
        (int)info.quality);
  expect(volley_scene_commit(scene, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AUTO), VOLLEY_OK, "volley_scene_commit");
  expect(volley_scene_get_info(scene, &info), VOLLEY_OK, "volley_scene_get_info");
  check(info.triangles == 2, "two triangles", (int)info.triangles);

  /* Rays that can never hit: answered as misses, reported by volley_validate_rays. */
  for (i = 0; i < 40; ++i) {
    rays[i].org[0] = -1.9f + 0.09f * (float)i, rays[i].org[1] = 0.37f, rays[i].org[2] = 1.0f;
    rays[i].dir[0] = 0.0f, rays[i].dir[1] = 0.0f, rays[i].dir[2] = -1.0f;
    rays[i].tmin = 0.0f, rays[i].tmax = 10.0f;
  }
  expect(volley_validate_rays(rays, 40, &bad), VOLLEY_OK, "volley_validate_rays");
  rays[17].dir[2] = 0.0f; /* zero direction, its origin on the floor's plane: still a miss */
  rays[17].org[2] = 0.0f;
  rays[23].org[1] = NAN;
  expect(volley_validate_rays(rays, 40, &bad), VOLLEY_ERROR_INVALID_RAY, "volley_validate_rays");
  check(bad == 17 && strstr(volley_last_error(), "zero") != NULL, "first invalid ray", (int)bad);
  expect(volley_validate_rays(NULL, 3, &bad), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_validate_rays");
  expect(volley_intersect1(scene, &rays[17], &hit), VOLLEY_OK, "volley_intersect1");
  check(hit.prim == VOLLEY_INVALID_PRIM && isinf(hit.t), "zero direction misses", 17);
  expect(volley_occluded1(scene, &rays[17], &occluded), VOLLEY_OK, "volley_occluded1");
  check(occluded == 0, "zero direction is not occluded", 17);
  expect(volley_intersect_stream(scene, rays, 40, hits), VOLLEY_OK, "volley_intersect_stream");
  expect(volley_occluded_stream(scene, rays, 40, blocked), VOLLEY_OK, "volley_occluded_stream");
  for (i = 0; i < 40; ++i) {
    const int hits_floor = i != 17 && i != 23;
    check((hits[i].prim != VOLLEY_INVALID_PRIM) == hits_floor && blocked[i] == hits_floor, "stream with bad rays", i);
  }
  expect(volley_intersect_stream(scene, NULL, 0, NULL), VOLLEY_OK, "volley_intersect_stream");
  expect(volley_intersect_stream(scene, NULL, 4, hits), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_intersect_stream");

  /* Packets: a zero-direction lane misses; misaligned packets are refused. */
  {
    volley_ray_packet16* packet = &memory.packet;
    volley_hit_packet16* hits16 = &memory.hits;
    memset(packet, 0, sizeof *packet);
    for (i = 0; i < 16; ++i) {
      packet->ox[i] = rays[i + 10].org[0], packet->oy[i] = rays[i + 10].org[1], packet->oz[i] = rays[i + 10].org[2];
      packet->dx[i] = rays[i + 10].dir[0], packet->dy[i] = rays[i + 10].dir[1], packet->dz[i] = rays[i + 10].dir[2];
      packet->tmin[i] = rays[i + 10].tmin, packet->tmax[i] = rays[i + 10].tmax;
    }
    packet->active = 0xffffu;
    volley_reset_hits16(hits16);
    expect(volley_intersect16(scene, packet, hits16), VOLLEY_OK, "volley_intersect16");
    expect(volley_occluded16(scene, packet, &mask), VOLLEY_OK, "volley_occluded16");
    for (i = 0; i < 16; ++i) {
      const int hits_floor = i + 10 != 17 && i + 10 != 23;
      check((hits16->prim[i] != VOLLEY_INVALID_PRIM) == hits_floor, "packet with bad rays", i + 10);
      check((int)((mask >> i) & 1u) == hits_floor, "occluded packet with bad rays", i + 10);
    }
    expect(volley_intersect16(scene, (const volley_ray_packet16*)(buffer + 4), hits16), VOLLEY_ERROR_MISALIGNED,
           "volley_intersect16");
    check(strstr(volley_last_error(), "rays is not 64-byte aligned") != NULL, "misaligned message", 0);
    expect(volley_intersect16(scene, packet, (volley_hit_packet16*)(buffer + sizeof *packet + 16)),
           VOLLEY_ERROR_MISALIGNED, "volley_intersect16");
    expect(volley_occluded16(scene, (const volley_ray_packet16*)(buffer + 32), &mask), VOLLEY_ERROR_MISALIGNED,
           "volley_occluded16");
    expect(volley_occluded4(scene, (const volley_ray_packet4*)(buffer + 8), &mask), VOLLEY_ERROR_MISALIGNED,
           "volley_occluded4");
    expect(volley_occluded8(scene, NULL, &mask), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_occluded8");
  }

  /* Adding geometry un-commits the scene. */
  expect(volley_scene_add_polygon(scene, kPolygonXyz, 6, NULL), VOLLEY_OK, "volley_scene_add_polygon");
  expect(volley_intersect1(scene, &rays[0], &hit), VOLLEY_ERROR_NOT_COMMITTED, "volley_intersect1");
  volley_scene_destroy(scene);
  volley_scene_destroy(NULL);
  check(sizeof(volley_ray_packet16) == 576 && sizeof(volley_hit_packet4) == 128 && sizeof(volley_hit) == 24,
        "packet sizes", 0);
}

int main(void) {
  static const volley_isa isas[] = {VOLLEY_ISA_AUTO, VOLLEY_ISA_SCALAR, VOLLEY_ISA_SSE42, VOLLEY_ISA_AVX2,
                                    VOLLEY_ISA_AVX512};
  static const volley_triangle_test tests[] = {VOLLEY_TEST_WATERTIGHT, VOLLEY_TEST_PLANE, VOLLEY_TEST_MOLLER};
  size_t t, i;
  int robust;
  volley_commit_options options;
  for (t = 0; t < 3; ++t)
    for (i = 0; i < 5; ++i)
      for (robust = 1; robust >= 0; --robust) {
        volley_commit_options_default(&options);
        options.test = tests[t], options.isa = isas[i], options.robust = robust;
        check_scene(&options);
      }
  /* Spatial splits (the same answers). */
  for (t = 0; t < 3; ++t)
    for (i = 0; i < 5; ++i) {
      volley_commit_options_default(&options);
      options.test = tests[t], options.isa = isas[i], options.quality = VOLLEY_BUILD_QUALITY_HIGH;
      check_scene(&options);
    }
  /* The double-precision reference (scalar oracle). */
  for (t = 0; t < 3; ++t) {
    volley_commit_options_default(&options);
    options.test = tests[t], options.isa = VOLLEY_ISA_SCALAR, options.reference_double = 1;
    check_scene(&options);
  }
  check_validation();
  check_geometries();
  check_refit();
  check_save_load();
  check_masks();
  check_instances();
  check_queries();
  if (failures) {
    printf("consumer_c: %d failures\n", failures);
    return 1;
  }
  printf("consumer_c: all checks passed (volley %s)\n", volley_version());
  return 0;
}
