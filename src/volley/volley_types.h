/* volley C API: the constants, enumerations and structs every function of volley/volley.h
 * takes or returns (included by volley/volley.h; C99, also valid C++). Each struct has the
 * layout of its C++ twin (volley/ray.h, volley/packet.h, volley/accel.h), checked where the
 * library is built. */
#ifndef VOLLEY_VOLLEY_TYPES_H
#define VOLLEY_VOLLEY_TYPES_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/** prim of a miss (and of hit-packet lanes with no hit yet). */
#define VOLLEY_INVALID_PRIM 0xffffffffu
/** geom of a miss; inst of a miss or of a hit not made through an instance. */
#define VOLLEY_INVALID_ID 0xffffffffu
/** The default geometry mask: every bit (volley_scene_set_geometry_mask). */
#define VOLLEY_MASK_ALL 0xffffffffu

/** Alignment of the packet structs below: 64 bytes (one cache line, any SIMD width).
 *  Stack variables of those types get it from the compiler; heap memory must come from
 *  aligned_alloc(64, ...) or posix_memalign. Packets at other addresses are rejected
 *  with VOLLEY_ERROR_MISALIGNED. */
#if defined(__cplusplus)
#define VOLLEY_ALIGN64 alignas(64)
#elif defined(__GNUC__) || defined(__clang__)
#define VOLLEY_ALIGN64 __attribute__((aligned(64)))
#else
#define VOLLEY_ALIGN64
#endif

/** Result of every fallible call. */
typedef enum volley_status {
  VOLLEY_OK = 0,                     /**< success */
  VOLLEY_ERROR_INVALID_ARGUMENT = 1, /**< a NULL pointer, an unknown enum value, a count out of range */
  VOLLEY_ERROR_INVALID_GEOMETRY = 2, /**< a non-finite vertex, an index out of range, a bad polygon */
  VOLLEY_ERROR_MISALIGNED = 3,       /**< packet memory not 64-byte aligned */
  VOLLEY_ERROR_NOT_COMMITTED = 4,    /**< a query on a scene not committed since its last change */
  VOLLEY_ERROR_UNSUPPORTED_ISA = 5,  /**< this CPU cannot run the requested ISA (or VOLLEY_ISA is bad) */
  VOLLEY_ERROR_OUT_OF_MEMORY = 6,    /**< an allocation failed */
  VOLLEY_ERROR_INVALID_RAY = 7,      /**< from volley_validate_rays only: a ray that can never hit */
  VOLLEY_ERROR_INTERNAL = 8,         /**< anything else: a bug in volley, please report it */
  VOLLEY_ERROR_FILE = 9,             /**< a structure file could not be written or read, or is not valid: missing,
                                          not a volley file, another format version, truncated, corrupted,
                                          inconsistent, or built for an ISA this CPU lacks (the message says which) */
  VOLLEY_ERROR_BUFFER_TOO_SMALL = 10 /**< volley_intersect_all: more hits than the buffer holds (the count was written) */
} volley_status;

/** Ray/triangle test, fixed at commit (same as volley::TriangleTest). */
typedef enum volley_triangle_test {
  VOLLEY_TEST_WATERTIGHT = 0, /**< Woop-Benthin-Wald 2013: no cracks at shared edges (default) */
  VOLLEY_TEST_PLANE = 1,      /**< the course notes' algorithm 1: ray/plane, then edge planes */
  VOLLEY_TEST_MOLLER = 2      /**< the notes' algorithm 2: Cramer's rule (Moller-Trumbore) */
} volley_triangle_test;

/** Instruction set of the kernels, fixed at commit (same as volley::Isa). */
typedef enum volley_isa {
  VOLLEY_ISA_AUTO = 0,   /**< the widest the CPU supports, unless the VOLLEY_ISA variable names one */
  VOLLEY_ISA_SCALAR = 1, /**< the scalar oracle */
  VOLLEY_ISA_SSE42 = 2,  /**< SSE4.2, 4 lanes */
  VOLLEY_ISA_AVX2 = 3,   /**< AVX2 + FMA, 8 lanes */
  VOLLEY_ISA_AVX512 = 4  /**< AVX-512 F/DQ/BW/VL, 16 lanes */
} volley_isa;

/** BVH build quality, fixed at commit (volley::BuildQuality; Embree's values). */
typedef enum volley_build_quality {
  VOLLEY_BUILD_QUALITY_MEDIUM = 1, /**< binned SAH: fast to build (default) */
  VOLLEY_BUILD_QUALITY_HIGH = 2    /**< also spatial splits (SBVH): slower to build, fewer nodes per ray where
                                        triangles are long; medium's answers but where rounding decides (ties) */
} volley_build_quality;

/** One ray (32 bytes; the layout of volley::Ray and of a .vray record). */
typedef struct volley_ray {
  float org[3]; /**< origin */
  float tmin;   /**< start of the search interval (inclusive) */
  float dir[3]; /**< direction, not necessarily normalized */
  float tmax;   /**< end of the search interval (exclusive) */
} volley_ray;

/** A closest-hit answer (24 bytes; the layout of volley::Hit and of a .vhit record).
 *  The hit point is org + t * dir = (1 - u - v) p0 + u p1 + v p2 for the triangle's
 *  vertices p0, p1, p2 in the order of its indices. Polygons report u = v = 0. */
typedef struct volley_hit {
  float t;       /**< distance along the ray in units of |dir|; +inf for a miss */
  float u;       /**< barycentric weight of the second vertex; 0 for a miss */
  float v;       /**< barycentric weight of the third vertex; 0 for a miss */
  uint32_t prim; /**< the primitive's index within its geometry; VOLLEY_INVALID_PRIM for a miss */
  uint32_t geom; /**< the geometry hit; VOLLEY_INVALID_ID for a miss */
  uint32_t inst; /**< the instance hit through; VOLLEY_INVALID_ID for none */
} volley_hit;

/** 4 rays in structure-of-arrays form (192 bytes, 64-byte aligned; the layout of
 *  volley::RayPacket<4>). Lane i takes part when bit i of `active` is set; the other
 *  lanes are ignored (never read for answers, never written). */
typedef struct VOLLEY_ALIGN64 volley_ray_packet4 {
  float ox[4], oy[4], oz[4];  /**< origins */
  float dx[4], dy[4], dz[4];  /**< directions */
  float tmin[4], tmax[4];     /**< search intervals tmin <= t < tmax */
  uint32_t active;            /**< bit i set: lane i takes part */
  uint32_t reserved[15];      /**< padding to the next 64 bytes; not read */
} volley_ray_packet4;

/** 8 rays in structure-of-arrays form (320 bytes; volley::RayPacket<8>). As volley_ray_packet4. */
typedef struct VOLLEY_ALIGN64 volley_ray_packet8 {
  float ox[8], oy[8], oz[8];  /**< origins */
  float dx[8], dy[8], dz[8];  /**< directions */
  float tmin[8], tmax[8];     /**< search intervals tmin <= t < tmax */
  uint32_t active;            /**< bit i set: lane i takes part */
  uint32_t reserved[15];      /**< padding to the next 64 bytes; not read */
} volley_ray_packet8;

/** 16 rays in structure-of-arrays form (576 bytes; volley::RayPacket<16>). As volley_ray_packet4. */
typedef struct VOLLEY_ALIGN64 volley_ray_packet16 {
  float ox[16], oy[16], oz[16]; /**< origins */
  float dx[16], dy[16], dz[16]; /**< directions */
  float tmin[16], tmax[16];     /**< search intervals tmin <= t < tmax */
  uint32_t active;              /**< bit i set: lane i takes part */
  uint32_t reserved[15];        /**< padding to the next 64 bytes; not read */
} volley_ray_packet16;

/** Closest hits of 4 rays (128 bytes, 64-byte aligned; volley::HitPacket<4>). Lane i
 *  means what volley_hit means; before a query, reset it (volley_reset_hits4) or leave an
 *  earlier answer there to bound the search. */
typedef struct VOLLEY_ALIGN64 volley_hit_packet4 {
  float t[4];       /**< distances; +inf: no hit */
  float u[4];       /**< barycentric u */
  float v[4];       /**< barycentric v */
  uint32_t prim[4]; /**< primitives within their geometries; VOLLEY_INVALID_PRIM: no hit */
  uint32_t geom[4]; /**< geometries; VOLLEY_INVALID_ID: no hit */
  uint32_t inst[4]; /**< instances; VOLLEY_INVALID_ID: none */
} volley_hit_packet4;

/** Closest hits of 8 rays (192 bytes; volley::HitPacket<8>). As volley_hit_packet4. */
typedef struct VOLLEY_ALIGN64 volley_hit_packet8 {
  float t[8];       /**< distances; +inf: no hit */
  float u[8];       /**< barycentric u */
  float v[8];       /**< barycentric v */
  uint32_t prim[8]; /**< primitives within their geometries; VOLLEY_INVALID_PRIM: no hit */
  uint32_t geom[8]; /**< geometries; VOLLEY_INVALID_ID: no hit */
  uint32_t inst[8]; /**< instances; VOLLEY_INVALID_ID: none */
} volley_hit_packet8;

/** Closest hits of 16 rays (384 bytes; volley::HitPacket<16>). As volley_hit_packet4. */
typedef struct VOLLEY_ALIGN64 volley_hit_packet16 {
  float t[16];       /**< distances; +inf: no hit */
  float u[16];       /**< barycentric u */
  float v[16];       /**< barycentric v */
  uint32_t prim[16]; /**< primitives within their geometries; VOLLEY_INVALID_PRIM: no hit */
  uint32_t geom[16]; /**< geometries; VOLLEY_INVALID_ID: no hit */
  uint32_t inst[16]; /**< instances; VOLLEY_INVALID_ID: none */
} volley_hit_packet16;

/** Facts about a committed scene (a subset of volley::AccelInfo). */
typedef struct volley_scene_info {
  size_t triangles;          /**< triangles added */
  size_t degenerate;         /**< zero-area triangles among them (never hit) */
  size_t polygons;           /**< polygons added */
  size_t nodes;              /**< BVH nodes */
  size_t leaves;             /**< BVH leaves */
  size_t depth;              /**< deepest leaf (root = 0) */
  size_t bytes;              /**< memory of the BVH and primitive data */
  double build_seconds;      /**< wall time of the last commit */
  int width;                 /**< children per node of the triangle BVH */
  int block_width;           /**< triangles per leaf block (SIMD lanes) */
  volley_triangle_test test; /**< the test in use */
  volley_isa isa;            /**< the ISA in use (never VOLLEY_ISA_AUTO) */
  size_t geometries;         /**< geometries added */
  size_t disabled;           /**< geometries left out at the last commit */
  int refitted;              /**< nonzero: the last commit refitted the BVH instead of building it */
  double sah_growth;         /**< SAH cost of the triangle BVH now / at the last full build */
  int loaded;                /**< nonzero: the structure was mapped from a file (volley_scene_load), not built */
  size_t layers;             /**< BVHs, one per distinct geometry mask (volley::AccelInfo::layers) */
  size_t instances;          /**< instance geometries (volley_scene_add_instance) */
  size_t instanced_triangles; /**< triangles seen through the instances */
  double load_seconds;       /**< wall time of volley_scene_load (0 when built) */
  volley_build_quality quality; /**< the build quality of the structure */
  size_t references;         /**< triangles stored in the leaves (above triangles with spatial splits) */
} volley_scene_info;

/** A scene: triangles and polygons plus the acceleration structure built over them.
 *  Opaque; create with volley_scene_create, free with volley_scene_destroy. */
typedef struct volley_scene volley_scene;

#ifdef __cplusplus
}
#endif

#endif /* VOLLEY_VOLLEY_TYPES_H */
