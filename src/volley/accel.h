// volley public API: the acceleration structure an embedder builds and queries.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include "volley/options.h"
#include "volley/packet.h"
#include "volley/point.h"
#include "volley/ray.h"

namespace volley {

/// Thrown for invalid input to the API (bad indices, NaN vertices, non-planar polygon,
/// query before commit). The message says what was expected.
class VOLLEY_API Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;  ///< constructed from the message
};

/// Thrown by commit() when memory runs out while building (a std::bad_alloc inside,
/// turned into a message that says what was being built). The Accel is then left
/// uncommitted: queries throw Error until a commit succeeds.
class VOLLEY_API OutOfMemory : public Error {
 public:
  using Error::Error;  ///< constructed from the message
};

/// Facts about a committed Accel (for `volley info` and --stats). With a SIMD ISA the
/// triangle BVH is the wide BVH (`width` children per node, leaves of triangle blocks of
/// `block_width` lanes); with Isa::scalar it is the oracle's binary BVH (width 2, block 1).
/// Polygons (always a binary BVH) add to nodes, leaves, depth and bytes.
struct AccelInfo {
  std::size_t triangles = 0;       ///< triangles added
  std::size_t degenerate = 0;      ///< zero-area triangles among them (never hit)
  std::size_t polygons = 0;        ///< planar polygons added
  std::size_t geometries = 0;      ///< geometries (one per add_triangles / add_polygon call)
  std::size_t disabled = 0;        ///< geometries disabled at the commit (left out of the structure)
  std::size_t instances = 0;       ///< instance geometries (add_instance)
  std::size_t instanced_triangles = 0;  ///< triangles seen through the instances (each prototype's times its instances)
  std::size_t layers = 0;          ///< BVHs, one per distinct geometry mask (1 when no mask was set; 0: nothing to hit);
                                   ///< with several, nodes / leaves / blocks / bytes are summed and the costs are the largest's
  bool loaded = false;             ///< the structure was mapped from a file (Accel::load), not built here
  bool refitted = false;           ///< the last commit refitted the BVH (Options::refit) instead of building it
  double sah_growth = 1.0;         ///< triangle SAH cost now / at the last full build (1 after a build)
  std::size_t nodes = 0;           ///< BVH nodes (wide: interior nodes; binary: all nodes)
  std::size_t leaves = 0;          ///< BVH leaves
  std::size_t depth = 0;           ///< deepest leaf (root = 0)
  double sah_cost = 0.0;           ///< SAH cost of the triangle BVH (node visit = 1, triangle test = 1)
  double binary_sah_cost = 0.0;    ///< the same for the binary binned-SAH BVH it was collapsed from
  double mean_leaf_size = 0.0;     ///< primitives per leaf
  std::size_t bytes = 0;           ///< memory of nodes + primitive data (triangle blocks)
  double build_seconds = 0.0;      ///< wall time of commit (of the original commit for a loaded one)
  double load_seconds = 0.0;       ///< wall time of Accel::load (0 when built here)
  int width = 2;                   ///< children per node of the triangle BVH
  int block_width = 1;             ///< triangles per block (SIMD lanes of the leaf kernels)
  std::size_t blocks = 0;          ///< triangle blocks (0 for scalar)
  double mean_children = 0.0;      ///< used children per node (of `width`)
  double block_fill = 0.0;         ///< stored triangles / (blocks * block_width)
  TriangleTest test = TriangleTest::watertight;
  Isa isa = Isa::scalar;           ///< ISA actually used
  bool robust = true;              ///< Options::robust: padded (conservative) slab tests
  bool reference_double = false;   ///< Options::reference_double: double-precision triangle tests
  BuildQuality quality = BuildQuality::medium;  ///< Options::quality the BVH was built with
  std::size_t references = 0;      ///< triangles stored in the leaves (more than the triangles with spatial splits)
};

/// Triangles and planar polygons, built once by commit(), then queried.
/// Not thread-safe while adding/committing; after commit() it is immutable and any number
/// of threads may call intersect()/occluded() concurrently.
class VOLLEY_API Accel {
 public:
  /// An empty structure: add geometry, then commit().
  Accel();
  /// Frees the geometry and the BVH. No query may be running.
  ~Accel();
  /// Takes over `other`'s geometry and BVH; `other` is left unusable (assign to it or destroy it).
  Accel(Accel&& other) noexcept;
  /// Takes over `other`'s geometry and BVH, freeing this one's; `other` is left unusable.
  Accel& operator=(Accel&& other) noexcept;
  Accel(const Accel&) = delete;             ///< not copyable (a BVH can be large): move it
  Accel& operator=(const Accel&) = delete;  ///< not copyable: move it

  /// Adds an indexed triangle mesh as a new geometry and returns its id (0, 1, 2, ... in
  /// the order of add_triangles and add_polygon calls). `xyz` holds 3*vertex_count floats,
  /// `indices` 3*triangle_count vertex indices. Data is copied. A hit on triangle i reports
  /// geom = the id returned and prim = i. Throws Error for an index out of range, a
  /// non-finite vertex, or more than 2^32 - 2 primitives in all.
  std::uint32_t add_triangles(const float* xyz, std::size_t vertex_count,
                              const std::uint32_t* indices, std::size_t triangle_count);

  /// Adds one planar polygon (convex or concave, >= 3 vertices, 3*vertex_count floats,
  /// in order around the boundary) as a new geometry and returns its id (hits report
  /// prim = 0). Throws Error when it is not planar within 1e-4 of its size, has a
  /// non-finite vertex or zero area.
  std::uint32_t add_polygon(const float* xyz, std::size_t vertex_count);

  /// Places a committed Accel (the prototype) in this one under an affine transform, as a
  /// new geometry (as Embree's instance geometry), and returns its id. `transform` holds
  /// 12 floats, the 3x4 matrix [A | t] row by row, mapping the prototype's coordinates to
  /// this Accel's: x' = A x + t. A hit through the instance reports inst = the id returned,
  /// and geom and prim as in the prototype; t is the distance along the ray as given (the
  /// ray is carried into the prototype's space, not normalised). Instances share the
  /// prototype's structure (its memory is not copied; it stays alive as long as an
  /// instance needs it); commit this Accel again after committing a changed prototype.
  /// One level: a prototype must not hold instances itself. Disable, enable and mask an
  /// instance like any geometry; update_vertices does not apply. Throws Error when the
  /// prototype is this Accel, not committed, or holds instances, or when the transform has a
  /// non-finite entry or is singular.
  std::uint32_t add_instance(const Accel& prototype, const float* transform);

  /// Leaves a geometry out of the structure from the next commit() on (as Embree's
  /// rtcDisableGeometry): nothing of it is hit, and it costs the walks nothing. Its data
  /// stays; enable_geometry() brings it back at a later commit. Uncommits the Accel.
  /// Throws Error for an id no add call returned.
  void disable_geometry(std::uint32_t geometry);

  /// Brings a disabled geometry back from the next commit() on (a no-op for an enabled
  /// one). Uncommits the Accel. Throws Error for an id no add call returned.
  void enable_geometry(std::uint32_t geometry);

  /// Sets a geometry's 32-bit mask (as Embree's rtcSetGeometryMask); the default is
  /// kMaskAll. A ray given a mask (the query forms that take one) sees the geometry only
  /// when their masks share a bit; the forms without one see every geometry whose mask is
  /// not 0. Geometries of one mask share a BVH: a scene that sets no mask keeps its one BVH
  /// and no mask test anywhere, and a ray walks the BVHs of the masks it shares a bit
  /// with (AccelInfo::layers). Takes effect at the next commit(); uncommits the Accel.
  /// Throws Error for an id no add call returned.
  void set_geometry_mask(std::uint32_t geometry, std::uint32_t mask);

  /// Moves the vertices of a triangle geometry: `xyz` holds 3*vertex_count floats, the
  /// same vertex_count as its add_triangles call, and its triangles keep their indices.
  /// Data is copied. The next commit() refits the BVH instead of building it when nothing
  /// else changed (Options::refit). Uncommits the Accel. Throws Error for an id no
  /// add_triangles call returned, another vertex count, or a non-finite coordinate (then
  /// nothing changes).
  void update_vertices(std::uint32_t geometry, const float* xyz, std::size_t vertex_count);

  /// Builds the acceleration structure. Call again after adding more geometry. Throws
  /// Error (leaving the Accel unchanged) when the CPU lacks options.isa, or when
  /// options.reference_double is set with an ISA other than scalar or with robust = false;
  /// OutOfMemory (leaving it uncommitted) when memory runs out while building.
  void commit(const Options& options = {});

  /// Closest hit along the ray (tmin <= t < tmax), or a miss. A ray with a non-finite
  /// origin or direction component, a zero direction, or a NaN tmin or tmax, misses (the
  /// same holds for every packet lane and stream ray).
  Hit intersect(const Ray& ray) const;
  /// True when anything is hit with tmin <= t < tmax.
  bool occluded(const Ray& ray) const;

  /// intersect(ray) for a ray with a mask: only geometries whose mask shares a bit with
  /// `mask` are hit (mask 0: a miss). Same answers as intersect(ray) on a scene of just those.
  Hit intersect(const Ray& ray, std::uint32_t mask) const;
  /// occluded(ray) for a ray with a mask, as intersect(ray, mask).
  bool occluded(const Ray& ray, std::uint32_t mask) const;

  /// intersect(ray, mask) with one primitive left out: the one `excluded` names by its geom,
  /// prim and inst (its t, u, v are not read; a miss leaves nothing out). A ray spawned at
  /// a hit point (tmin = 0) passes over the triangle it leaves by its id instead of an
  /// offset of its origin. Same answers as intersect(ray, mask) on the scene without that
  /// primitive (in an instance: without it in that instance only). One primitive is left
  /// out, not the surface: a ray leaving a point of an edge or vertex it shares with a
  /// neighbour still meets the neighbour at t = 0. Throws Error when `excluded` names no
  /// primitive of this scene.
  Hit intersect_excluding(const Ray& ray, const Hit& excluded, std::uint32_t mask = kMaskAll) const;
  /// occluded(ray, mask) with the primitive `excluded` names left out, as intersect_excluding.
  bool occluded_excluding(const Ray& ray, const Hit& excluded, std::uint32_t mask = kMaskAll) const;
  /// A batch of `count` rays with what varies between calls in `args` (masks, excluded
  /// primitives, threads; QueryArguments): hits[i] answers rays[i], as intersect(ray, mask)
  /// or intersect_excluding(ray, excluded[i], mask). Every excluded hit is checked before
  /// any answer is written. Throws Error as the forms it stands for.
  void intersect(const Ray* rays, std::size_t count, Hit* hits, const QueryArguments& args) const;
  /// Occlusion of a batch (blocked[i] = 1 when rays[i] is blocked), as intersect(rays, count, hits, args).
  void occluded(const Ray* rays, std::size_t count, std::uint8_t* blocked, const QueryArguments& args) const;

  /// Closest hits of the active lanes of a packet (bit i of rays.active), K = 4, 8 or 16.
  /// Lane i searches tmin <= t < min(tmax, hits.t[i]): reset the hits first with
  /// volley::reset(hits) (t = +inf, prim = kInvalidPrim), or pass earlier answers to bound
  /// the search. Only active lanes that find a nearer hit are written; inactive lanes are
  /// neither read nor written. Same answers as intersect(ray) per lane; NaN or Inf lanes
  /// miss without disturbing the others. Coherent packets (4x4 pixel blocks of primary
  /// rays) are fastest; a packet whose lanes diverge continues lane by lane.
  template <int K>
  void intersect(const RayPacket<K>& rays, HitPacket<K>& hits) const;
  /// Occlusion of the active lanes (tmin <= t < tmax): returns the mask of those occluded
  /// (bit i = lane i). Inactive lanes are never set.
  template <int K>
  std::uint32_t occluded(const RayPacket<K>& rays) const;

  /// Packets with a mask per lane: masks[i] is lane i's (K of them), as intersect(ray, mask).
  /// Throws Error for a null masks.
  template <int K>
  void intersect(const RayPacket<K>& rays, HitPacket<K>& hits, const std::uint32_t* masks) const;
  /// Occlusion of a packet with a mask per lane.
  template <int K>
  std::uint32_t occluded(const RayPacket<K>& rays, const std::uint32_t* masks) const;

  /// Closest hits of a stream of `count` rays: hits[i] answers rays[i] (a miss where
  /// nothing is hit; every entry written). Policy: the stream is cut into runs of 16
  /// consecutive rays (the rest ray by ray). A run whose directions share one octant is
  /// traced as a packet (primary rays in 4x4 blocks, shadow rays toward one light). On
  /// AVX-512, AVX2 and SSE4.2, in a scene of one BVH (no instances, polygons or geometry
  /// masks of several values), the runs whose directions spread across two or more axis
  /// planes (bounce and ambient-occlusion rays), when they hold 256 rays or more, walk the
  /// tree together by the stream walk (docs/kernels.md; 1.2-2.3x the rate ray by ray on
  /// diffuse rays, perf/reports/rays.md). Other runs:
  /// closest hits ray by ray, which was faster for diffuse rays (perf/reports/traversal.md);
  /// occlusion on AVX-512 and AVX2, and every run of a scene with instances, as a packet
  /// (shadow rays straddling one axis plane gained there; with instances a packet shares
  /// the top level's walk: perf/reports/instances.md); on AVX2, in a scene of one BVH and with no
  /// masks, two neighbouring occlusion runs as one packet of 32 (docs/kernels.md). A call of
  /// 4096 rays or more on AVX-512 or AVX2 first counts the leaves the single-ray walk reaches
  /// for 64 of its rays spread over it: under 0.3 a ray (rays that mostly leave the tree
  /// near its root: bounce rays in rooms), or in a tree of 16 leaves or fewer, every run
  /// goes as a packet, whatever its octants (1.3-1.6x the stream walk there; counts, not
  /// time, decide: perf/reports/rays.md). The stream walk reorders nothing the caller
  /// sees. Same answers as intersect(ray) per ray.
  /// `threads`, as in every batch call: 0 (the default) on the caller's oneTBB arena (all
  /// its threads; the default arena otherwise: all cores), 1 on the calling thread alone,
  /// n > 1 on exactly n threads, in pieces of whole runs (at least 1024 rays each, handed to
  /// the policy 4096 at a time), with the same answers. Error for threads < 0.
  void intersect(const Ray* rays, std::size_t count, Hit* hits, int threads = 0) const;
  /// Occlusion of a stream: blocked[i] = 1 when rays[i] is occluded, else 0. Regrouped as
  /// intersect(rays, count, hits).
  void occluded(const Ray* rays, std::size_t count, std::uint8_t* blocked, int threads = 0) const;
  /// Streams with a mask per ray: masks[i] is rays[i]'s, as intersect(ray, mask). Throws
  /// Error for a null masks with count > 0.
  void intersect(const Ray* rays, const std::uint32_t* masks, std::size_t count, Hit* hits, int threads = 0) const;
  void occluded(const Ray* rays, const std::uint32_t* masks, std::size_t count, std::uint8_t* blocked,
                int threads = 0) const;

  // --- Beyond the first hit (docs/crossings.md) -------------------------------------
  // Crossing queries count every surface a ray passes through exactly once: with the
  // watertight test (the default), a ray through an edge or vertex that closed meshes
  // share hits exactly one of the triangles there, and one grazing a silhouette an even
  // number (the crossing rule). Möller and plane tests report their own hits, without that rule.
  // Batches: `threads` = 0 runs on the caller's oneTBB arena (all its threads; the default
  // arena otherwise), n >= 1 on exactly n threads (1: the calling thread alone).

  /// Every hit along the ray with tmin <= t < tmax, nearest first (ties by instance,
  /// geometry, primitive), through the layers `mask` selects: writes the first min(count, capacity)
  /// into `hits` (null allowed with capacity 0) and returns the count.
  std::size_t intersect_all(const Ray& ray, Hit* hits, std::size_t capacity, std::uint32_t mask = kMaskAll) const;
  /// intersect_all over `count` rays into lists (every hit of every ray).
  HitLists intersect_all(const Ray* rays, std::size_t count, int threads = 0) const;
  /// The number of hits along the ray (intersect_all's count, no list).
  std::uint32_t count_intersections(const Ray& ray, std::uint32_t mask = kMaskAll) const;
  /// count_intersections of `count` rays into counts[0 .. count).
  void count_intersections(const Ray* rays, std::size_t count, std::uint32_t* counts, int threads = 0) const;

  /// Whether the point lies inside the closed geometry: the parity of the crossings of one
  /// ray from it (a fixed direction, kContainsDirection), no voting. For geometry that is
  /// not closed the answer is that ray's parity (it depends on the direction); a point on
  /// the surface may go either way. NaN or Inf coordinates: false.
  bool contains(const float point[3]) const;
  /// contains for `count` points (xyz: 3 floats each): inside[i] = 1 or 0.
  void contains(const float* xyz, std::size_t count, std::uint8_t* inside, int threads = 0) const;
  /// The nearest surface point within max_distance (a miss beyond it: ClosestPoint::found()
  /// is false, distance +inf). Triangles (watertight or Möller test) and polygons; throws
  /// Error for a scene with instances or built with the plane test.
  ClosestPoint closest_point(const float point[3], float max_distance = std::numeric_limits<float>::infinity()) const;
  /// closest_point for `count` points.
  void closest_points(const float* xyz, std::size_t count, ClosestPoint* out,
                      float max_distance = std::numeric_limits<float>::infinity(), int threads = 0) const;
  /// Distance to the surface (+inf for an empty scene). signed_distance: negative inside
  /// (contains), as Open3D's compute_signed_distance.
  float distance(const float point[3]) const;
  float signed_distance(const float point[3]) const;
  /// distance or signed_distance for `count` points.
  void distances(const float* xyz, std::size_t count, float* out, bool is_signed, int threads = 0) const;

  /// The unit geometric normal of the primitive a hit names, in this Accel's space (through
  /// the hit's instance when it has one: the prototype's normal under the inverse transpose
  /// of the transform): normalize((p1 - p0) x (p2 - p0)) for a triangle of vertices p0 p1 p2
  /// as added (Embree's Ng, normalized), the right-hand-rule normal of a polygon's vertex
  /// order. The side the ray came from is not taken into account. NaN in every component
  /// for a miss, for a hit naming nothing here, or for a degenerate triangle. Works on a
  /// committed Accel (built or loaded).
  std::array<float, 3> geometric_normal(const Hit& hit) const;
  /// geometric_normal for `count` hits, three floats each into `xyz`, on `threads` (the
  /// batch rule: 0, the default, all of the caller's arena; 1 the calling thread).
  void geometric_normals(const Hit* hits, std::size_t count, float* xyz, int threads = 0) const;

  /// Facts about the committed structure.
  AccelInfo info() const;
  /// What the single-ray walk visits for `ray` (closest hit, or occlusion with any_hit):
  /// interior nodes, leaves and triangles, for comparing trees and traversals
  /// (`volley trace --stats`). The answer is not kept. Error unless the scene is triangles
  /// in one layer with no instances on a SIMD ISA (the wide BVH alone).
  WalkCounts walk_counts(const Ray& ray, bool any_hit = false) const;

  /// Writes the committed structure to `path` (replacing a file there; written under
  /// `path`.tmp first, so a failed save leaves no partial file): the wide BVH and triangle
  /// blocks as built, the geometries with their vertices, indices and flags, the options,
  /// the test and ISA it was built for, a format version and a checksum. load() maps it
  /// back. Throws Error when not committed or when the file cannot be written.
  void save(const std::string& path) const;

  /// An Accel mapped from a file save() wrote, committed and ready to query, with the same
  /// answers as the one saved. The wide BVH is queried where it lies in the mapped file (no
  /// build, no copy); the geometry comes back into memory only when it is changed or the
  /// Accel is committed again (it can be changed as before: add, update_vertices, refit).
  /// Structures committed with Isa::scalar are rebuilt from the saved geometry. Throws Error
  /// naming the path and the fault for a file that is missing, not a volley structure, of
  /// another format version, truncated, corrupted (checksum), built for an ISA this CPU
  /// lacks, or inconsistent in any count, id or reference.
  static Accel load(const std::string& path);

 private:
  struct Impl;
  /// Shared with the Accels that instance this one (add_instance), which keep it alive.
  std::shared_ptr<Impl> impl_;
};

}  // namespace volley
