/* volley public C API (C99; also valid C++): build a scene of triangles and planar
 * polygons, commit it, then ask for closest hits and occlusion of single rays, SoA ray
 * packets of 4, 8 or 16 lanes, and ray streams. For C programs and for foreign-function
 * interfaces (Python ctypes/cffi, Rust, Julia, ...); C++ programs may use it or the C++
 * API in volley/accel.h, which it wraps (same kernels, same answers).
 *
 * Conventions, for every function below:
 * - Every function that can fail returns a volley_status; VOLLEY_OK (0) is success.
 *   On failure a message naming the function and the problem is kept for the calling
 *   thread: volley_last_error(). No C++ exception ever leaves the library.
 * - A call rejected for its input changes nothing: the scene is left as it was and output
 *   arguments are not written. After VOLLEY_ERROR_OUT_OF_MEMORY or VOLLEY_ERROR_INTERNAL
 *   the scene may hold part of the call's work: destroy it.
 * - Thread safety: one thread at a time may create, add to, commit or destroy a scene.
 *   Once committed, a scene is read-only; any number of threads may query it at once
 *   (intersect / occluded / info), as long as nobody adds to, commits or destroys it.
 * - Rays: r(t) = org + t * dir over tmin <= t < tmax. dir need not be normalized; t is in
 *   units of |dir|. A ray with a non-finite origin or direction component, a NaN tmin or
 *   tmax, tmin >= tmax, or a zero direction (dx = dy = dz = 0) is answered as a miss
 *   (never hit, never occluded); this is not an error. volley_validate_rays reports such
 *   rays for callers who want to know.
 * - Geometries: every volley_scene_add_triangles / volley_scene_add_polygon call creates
 *   a geometry, numbered 0, 1, 2, ... in order of addition. A hit reports the geometry in
 *   `geom` and the primitive's index within it in `prim` (triangle i of the call; 0 for a
 *   polygon), as Embree's geomID and primID; a miss has prim = VOLLEY_INVALID_PRIM and
 *   geom = VOLLEY_INVALID_ID. `inst` is VOLLEY_INVALID_ID for a hit not made through an
 *   instance. */
#ifndef VOLLEY_VOLLEY_H
#define VOLLEY_VOLLEY_H

#include <stddef.h>
#include <stdint.h>

#include "volley/export.h"
/* The constants, enumerations and structs of the API. */
#include "volley/volley_types.h"

#ifdef __cplusplus
extern "C" {
#endif

/** Version of these headers (and of the library they came with): major.minor.patch.
 *  volley_version() returns the version of the library actually loaded. */
#define VOLLEY_VERSION_MAJOR 0
#define VOLLEY_VERSION_MINOR 1   /**< see VOLLEY_VERSION_MAJOR */
#define VOLLEY_VERSION_PATCH 0   /**< see VOLLEY_VERSION_MAJOR */

/** The library's version, "major.minor.patch". Static storage; never fails. */
VOLLEY_API const char* volley_version(void);

/** The message of the most recent failing call made by this thread ("" when none has
 *  failed). The pointer stays valid until this thread's next failing call; a successful
 *  call leaves the message as it was (as errno does). */
VOLLEY_API const char* volley_last_error(void);

/** The name of a status ("VOLLEY_ERROR_MISALIGNED", ...); "unknown status" for a value
 *  outside the enum. Static storage; never fails. */
VOLLEY_API const char* volley_status_string(volley_status status);

/** 1 when this CPU (and OS) can run `isa`, else 0. VOLLEY_ISA_AUTO and VOLLEY_ISA_SCALAR
 *  are always supported; a value outside the enum is not. */
VOLLEY_API int volley_isa_supported(volley_isa isa);

/** Creates an empty scene in *out (the caller owns it: volley_scene_destroy).
 *  VOLLEY_ERROR_INVALID_ARGUMENT when out is NULL. */
VOLLEY_API volley_status volley_scene_create(volley_scene** out);

/** Frees a scene and everything it holds. NULL is allowed (nothing happens). No query on
 *  the scene may be running. */
VOLLEY_API void volley_scene_destroy(volley_scene* scene);

/** Adds an indexed triangle mesh as a new geometry and copies it: the caller may free or
 *  reuse `xyz` and `indices` as soon as the call returns. `xyz` holds 3 * vertex_count
 *  floats (x, y, z of each vertex), `indices` 3 * triangle_count vertex indices
 *  (0-based). The geometry's id is stored in *geometry when geometry is not NULL; a hit on
 *  its triangle i reports geom = that id and prim = i. Zero-area triangles are accepted
 *  and never hit. The scene must be committed again before the next query.
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT for a NULL scene, a NULL array with a non-zero
 *  count, or more primitives than prim ids (2^32 - 1 in all);
 *  VOLLEY_ERROR_INVALID_GEOMETRY for a NaN or infinite coordinate (of any vertex, used
 *  or not) or an index >= vertex_count. Nothing is added on error. */
VOLLEY_API volley_status volley_scene_add_triangles(volley_scene* scene, const float* xyz, size_t vertex_count,
                                                    const uint32_t* indices, size_t triangle_count,
                                                    uint32_t* geometry);

/** Adds one planar polygon (convex or concave, vertex_count >= 3 vertices in order around
 *  its boundary, 3 * vertex_count floats) as a new geometry and copies it. The geometry's
 *  id is stored in *geometry when geometry is not NULL. Hits on polygons report prim = 0
 *  and u = v = 0.
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT for a NULL scene or xyz, or too many
 *  primitives; VOLLEY_ERROR_INVALID_GEOMETRY for fewer than 3 vertices, a non-finite
 *  coordinate, a polygon that is not planar (within 1e-4 of its size) or has zero area.
 *  Nothing is added on error. */
VOLLEY_API volley_status volley_scene_add_polygon(volley_scene* scene, const float* xyz, size_t vertex_count,
                                                  uint32_t* geometry);

/** Leaves a geometry out of the scene from the next commit on (as Embree's
 *  rtcDisableGeometry): nothing of it is hit. Its data stays; volley_scene_enable_geometry
 *  brings it back. The scene must be committed again before the next query.
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT for a NULL scene or an id no add call returned. */
VOLLEY_API volley_status volley_scene_disable_geometry(volley_scene* scene, uint32_t geometry);

/** Moves the vertices of a triangle geometry: xyz holds 3 * vertex_count floats, the same
 *  vertex_count as its volley_scene_add_triangles call; its triangles keep their indices.
 *  Copied. The next commit refits the BVH instead of building it when nothing else changed
 *  (volley_commit_options.refit); the scene must be committed again before the next query.
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT for a NULL scene or xyz, an id no
 *  volley_scene_add_triangles call returned, or another vertex count;
 *  VOLLEY_ERROR_INVALID_GEOMETRY for a non-finite coordinate. Nothing changes on error. */
VOLLEY_API volley_status volley_scene_update_vertices(volley_scene* scene, uint32_t geometry, const float* xyz,
                                                      size_t vertex_count);

/** Brings a disabled geometry back from the next commit on (nothing changes for an
 *  enabled one, but the scene must still be committed again).
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT for a NULL scene or an id no add call returned. */
VOLLEY_API volley_status volley_scene_enable_geometry(volley_scene* scene, uint32_t geometry);

/** Places the committed scene `prototype` in `scene` under an affine transform as a new
 *  geometry (volley::Accel::add_instance; Embree's instance geometry): transform holds 12
 *  floats, the 3x4 matrix [A | t] row by row (x' = A x + t). Hits through it report
 *  inst = its id (stored in *geometry when not NULL) and geom, prim as in the prototype.
 *  The prototype's structure is shared, not copied, and stays alive while an instance
 *  needs it (volley_scene_destroy of the prototype is allowed); commit `scene` again
 *  after changing and committing the prototype. One level: a prototype holding instances
 *  is refused. The scene must be committed again before the next query.
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT for a NULL scene, prototype or transform, the
 *  scene itself as prototype, a prototype with instances, a non-finite or singular
 *  transform; VOLLEY_ERROR_NOT_COMMITTED when the prototype is not committed. */
VOLLEY_API volley_status volley_scene_add_instance(volley_scene* scene, const volley_scene* prototype,
                                                   const float* transform, uint32_t* geometry);

/** Sets a geometry's 32-bit mask (volley::Accel::set_geometry_mask; default
 *  VOLLEY_MASK_ALL): the masked queries see it only when their mask shares a bit with it.
 *  Geometries of one mask share a BVH; a scene that sets none keeps one. The scene must
 *  be committed again before the next query.
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT for a NULL scene or an id no add call returned. */
VOLLEY_API volley_status volley_scene_set_geometry_mask(volley_scene* scene, uint32_t geometry, uint32_t mask);

/** Builds the acceleration structure with the given test and ISA (VOLLEY_TEST_WATERTIGHT
 *  and VOLLEY_ISA_AUTO are the defaults of volley trace and volley render). May be called
 *  again after adding more geometry; an empty scene commits (and every ray misses).
 *  Uses oneTBB worker threads.
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT for a NULL scene or an enum value out of range;
 *  VOLLEY_ERROR_UNSUPPORTED_ISA when this CPU lacks `isa` (or, for VOLLEY_ISA_AUTO, when
 *  the VOLLEY_ISA environment variable names a bad or unsupported ISA); the scene is
 *  then unchanged (and still committed if it was). */
VOLLEY_API volley_status volley_scene_commit(volley_scene* scene, volley_triangle_test test, volley_isa isa);

/** Writes the committed scene's structure to `path` (volley::Accel::save): the BVH and
 *  triangle blocks as built, the geometries with their vertices, indices and flags, the
 *  options, the test and ISA, a format version and a checksum. Written to `path`.tmp first
 *  and then renamed: a failed save leaves no partial file at `path`.
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT for a NULL scene or path; VOLLEY_ERROR_NOT_COMMITTED;
 *  VOLLEY_ERROR_FILE when the file cannot be written. */
VOLLEY_API volley_status volley_scene_save(const volley_scene* scene, const char* path);

/** Creates in *out a committed scene mapped from a file volley_scene_save wrote
 *  (volley::Accel::load): ready to query with the same answers as the scene saved, without
 *  a build (the BVH is queried where it lies in the mapped file). It can be changed and
 *  committed again like any scene. The caller owns it (volley_scene_destroy).
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT for a NULL path or out; VOLLEY_ERROR_FILE for a
 *  file that is missing, not a volley structure, of another format version, truncated,
 *  corrupted (checksum), inconsistent, or built for an ISA this CPU lacks;
 *  VOLLEY_ERROR_OUT_OF_MEMORY. *out is left as it was on error. */
VOLLEY_API volley_status volley_scene_load(const char* path, volley_scene** out);

/** Everything volley_scene_commit_ex can set (volley::Options). Fill it with
 *  volley_commit_options_default first, then change what you need: fields may be added at
 *  the end in later versions, and the default function fills them all. */
typedef struct volley_commit_options {
  volley_triangle_test test; /**< default VOLLEY_TEST_WATERTIGHT */
  volley_isa isa;            /**< default VOLLEY_ISA_AUTO */
  int robust;                /**< nonzero (default): box tests padded against rounding, so the watertight
                                  test stays watertight through the whole BVH; 0: plain box tests (faster) */
  int reference_double;      /**< nonzero: the scalar oracle with triangle tests in double precision (the
                                  accuracy reference); needs VOLLEY_ISA_SCALAR and robust; default 0 */
  int refit;                 /**< nonzero (default): after volley_scene_update_vertices with nothing else
                                  changed, refit the BVH instead of building it (volley::Options::refit) */
  volley_build_quality quality; /**< default VOLLEY_BUILD_QUALITY_MEDIUM */
} volley_commit_options;

/** The defaults of volley_commit_options (those of volley_scene_commit). NULL is ignored. */
VOLLEY_API void volley_commit_options_default(volley_commit_options* options);

/** volley_scene_commit with every option. Errors as volley_scene_commit, and
 *  VOLLEY_ERROR_INVALID_ARGUMENT for a NULL options or reference_double with another ISA
 *  than VOLLEY_ISA_SCALAR or with robust = 0. */
VOLLEY_API volley_status volley_scene_commit_ex(volley_scene* scene, const volley_commit_options* options);

/** Facts about the committed scene, stored in *info.
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT (NULL argument), VOLLEY_ERROR_NOT_COMMITTED. */
VOLLEY_API volley_status volley_scene_get_info(const volley_scene* scene, volley_scene_info* info);

/** Closest hit of one ray, stored in *hit (a miss when nothing is hit; see the ray
 *  conventions above).
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT (NULL argument), VOLLEY_ERROR_NOT_COMMITTED. */
VOLLEY_API volley_status volley_intersect1(const volley_scene* scene, const volley_ray* ray, volley_hit* hit);

/** Occlusion of one ray: *occluded = 1 when anything lies at tmin <= t < tmax, else 0.
 *  Errors: as volley_intersect1. */
VOLLEY_API volley_status volley_occluded1(const volley_scene* scene, const volley_ray* ray, int* occluded);

/** Closest hits of the active lanes of a packet of 4. Lane i searches
 *  tmin <= t < min(tmax, hits->t[i]) and writes lane i of *hits only when it finds a
 *  nearer hit: reset the hits first (volley_reset_hits4), or keep earlier answers to
 *  bound the search. Inactive lanes of *hits are never written. Same answers as
 *  volley_intersect1 per lane.
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT (NULL argument), VOLLEY_ERROR_MISALIGNED (rays
 *  or hits not 64-byte aligned), VOLLEY_ERROR_NOT_COMMITTED. */
VOLLEY_API volley_status volley_intersect4(const volley_scene* scene, const volley_ray_packet4* rays,
                                           volley_hit_packet4* hits);
/** As volley_intersect4 for 8 lanes. */
VOLLEY_API volley_status volley_intersect8(const volley_scene* scene, const volley_ray_packet8* rays,
                                           volley_hit_packet8* hits);
/** As volley_intersect4 for 16 lanes. */
VOLLEY_API volley_status volley_intersect16(const volley_scene* scene, const volley_ray_packet16* rays,
                                            volley_hit_packet16* hits);

/** Occlusion of the active lanes of a packet of 4: *occluded gets bit i set when lane i
 *  is active and blocked (tmin <= t < tmax); other bits are 0.
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT (NULL argument), VOLLEY_ERROR_MISALIGNED (rays
 *  not 64-byte aligned), VOLLEY_ERROR_NOT_COMMITTED. */
VOLLEY_API volley_status volley_occluded4(const volley_scene* scene, const volley_ray_packet4* rays,
                                          uint32_t* occluded);
/** As volley_occluded4 for 8 lanes. */
VOLLEY_API volley_status volley_occluded8(const volley_scene* scene, const volley_ray_packet8* rays,
                                          uint32_t* occluded);
/** As volley_occluded4 for 16 lanes. */
VOLLEY_API volley_status volley_occluded16(const volley_scene* scene, const volley_ray_packet16* rays,
                                           uint32_t* occluded);

/** Sets every lane of *hits to "no hit yet" (t = +inf, u = v = 0, prim =
 *  VOLLEY_INVALID_PRIM). Needs no alignment; does nothing for NULL. */
VOLLEY_API void volley_reset_hits4(volley_hit_packet4* hits);
/** As volley_reset_hits4 for 8 lanes. */
VOLLEY_API void volley_reset_hits8(volley_hit_packet8* hits);
/** As volley_reset_hits4 for 16 lanes. */
VOLLEY_API void volley_reset_hits16(volley_hit_packet16* hits);

/** Closest hits of `count` rays: hits[i] answers rays[i]; every entry is written (a miss
 *  where nothing is hit). The library regroups coherent runs of rays into packets; the
 *  answers equal volley_intersect1 per ray. No alignment needed. count = 0 does nothing
 *  (and the arrays may then be NULL). Should a call fail after it started tracing (out
 *  of memory), hits may be partly written.
 *  Errors: VOLLEY_ERROR_INVALID_ARGUMENT (NULL argument), VOLLEY_ERROR_NOT_COMMITTED,
 *  VOLLEY_ERROR_OUT_OF_MEMORY. */
VOLLEY_API volley_status volley_intersect_stream(const volley_scene* scene, const volley_ray* rays, size_t count,
                                                 volley_hit* hits);

/** Occlusion of `count` rays: occluded[i] = 1 when blocked, else 0; as volley_intersect_stream. */
VOLLEY_API volley_status volley_occluded_stream(const volley_scene* scene, const volley_ray* rays, size_t count,
                                                uint8_t* occluded);

/** The unit geometric normal of the primitive `hit` names, in the scene's space (through
 *  the hit's instance): normalize((p1 - p0) x (p2 - p0)) for a triangle as added (Embree's
 *  Ng, normalized), the right-hand-rule normal of a polygon. NaN in every component for a
 *  miss or a hit naming nothing in this scene. volley_geometric_normals: the same for
 *  `count` hits, three floats each. Errors: VOLLEY_ERROR_INVALID_ARGUMENT (a NULL argument,
 *  a NULL array with count > 0), VOLLEY_ERROR_NOT_COMMITTED. */
VOLLEY_API volley_status volley_geometric_normal(const volley_scene* scene, const volley_hit* hit, float normal[3]);
VOLLEY_API volley_status volley_geometric_normals(const volley_scene* scene, const volley_hit* hits, size_t count,
                                                  float* normals);

/** Checks rays without tracing them: VOLLEY_OK when every ray can hit something;
 *  VOLLEY_ERROR_INVALID_RAY for the first ray that is always a miss (non-finite origin or
 *  direction, NaN tmin or tmax, tmin >= tmax, zero direction), whose index goes to
 *  *first_invalid when first_invalid is not NULL, with a message naming the ray and the
 *  reason. VOLLEY_ERROR_INVALID_ARGUMENT for rays = NULL with count > 0. Not needed
 *  before a query (such rays simply miss); for callers who treat them as bugs. */
VOLLEY_API volley_status volley_validate_rays(const volley_ray* rays, size_t count, size_t* first_invalid);

#ifdef __cplusplus
}
#endif

/* The query forms with a ray mask. */
#include "volley/volley_masked.h"
/* Queries beyond the first hit: all hits, counts, inside/outside, closest points. */
#include "volley/volley_queries.h"
/* The query forms that leave one primitive out (a ray leaving its own triangle). */
#include "volley/volley_excluding.h"

#endif /* VOLLEY_VOLLEY_H */
