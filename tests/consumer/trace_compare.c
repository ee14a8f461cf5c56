/* trace_compare: traces a ray file through the C API in every query mode and compares
 * the answers, bit for bit, with a hit file written by `volley trace`.
 *
 *   trace_compare MESH.obj RAYS.vray HITS.vhit [--occluded] [--test T] [--isa I]
 *
 * MESH is read here (v and f lines; faces fan-triangulated in file order, as volley does),
 * so the scene the C API builds is the one `volley trace MESH` builds. T and I take the
 * names of volley's --test and --isa (default watertight, auto: those of volley trace).
 * With --occluded the hit file holds occlusion records (t = 0, prim = 0 when blocked).
 * Exit status 0 when single rays, packets of 4, 8 and 16 and streams all equal the file. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <volley/volley.h>

static void die(const char* what, const char* detail) {
  fprintf(stderr, "trace_compare: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
  exit(2);
}

static void* grow(void* p, size_t* capacity, size_t needed, size_t size) {
  if (needed <= *capacity) return p;
  *capacity = needed * 2;
  p = realloc(p, *capacity * size);
  if (!p) die("out of memory", NULL);
  return p;
}

/* Vertices and fan-triangulated faces of an OBJ file (positive or negative indices,
 * v, v/vt, v//vn, v/vt/vn corners). */
static void read_obj(const char* file, float** xyz, size_t* nv, uint32_t** indices, size_t* nt) {
  char line[4096];
  size_t vcap = 0, icap = 0;
  FILE* f = fopen(file, "r");
  if (!f) die("cannot open", file);
  *xyz = NULL, *indices = NULL, *nv = 0, *nt = 0;
  while (fgets(line, sizeof line, f)) {
    if (line[0] == 'v' && line[1] == ' ') {
      *xyz = (float*)grow(*xyz, &vcap, 3 * (*nv + 1), sizeof(float));
      if (sscanf(line + 2, "%f %f %f", &(*xyz)[3 * *nv], &(*xyz)[3 * *nv + 1], &(*xyz)[3 * *nv + 2]) != 3)
        die("bad vertex line", line);
      ++*nv;
    } else if (line[0] == 'f' && line[1] == ' ') {
      long corner[256];
      int n = 0, k;
      char* p = line + 2;
      char* end;
      for (;;) {
        long idx = strtol(p, &end, 10);
        if (end == p) break;
        if (n == 256) die("face with too many corners", line);
        corner[n++] = idx < 0 ? (long)*nv + idx : idx - 1;
        p = end;
        while (*p && *p != ' ' && *p != '\t') ++p; /* skip /vt/vn */
      }
      if (n < 3) die("face with fewer than 3 corners", line);
      for (k = 1; k + 1 < n; ++k) {
        *indices = (uint32_t*)grow(*indices, &icap, 3 * (*nt + 1), sizeof(uint32_t));
        (*indices)[3 * *nt] = (uint32_t)corner[0];
        (*indices)[3 * *nt + 1] = (uint32_t)corner[k];
        (*indices)[3 * *nt + 2] = (uint32_t)corner[k + 1];
        ++*nt;
      }
    }
  }
  fclose(f);
}

/* Records of a .vray or .vhit file: 4-byte magic, u32 version (.vray 1, .vhit 2), u64
 * count, records. */
static void* read_records(const char* file, const char* magic, uint32_t want_version, size_t record_bytes,
                          size_t* count) {
  unsigned char header[16];
  uint64_t n;
  uint32_t version;
  void* data;
  FILE* f = fopen(file, "rb");
  if (!f) die("cannot open", file);
  if (fread(header, 1, 16, f) != 16 || memcmp(header, magic, 4) != 0) die("not a volley ray/hit file", file);
  memcpy(&version, header + 4, 4);
  memcpy(&n, header + 8, 8);
  if (version != want_version) die("unknown version", file);
  data = malloc(n ? n * record_bytes : 1);
  if (!data || fread(data, record_bytes, n, f) != n) die("truncated file", file);
  fclose(f);
  *count = (size_t)n;
  return data;
}

static int mismatches = 0;

static void compare(const char* mode, size_t i, const volley_hit* got, const volley_hit* expected) {
  if (memcmp(got, expected, sizeof *got) == 0) return;
  if (++mismatches <= 10)
    printf("%s ray %zu: t %.9g u %.9g v %.9g prim %u geom %u, volley trace: t %.9g u %.9g v %.9g prim %u geom %u\n",
           mode, i, got->t, got->u, got->v, got->prim, got->geom, expected->t, expected->u, expected->v, expected->prim,
           expected->geom);
}

/* The .vhit record of an occlusion answer (as volley trace --occluded writes it). */
static volley_hit occlusion_record(int blocked) {
  volley_hit h = {INFINITY, 0.0f, 0.0f, VOLLEY_INVALID_PRIM, VOLLEY_INVALID_ID, VOLLEY_INVALID_ID};
  if (blocked) h.t = 0.0f, h.prim = 0, h.geom = 0;
  return h;
}

#define TRACE_PACKETS(K)                                                                              \
  static void trace_packets##K(const volley_scene* scene, const volley_ray* rays, size_t count,       \
                               int occluded, const volley_hit* expected) {                           \
    volley_ray_packet##K packet;                                                                      \
    volley_hit_packet##K hits;                                                                        \
    size_t i;                                                                                         \
    int l;                                                                                            \
    for (i = 0; i < count; i += K) {                                                                  \
      const int n = count - i < K ? (int)(count - i) : K;                                            \
      uint32_t blocked = 0;                                                                           \
      memset(&packet, 0, sizeof packet);                                                              \
      for (l = 0; l < n; ++l) {                                                                       \
        const volley_ray* r = &rays[i + l];                                                           \
        packet.ox[l] = r->org[0], packet.oy[l] = r->org[1], packet.oz[l] = r->org[2];                 \
        packet.dx[l] = r->dir[0], packet.dy[l] = r->dir[1], packet.dz[l] = r->dir[2];                 \
        packet.tmin[l] = r->tmin, packet.tmax[l] = r->tmax;                                           \
        packet.active |= 1u << l;                                                                     \
      }                                                                                               \
      volley_reset_hits##K(&hits);                                                                    \
      if ((occluded ? volley_occluded##K(scene, &packet, &blocked)                                    \
                    : volley_intersect##K(scene, &packet, &hits)) != VOLLEY_OK)                       \
        die(volley_last_error(), NULL);                                                               \
      for (l = 0; l < n; ++l) {                                                                       \
        volley_hit h = occlusion_record((blocked >> l) & 1u);                                         \
        if (!occluded) h.t = hits.t[l], h.u = hits.u[l], h.v = hits.v[l], h.prim = hits.prim[l],      \
                       h.geom = hits.geom[l], h.inst = hits.inst[l];                                  \
        compare("packet" #K, i + l, &h, &expected[i + l]);                                            \
      }                                                                                               \
    }                                                                                                 \
  }
TRACE_PACKETS(4)
TRACE_PACKETS(8)
TRACE_PACKETS(16)

static int parse_name(const char* name, const char* const* names, int count, const char* what) {
  int i;
  for (i = 0; i < count; ++i)
    if (strcmp(name, names[i]) == 0) return i;
  die(what, name);
  return 0;
}

int main(int argc, char** argv) {
  static const char* const tests[] = {"watertight", "plane", "moller"};
  static const char* const isas[] = {"auto", "scalar", "sse4.2", "avx2", "avx512"};
  volley_triangle_test test = VOLLEY_TEST_WATERTIGHT;
  volley_isa isa = VOLLEY_ISA_AUTO;
  int occluded = 0, a;
  float* xyz;
  uint32_t* indices;
  size_t nv, nt, nrays, nhits, i;
  volley_ray* rays;
  volley_hit *expected, *stream;
  uint8_t* blocked;
  volley_scene* scene;
  volley_scene_info info;

  if (argc < 4) die("usage: trace_compare MESH.obj RAYS.vray HITS.vhit [--occluded] [--test T] [--isa I]", NULL);
  for (a = 4; a < argc; ++a) {
    if (strcmp(argv[a], "--occluded") == 0) occluded = 1;
    else if (strcmp(argv[a], "--test") == 0 && a + 1 < argc) test = (volley_triangle_test)parse_name(argv[++a], tests, 3, "unknown test");
    else if (strcmp(argv[a], "--isa") == 0 && a + 1 < argc) isa = (volley_isa)parse_name(argv[++a], isas, 5, "unknown ISA");
    else die("unknown argument", argv[a]);
  }
  read_obj(argv[1], &xyz, &nv, &indices, &nt);
  rays = (volley_ray*)read_records(argv[2], "VRAY", 1, sizeof(volley_ray), &nrays);
  expected = (volley_hit*)read_records(argv[3], "VHIT", 2, sizeof(volley_hit), &nhits);
  if (nrays != nhits) die("the ray and hit files differ in length", NULL);

  if (volley_scene_create(&scene) != VOLLEY_OK || volley_scene_add_triangles(scene, xyz, nv, indices, nt, NULL) != VOLLEY_OK ||
      volley_scene_commit(scene, test, isa) != VOLLEY_OK || volley_scene_get_info(scene, &info) != VOLLEY_OK)
    die(volley_last_error(), NULL);

  for (i = 0; i < nrays; ++i) { /* single rays */
    volley_hit h;
    int b = 0;
    if ((occluded ? volley_occluded1(scene, &rays[i], &b) : volley_intersect1(scene, &rays[i], &h)) != VOLLEY_OK)
      die(volley_last_error(), NULL);
    if (occluded) h = occlusion_record(b);
    compare("single", i, &h, &expected[i]);
  }
  trace_packets4(scene, rays, nrays, occluded, expected);
  trace_packets8(scene, rays, nrays, occluded, expected);
  trace_packets16(scene, rays, nrays, occluded, expected);
  stream = (volley_hit*)malloc((nrays ? nrays : 1) * sizeof *stream);
  blocked = (uint8_t*)malloc(nrays ? nrays : 1);
  if (!stream || !blocked) die("out of memory", NULL);
  if ((occluded ? volley_occluded_stream(scene, rays, nrays, blocked) : volley_intersect_stream(scene, rays, nrays, stream)) !=
      VOLLEY_OK)
    die(volley_last_error(), NULL);
  for (i = 0; i < nrays; ++i) {
    if (occluded) stream[i] = occlusion_record(blocked[i]);
    compare("stream", i, &stream[i], &expected[i]);
  }

  {
    size_t answered = 0;
    for (i = 0; i < nrays; ++i) answered += expected[i].prim != VOLLEY_INVALID_PRIM;
    printf("%s: %zu triangles, %zu rays (%zu %s), %s/%s: ", argv[2], nt, nrays, answered,
           occluded ? "blocked" : "hit", tests[info.test], isas[info.isa]);
    if (mismatches) printf("%d answers differ from volley trace\n", mismatches);
    else printf("single, packet4/8/16 and stream equal volley trace\n");
  }
  volley_scene_destroy(scene);
  free(xyz), free(indices), free(rays), free(expected), free(stream), free(blocked);
  return mismatches ? 1 : 0;
}
