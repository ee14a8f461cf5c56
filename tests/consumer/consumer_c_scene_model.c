/* The C side of the consumer, the scene model: geometries, refit, save and load, ray masks,
 * instances (consumer_c.c has the rest and main). C99. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <volley/volley.h>

#include "consumer_c.h"
#include "scene.h"

/* The masked packets of 4 and 8: lane k masked 0x1 (the floor), 0x2 (the table) or 0
 * (nothing) by `masks`; every ray is `r`. */
#define CHECK_MASKED_PACKET(K)                                                                                  \
  {                                                                                                             \
    volley_ray_packet##K p;                                                                                     \
    volley_hit_packet##K h;                                                                                     \
    uint32_t blocked = 0;                                                                                       \
    int i;                                                                                                      \
    for (i = 0; i < K; ++i) {                                                                                   \
      p.ox[i] = r->org[0], p.oy[i] = r->org[1], p.oz[i] = r->org[2];                                            \
      p.dx[i] = r->dir[0], p.dy[i] = r->dir[1], p.dz[i] = r->dir[2];                                            \
      p.tmin[i] = r->tmin, p.tmax[i] = r->tmax;                                                                 \
    }                                                                                                           \
    p.active = (1u << K) - 1u;                                                                                  \
    volley_reset_hits##K(&h);                                                                                   \
    expect(volley_intersect##K##_masked(scene, &p, masks, &h), VOLLEY_OK, "volley_intersect" #K "_masked");     \
    expect(volley_occluded##K##_masked(scene, &p, masks, &blocked), VOLLEY_OK, "volley_occluded" #K "_masked"); \
    for (i = 0; i < K; ++i) {                                                                                   \
      const uint32_t want = masks[i] == 0x1u ? 0u : masks[i] == 0x2u ? 1u : VOLLEY_INVALID_ID;                  \
      check(h.geom[i] == want, "packet" #K " lane by its mask", i);                                             \
      check(((blocked >> i) & 1u) == (want != VOLLEY_INVALID_ID), "occluded packet" #K " lane by its mask", i); \
    }                                                                                                           \
  }

static void check_masked_packets4_8(const volley_scene* scene, const volley_ray* r, const uint32_t* masks) {
  CHECK_MASKED_PACKET(4)
  CHECK_MASKED_PACKET(8)
}

/* Masks: the table (geometry 1) masked 0x2; rays of mask 0x1 see the floor under it, rays
 * of mask 0x2 the table, in every masked form; mask 0 sees nothing. */
void check_masks(void) {
  volley_scene* scene = make_scene();
  volley_ray r = scene_ray(0);
  volley_hit h;
  int blocked = 7;
  uint32_t masks[16], blocked_lanes = 0;
  volley_ray rays[16];
  volley_hit hits[16];
  volley_scene_info info;
  volley_ray_packet16 packet;
  volley_hit_packet16 hit_packet;
  int k;
  r.org[0] = 0.5f, r.org[1] = 0.25f; /* over the table, which lies on the floor */
  expect(volley_scene_set_geometry_mask(scene, 1, 0x2u), VOLLEY_OK, "volley_scene_set_geometry_mask");
  expect(volley_scene_set_geometry_mask(scene, 7, 0x2u), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_set_geometry_mask");
  expect(volley_scene_set_geometry_mask(NULL, 1, 0x2u), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_set_geometry_mask");
  expect(volley_scene_commit(scene, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AUTO), VOLLEY_OK, "volley_scene_commit");
  expect(volley_scene_get_info(scene, &info), VOLLEY_OK, "volley_scene_get_info");
  check(info.layers == 2, "two masks, two layers", (int)info.layers);
  expect(volley_intersect1_masked(scene, &r, 0x1u, &h), VOLLEY_OK, "volley_intersect1_masked");
  check(h.geom == 0, "mask 0x1: the floor", (int)h.geom);
  expect(volley_intersect1_masked(scene, &r, 0x2u, &h), VOLLEY_OK, "volley_intersect1_masked");
  check(h.geom == 1, "mask 0x2: the table", (int)h.geom);
  expect(volley_intersect1(scene, &r, &h), VOLLEY_OK, "volley_intersect1");
  check(h.geom == 1, "no mask: the table", (int)h.geom);
  expect(volley_occluded1_masked(scene, &r, 0x0u, &blocked), VOLLEY_OK, "volley_occluded1_masked");
  check(blocked == 0, "mask 0 sees nothing", blocked);
  for (k = 0; k < 16; ++k) rays[k] = r, masks[k] = (k & 1) ? 0x2u : 0x1u;
  expect(volley_intersect_stream_masked(scene, rays, masks, 16, hits), VOLLEY_OK, "volley_intersect_stream_masked");
  for (k = 0; k < 16; ++k) check(hits[k].geom == ((k & 1) ? 1u : 0u), "stream lane by its mask", k);
  for (k = 0; k < 16; ++k) {
    packet.ox[k] = r.org[0], packet.oy[k] = r.org[1], packet.oz[k] = r.org[2];
    packet.dx[k] = r.dir[0], packet.dy[k] = r.dir[1], packet.dz[k] = r.dir[2];
    packet.tmin[k] = r.tmin, packet.tmax[k] = r.tmax;
    masks[k] = (k % 3 == 0) ? 0x0u : (k & 1) ? 0x2u : 0x1u;
  }
  packet.active = 0xffffu;
  volley_reset_hits16(&hit_packet);
  expect(volley_intersect16_masked(scene, &packet, masks, &hit_packet), VOLLEY_OK, "volley_intersect16_masked");
  for (k = 0; k < 16; ++k)
    check(hit_packet.geom[k] == ((k % 3 == 0) ? VOLLEY_INVALID_ID : (k & 1) ? 1u : 0u), "packet lane by its mask", k);
  expect(volley_occluded16_masked(scene, &packet, masks, &blocked_lanes), VOLLEY_OK, "volley_occluded16_masked");
  for (k = 0; k < 16; ++k) check(((blocked_lanes >> k) & 1u) == (k % 3 != 0), "occluded lane by its mask", k);
  check_masked_packets4_8(scene, &r, masks);
  {
    uint8_t blocked_rays[16];
    for (k = 0; k < 16; ++k) masks[k] = (k & 1) ? 0x2u : 0x0u;
    expect(volley_occluded_stream_masked(scene, rays, masks, 16, blocked_rays), VOLLEY_OK,
           "volley_occluded_stream_masked");
    for (k = 0; k < 16; ++k) check(blocked_rays[k] == (k & 1), "occluded stream ray by its mask", k);
  }
  expect(volley_intersect16_masked(scene, &packet, NULL, &hit_packet), VOLLEY_ERROR_INVALID_ARGUMENT,
         "volley_intersect16_masked");
  expect(volley_occluded_stream_masked(scene, rays, NULL, 16, (uint8_t*)hits), VOLLEY_ERROR_INVALID_ARGUMENT,
         "volley_occluded_stream_masked");
  volley_scene_destroy(scene);
}

/* Instances: the scene (floor, table, polygon) placed twice, 10 lower, and mirrored in x
 * about 5 and 20 lower; rays from above hit them with inst set, 10 and 20 further. */
void check_instances(void) {
  static const float down[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, -10};
  static const float mirrored[12] = {-1, 0, 0, 10, 0, 1, 0, 0, 0, 0, 1, -20};
  static const float singular[12] = {1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0};
  volley_scene* prototype = make_scene();
  volley_scene* world = NULL;
  volley_ray r = scene_ray(0);
  volley_hit h, direct;
  volley_scene_info info;
  uint32_t a = 99, b = 99;
  r.org[0] = 0.5f, r.org[1] = 0.25f; /* over the table */
  expect(volley_scene_create(&world), VOLLEY_OK, "volley_scene_create");
  expect(volley_scene_add_instance(world, prototype, down, &a), VOLLEY_ERROR_NOT_COMMITTED, "volley_scene_add_instance");
  expect(volley_scene_commit(prototype, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AUTO), VOLLEY_OK, "volley_scene_commit");
  expect(volley_intersect1(prototype, &r, &direct), VOLLEY_OK, "volley_intersect1");
  expect(volley_scene_add_instance(world, prototype, down, &a), VOLLEY_OK, "volley_scene_add_instance");
  expect(volley_scene_add_instance(world, prototype, mirrored, &b), VOLLEY_OK, "volley_scene_add_instance");
  check(a == 0 && b == 1, "instance ids", (int)b);
  expect(volley_scene_add_instance(world, prototype, singular, NULL), VOLLEY_ERROR_INVALID_ARGUMENT,
         "volley_scene_add_instance");
  expect(volley_scene_add_instance(world, world, down, NULL), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_add_instance");
  expect(volley_scene_add_instance(world, prototype, NULL, NULL), VOLLEY_ERROR_INVALID_ARGUMENT,
         "volley_scene_add_instance");
  volley_scene_destroy(prototype); /* the instances keep its structure */
  expect(volley_scene_commit(world, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AUTO), VOLLEY_OK, "volley_scene_commit");
  expect(volley_scene_get_info(world, &info), VOLLEY_OK, "volley_scene_get_info");
  check(info.instances == 2 && info.instanced_triangles == 8, "info: 2 instances of 4 triangles", (int)info.instances);
  expect(volley_intersect1(world, &r, &h), VOLLEY_OK, "volley_intersect1");
  check(h.inst == a && h.geom == direct.geom && h.prim == direct.prim && scene_t_close(h.t, direct.t + 10.0f),
        "the hit through the first instance", (int)h.inst);
  r.org[0] = 9.5f; /* over the mirrored table (x -> 10 - x), 20 below */
  expect(volley_intersect1(world, &r, &h), VOLLEY_OK, "volley_intersect1");
  check(h.inst == b && h.geom == direct.geom && scene_t_close(h.t, direct.t + 20.0f), "the mirrored instance",
        (int)h.inst);
  volley_scene_destroy(world);
}

/* Save and load: a loaded scene answers every ray bit for bit as the saved one, at every
 * ISA this CPU has; it reports itself loaded; bad paths and files fail with
 * VOLLEY_ERROR_FILE and leave *out alone. */
void check_save_load(void) {
  static const volley_isa isas[] = {VOLLEY_ISA_SCALAR, VOLLEY_ISA_SSE42, VOLLEY_ISA_AVX2, VOLLEY_ISA_AVX512};
  const char* path = "consumer_c_scene.vacc";
  volley_scene *scene, *loaded = NULL, *untouched = (volley_scene*)&failures;
  volley_scene_info info;
  volley_hit a, b;
  size_t i;
  int k;
  FILE* junk;
  for (i = 0; i < 4; ++i) {
    if (!volley_isa_supported(isas[i])) continue;
    scene = make_scene();
    expect(volley_scene_save(scene, path), VOLLEY_ERROR_NOT_COMMITTED, "volley_scene_save");
    expect(volley_scene_commit(scene, VOLLEY_TEST_WATERTIGHT, isas[i]), VOLLEY_OK, "volley_scene_commit");
    expect(volley_scene_save(scene, path), VOLLEY_OK, "volley_scene_save");
    expect(volley_scene_load(path, &loaded), VOLLEY_OK, "volley_scene_load");
    expect(volley_scene_get_info(loaded, &info), VOLLEY_OK, "volley_scene_get_info");
    check(info.loaded == 1 && info.isa == isas[i] && info.geometries == 3, "loaded scene info", (int)i);
    for (k = 0; k < SCENE_RAYS; k += 7) {
      volley_ray r = scene_ray(k);
      expect(volley_intersect1(scene, &r, &a), VOLLEY_OK, "volley_intersect1");
      expect(volley_intersect1(loaded, &r, &b), VOLLEY_OK, "volley_intersect1");
      check(memcmp(&a, &b, sizeof a) == 0, "loaded scene: same hit", k);
    }
    /* A loaded scene changes like any: the table disabled, committed again. */
    expect(volley_scene_disable_geometry(loaded, 1), VOLLEY_OK, "volley_scene_disable_geometry");
    expect(volley_scene_commit(loaded, VOLLEY_TEST_WATERTIGHT, isas[i]), VOLLEY_OK, "volley_scene_commit");
    expect(volley_scene_get_info(loaded, &info), VOLLEY_OK, "volley_scene_get_info");
    check(info.loaded == 0 && info.disabled == 1, "loaded scene committed again", (int)i);
    volley_scene_destroy(loaded);
    expect(volley_scene_save(NULL, path), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_save");
    expect(volley_scene_save(scene, NULL), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_save");
    expect(volley_scene_save(scene, "no_such_folder/x.vacc"), VOLLEY_ERROR_FILE, "volley_scene_save");
    volley_scene_destroy(scene);
  }
  expect(volley_scene_load(NULL, &loaded), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_load");
  expect(volley_scene_load(path, NULL), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_load");
  expect(volley_scene_load("no_such_file.vacc", &untouched), VOLLEY_ERROR_FILE, "volley_scene_load");
  check(untouched == (volley_scene*)&failures, "a failed load leaves *out alone", 0);
  junk = fopen(path, "wb");
  if (junk) {
    fputs("not a structure", junk);
    fclose(junk);
  }
  expect(volley_scene_load(path, &untouched), VOLLEY_ERROR_FILE, "volley_scene_load");
  check(strstr(volley_last_error(), "not a volley structure file") != NULL, "the message says why", 0);
  remove(path);
}

/* Commits the scene (watertight, the default ISA) and traces one ray, both expected to succeed. */
static void commit_and_intersect(volley_scene* scene, const volley_ray* r, volley_hit* h) {
  expect(volley_scene_commit(scene, VOLLEY_TEST_WATERTIGHT, VOLLEY_ISA_AUTO), VOLLEY_OK, "volley_scene_commit");
  expect(volley_intersect1(scene, r, h), VOLLEY_OK, "volley_intersect1");
}

/* Geometries: a disabled one is left out from the next commit until it is enabled again;
 * ids no add call returned are argument errors. */
void check_geometries(void) {
  volley_scene* scene = make_scene();
  volley_ray r = scene_ray(0);
  volley_hit h;
  volley_scene_info info;
  r.org[0] = 0.5f, r.org[1] = 0.25f; /* over the table (geometry 1), which lies on the floor (0) */
  commit_and_intersect(scene, &r, &h);
  check(h.geom == 1 && h.prim == 0 && h.inst == VOLLEY_INVALID_ID, "hit on the table", (int)h.geom);
  expect(volley_scene_disable_geometry(scene, 1), VOLLEY_OK, "volley_scene_disable_geometry");
  expect(volley_intersect1(scene, &r, &h), VOLLEY_ERROR_NOT_COMMITTED, "volley_intersect1");
  commit_and_intersect(scene, &r, &h);
  check(h.geom == 0 && h.prim == 0, "the table disabled: the floor", (int)h.geom);
  expect(volley_scene_get_info(scene, &info), VOLLEY_OK, "volley_scene_get_info");
  check(info.geometries == 3 && info.disabled == 1, "info: 3 geometries, 1 disabled", (int)info.disabled);
  expect(volley_scene_enable_geometry(scene, 1), VOLLEY_OK, "volley_scene_enable_geometry");
  commit_and_intersect(scene, &r, &h);
  check(h.geom == 1, "the table enabled again", (int)h.geom);
  expect(volley_scene_disable_geometry(scene, 3), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_disable_geometry");
  expect(volley_scene_enable_geometry(scene, VOLLEY_INVALID_ID), VOLLEY_ERROR_INVALID_ARGUMENT,
         "volley_scene_enable_geometry");
  expect(volley_scene_disable_geometry(NULL, 0), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_disable_geometry");
  expect(volley_scene_enable_geometry(NULL, 0), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_enable_geometry");
  volley_scene_destroy(scene);
}

/* Refit: the floor moved up by 0.5 after a commit; the next commit refits and the rays
 * see the floor there. Bad updates are rejected and change nothing. */
void check_refit(void) {
  volley_scene* scene = make_scene();
  volley_ray r = scene_ray(0);
  volley_hit h;
  volley_scene_info info;
  volley_commit_options options;
  float moved[12], bad[12];
  int k;
  for (k = 0; k < 12; ++k) moved[k] = kFloorXyz[k] + (k % 3 == 2 ? 0.5f : 0.0f), bad[k] = moved[k];
  bad[4] = NAN;
  r.org[0] = 1.5f, r.org[1] = 1.5f; /* over the floor only */
  volley_commit_options_default(&options);
  check(options.refit == 1, "refit is the default", 0);
  expect(volley_scene_commit_ex(scene, &options), VOLLEY_OK, "volley_scene_commit_ex");
  expect(volley_intersect1(scene, &r, &h), VOLLEY_OK, "volley_intersect1");
  check(h.geom == 0 && scene_t_close(h.t, 5.0f), "the floor before", (int)h.geom);
  expect(volley_scene_update_vertices(scene, 0, moved, 4), VOLLEY_OK, "volley_scene_update_vertices");
  expect(volley_intersect1(scene, &r, &h), VOLLEY_ERROR_NOT_COMMITTED, "volley_intersect1");
  expect(volley_scene_commit_ex(scene, &options), VOLLEY_OK, "volley_scene_commit_ex");
  expect(volley_scene_get_info(scene, &info), VOLLEY_OK, "volley_scene_get_info");
  check(info.refitted == 1 && info.sah_growth > 0.5, "the commit refitted", info.refitted);
  expect(volley_intersect1(scene, &r, &h), VOLLEY_OK, "volley_intersect1");
  check(h.geom == 0 && scene_t_close(h.t, 4.5f), "the floor moved up", (int)(h.t * 100));
  expect(volley_scene_update_vertices(scene, 0, moved, 3), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_update_vertices");
  expect(volley_scene_update_vertices(scene, 2, moved, 4), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_update_vertices");
  expect(volley_scene_update_vertices(scene, 9, moved, 4), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_update_vertices");
  expect(volley_scene_update_vertices(scene, 0, bad, 4), VOLLEY_ERROR_INVALID_GEOMETRY, "volley_scene_update_vertices");
  expect(volley_scene_update_vertices(scene, 0, NULL, 4), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_update_vertices");
  expect(volley_scene_update_vertices(NULL, 0, moved, 4), VOLLEY_ERROR_INVALID_ARGUMENT, "volley_scene_update_vertices");
  expect(volley_intersect1(scene, &r, &h), VOLLEY_OK, "volley_intersect1"); /* still committed */
  options.refit = 0;
  expect(volley_scene_update_vertices(scene, 0, kFloorXyz, 4), VOLLEY_OK, "volley_scene_update_vertices");
  expect(volley_scene_commit_ex(scene, &options), VOLLEY_OK, "volley_scene_commit_ex");
  expect(volley_scene_get_info(scene, &info), VOLLEY_OK, "volley_scene_get_info");
  check(info.refitted == 0, "refit = 0 rebuilds", info.refitted);
  volley_scene_destroy(scene);
}
