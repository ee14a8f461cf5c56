// Accel's private state: the geometry as added, and at commit its layers: one per distinct
// geometry mask (Accel::set_geometry_mask; a scene that sets none has one), each with one
// engine per kind of primitive it holds (triangles: the wide SIMD BVH, the scalar oracle or
// the double reference; polygons: engine.h), and the table of query entry points chosen
// for the scene (Queries). A ray walks the layers whose mask shares a bit with its own:
// triangles, then polygons bounded by their hit, then instances.
#pragma once
#include <array>
#include <cstdint>
#include <limits>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "accel/accel_file.h"
#include "accel/engine.h"
#include "accel/instance_tree.h"
#include "accel/wide/wide_accel.h"
#include "core/bvh.h"
#include "core/polygon.h"
#include "volley/accel.h"
#include "volley/packet.h"

namespace volley {

/// Hits nearest first; ties (one t on two primitives) by instance, geometry, primitive.
void sort_hits(Hit* first, Hit* last);

/// Drops repeated triangles from hits[first ..): with spatial splits (BuildQuality::high) a
/// triangle may sit in several leaves a ray enters, and each test of it gives the same hit
/// (the same test of the same ray), so one of each is kept. The order of the rest changes.
void drop_repeated_hits(std::vector<Hit>& hits, std::size_t first);

/// The ray of contains(): from the point along kContainsDirection, t >= 0.
inline Ray contains_ray(const float* p) {
  return Ray{{p[0], p[1], p[2]}, 0.0f, {kContainsDirection[0], kContainsDirection[1], kContainsDirection[2]},
             std::numeric_limits<float>::infinity()};
}

struct Accel::Impl {
  Impl();

  /// What a geometry holds; each kind has its engine in a layer (Layer::engines), except
  /// instances, which the layers walk after their engines.
  enum class Kind : std::uint8_t { triangles, polygon, instance };
  /// One add_triangles / add_polygon / add_instance call: its primitives have the internal ids first ..
  /// first + count (the engines answer with those; attribute() turns one back into the
  /// geometry and the index within it).
  struct Geometry {
    std::uint32_t first;  ///< internal id of its first primitive
    std::uint32_t count;  ///< primitives
    std::size_t index;    ///< its first primitive's place in triangle_ids or polygon_ids, or in instances
    Kind kind;
    bool enabled = true;
    std::vector<std::uint32_t> indices;  ///< triangles: the vertex indices as added (update_vertices)
    std::size_t vertex_count = 0;        ///< triangles: the vertices the add call gave
    bool moved = false;                  ///< update_vertices was called on it (a deforming mesh)
    std::uint32_t mask = kMaskAll;       ///< set_geometry_mask
    std::size_t packed_vertices = 0;     ///< a loaded triangle geometry's first vertex in Packed::vertices
  };

  /// One add_instance call: a prototype under an affine transform.
  struct Instance {
    std::shared_ptr<const Impl> prototype;
    float to_world[12];   ///< [A | t] row by row, as given
    float to_object[12];  ///< its inverse (computed in double)
    std::uint32_t geometry;
  };

  /// What a ray that enters an instance reads of it, in one compact record per instance of
  /// a layer (the walk's visit was three dependent loads into Instance before: a cache
  /// miss each, perf/reports/instances.md).
  struct InstanceSlot {
    alignas(16) float object_columns[4][4];  ///< to_object by columns (lane 3 zero), for the SSE transform
    const Impl* prototype;                   ///< kept alive by the Instance
    std::uint32_t geometry;
  };

  /// The engines over the enabled geometries of one mask.
  struct Layer {
    std::uint32_t mask = kMaskAll;
    /// One engine per kind of primitive the layer holds, in query order: triangles, then
    /// polygons (each answer bounds the next engine's search). The queries loop over them;
    /// a new kind adds its engine in its builder (build_layer).
    std::vector<std::unique_ptr<accel::Engine>> engines;
    /// The triangle engine among them (refit, SAH costs, the saved image), or null.
    accel::TriangleEngine* triangle_engine = nullptr;
    /// Appends `engine` after the kinds before it; returns it.
    template <class E>
    E* add(std::unique_ptr<E> engine) {
      E* e = engine.get();
      engines.push_back(std::move(engine));
      return e;
    }
    std::vector<unsigned char> excluded;  ///< per triangle: not in this layer's BVH (another layer's, disabled, degenerate)
    core::BvhStats triangle_stats;        ///< of the binary triangle BVH, as built (unit costs)
    std::vector<InstanceSlot> instances;  ///< the layer's instances
    accel::InstanceTree instance_tree;    ///< over their world boxes
    double built_sah = 0.0;               ///< triangle SAH cost at the last build
    double sah_now = 0.0;                 ///< the same now (after refits)
  };

  /// A loaded Accel's triangle input, still in the mapped file (Accel::load): unpack() copies
  /// it into Added's vectors before anything reads them (a query does not).
  struct Packed {
    std::shared_ptr<const accel::file::Mapping> file;
    std::span<const float> vertices;  ///< the triangle geometries' vertices, geometry after geometry
    std::span<const std::uint32_t> indices;
    std::span<const unsigned char> excluded_flat;
  };

  /// What the stream policy (stream.cpp) may do with the committed scene.
  struct StreamPlan {
    /// Runs of 16 rays may go as packets: every layer traces packets (or holds only
    /// instances), and instances, if any, have packet walks (a SIMD ISA).
    bool packets = false;
    /// Runs of mixed octants may go as packets too: closest-hit runs when the packet shares
    /// the instances' top level (perf/reports/instances.md); runs whose walk needs no order
    /// (occlusion, every hit) then and where the ISA's traits say so (simd::stream_traits).
    bool mixed_closest = false;
    bool mixed_any = false;
    /// Every-hit runs may go as packets (packets, and no instances).
    bool every_hit_packets = false;
    /// Batch calls may send runs of every octant as packets when their rays share their
    /// nodes (Accel::Impl::batch_runs_share_nodes), where the ISA's traits say so.
    bool probe_batches = false;
  };
  /// The committed scene's entry points for the queries and forms that some scenes answer
  /// faster another way. Each starts as the layer walk's form, which answers any scene
  /// (LayerWalk, scene_queries.cpp), and a scene that is one wide BVH of triangles takes the
  /// kernels' own (WideDirect). Chosen at commit (choose_queries): the queries call them and
  /// never ask what the scene holds. Single rays answer attributed; full packets (16 lanes,
  /// all active, no masks) answer as the engines do (prim an internal id).
  struct Queries {
    /// Single rays of every mask (kMaskAll), the hot path: fn(unmasked_target, ...), the
    /// kernels' own entries for a scene that is one wide BVH. They answer as the engines do
    /// (prim an internal id) or, through an instance, complete (inst set): see unmasked().
    void (*intersect_unmasked)(const void* target, const Ray&, Hit&);
    bool (*occluded_unmasked)(const void* target, const Ray&);
    const void* unmasked_target;
    Hit (*intersect)(const Impl&, const Ray&, std::uint32_t mask);
    bool (*occluded)(const Impl&, const Ray&, std::uint32_t mask);
    /// `id`: excluded_id(excluded).
    Hit (*intersect_excluding)(const Impl&, const Ray&, std::uint32_t mask, std::uint32_t id, const Hit& excluded);
    bool (*occluded_excluding)(const Impl&, const Ray&, std::uint32_t mask, std::uint32_t id, const Hit& excluded);
    void (*intersect_full)(const Impl&, const RayPacket<16>&, HitPacket<16>&);
    std::uint32_t (*occluded_full)(const Impl&, const RayPacket<16>&);
    /// The wide BVH of a scene that is one, else null: the direct forms, the stream walk
    /// (simd/wide/stream_walk.h: every SIMD ISA has it), double packets and walk_counts
    /// take it. `wide_mask`: its layer's mask.
    const accel::WideAccel* wide = nullptr;
    std::uint32_t wide_mask = 0;
    StreamPlan stream;
  };
  /// The layers one by one: every scene's forms. The kernels directly: a scene that is one wide BVH.
  struct LayerWalk;
  struct WideDirect;

  /// The scene as added, which lives as long as the Accel: each kind's input in internal-id
  /// order, and what changed since the last commit.
  struct Added {
    std::vector<glm::vec3> triangles;  ///< 3 vertices per triangle
    std::vector<std::uint32_t> triangle_ids;
    std::vector<core::Polygon> polygons;
    std::vector<std::uint32_t> polygon_ids;
    std::vector<Geometry> geometries;  ///< by geometry id
    std::vector<Instance> instances;
    std::uint32_t next_id = 0;
    // What decides between a refit and a build at the next commit (Options::refit).
    bool topology_changed = true;   ///< a geometry added, enabled, disabled or masked since the last build
    bool vertices_changed = false;  ///< update_vertices since the last commit
  };
  /// The committed scene, made anew by each commit (or load): its options, layers and
  /// engines, the tables that turn an engine's answer back into the caller's names, and the
  /// table of query entry points.
  struct Built {
    bool committed = false;
    TriangleTest test = TriangleTest::watertight;
    Isa isa = Isa::scalar;
    bool robust = true;                           ///< Options::robust: padded slab tests
    bool reference_double = false;                ///< Options::reference_double (isa == scalar only)
    BuildQuality quality = BuildQuality::medium;  ///< Options::quality (high: triangles may repeat in leaves)
    double build_seconds = 0.0;
    std::size_t degenerate = 0;
    std::size_t disabled = 0;   ///< geometries left out at the commit
    bool one_geometry = false;  ///< the committed scene has one geometry (hits need no search)
    /// {first id, geometry} of the geometries that hold primitives, by first id: what
    /// attribute_search searches (instances and empty geometries left out: a field of
    /// instances over one mesh searches one entry, not thousands).
    std::vector<std::pair<std::uint32_t, std::uint32_t>> id_starts;
    Options built_with;                        ///< the options of the last build (isa resolved)
    std::vector<unsigned char> excluded_flat;  ///< per triangle: left out as degenerate at the last build
    bool refitted = false;                     ///< the last commit refitted
    /// Boxes whose union holds everything hittable: the wide roots' children where every
    /// layer is a wide BVH of triangles, else the box of every vertex added. An instance of
    /// this Accel is bounded by them transformed (tighter than one box when it is rotated).
    std::vector<core::BBox> bound_parts;
    bool has_instances = false;  ///< some layer holds instances (the queries then walk them after the rest)
    std::vector<Layer> layers;   ///< by descending mask; none when nothing can be hit
    Queries queries;
  };
  /// The loaded image (Accel::load): the mapped file, while it still holds the input.
  struct Mapped {
    std::optional<Packed> packed;
    std::size_t loaded_triangles = 0;  ///< the triangles while packed
    bool loaded = false;               ///< the structure came from a file (AccelInfo::loaded)
    double load_seconds = 0.0;
  };
  Added added;
  Built built;
  Mapped mapped;
  /// Fills `queries` for the committed layers (after a build, refit or load).
  void choose_queries();

  /// Registers the geometry of the next `count` ids and returns its id; uncommits.
  std::uint32_t new_geometry(std::uint32_t count, Kind kind);
  /// The geometry with id `geometry`; Error naming `caller` when there is none.
  Geometry& geometry_at(const char* caller, std::uint32_t geometry);
  /// An engine's answer (prim = internal id) as the API reports it: the geometry and the
  /// index within it. Leaves a miss as it is.
  void attribute(std::uint32_t& prim, std::uint32_t& geom) const {
    if (prim == kInvalidPrim) return;
    if (built.one_geometry) {
      geom = 0;
      return;
    }
    attribute_search(prim, geom);
  }

  /// The unit geometric normal of primitive `prim` of geometry `geom` in this Accel's space
  /// (Accel::geometric_normal); NaN when there is no such primitive.
  std::array<float, 3> local_normal(std::uint32_t geom, std::uint32_t prim) const;

  /// Triangles added (also while packed).
  std::size_t triangle_count() const { return mapped.packed ? mapped.loaded_triangles : added.triangle_ids.size(); }
  /// Copies a loaded Accel's input out of the file (a no-op otherwise): called before the
  /// input is changed or built from.
  void unpack();
  /// Writes the committed structure and its input (accel_save.cpp).
  void save_to(const std::string& path) const;
  /// Fills a fresh Impl from a saved file, committed (accel_load.cpp). Throws Error.
  void load_from(const std::string& path);

  /// Builds every layer for the committed options (test, isa, robust, reference_double).
  void build();
  /// The distinct masks of the enabled geometries, 0 left out, descending: the layers.
  std::vector<std::uint32_t> layer_masks() const;
  /// Sets layer.excluded: the triangles not in it (another mask, disabled, degenerate).
  void exclude_others(Layer& layer) const;
  /// Builds a layer's engines, kind after kind (the one list of them): each builder adds its
  /// engine when the layer holds that kind.
  void build_layer(Layer& layer);
  /// The triangle engine over the layer's enabled triangle geometries.
  void build_triangles(Layer& layer);
  /// The polygon engine over its enabled polygon geometries.
  void build_polygons(Layer& layer);
  /// Sets one_geometry, the refit state and the queries (choose_queries) after a build or a load.
  void finish_build();
  /// Refits the triangle engines to moved vertices when that is allowed and pays (see
  /// Options::refit); false (nothing built) when the caller must build instead.
  bool refit(const Options& options);
  /// SAH costs summed over the layers: at the last build and now.
  double built_sah() const;
  double sah_now() const;

  /// Sets `bound_parts` from the structure as built or refitted (the vertices only when
  /// some layer is not a wide BVH of triangles alone).
  void compute_bound_parts();
  /// Builds each layer's instance BVH (accel_instances.cpp).
  void build_instances();
  /// The nearest hit through the layers' instances at t < hit.t (tmin as the ray's):
  /// overwrites `hit` (complete: inst, geom, prim) and returns true when there is one.
  /// excluded (or null): the excluding queries' primitive, passed over in its instance.
  bool intersect_instances(const Ray& ray, std::uint32_t mask, Hit& hit, const Hit* excluded = nullptr) const;
  bool occluded_instances(const Ray& ray, std::uint32_t mask, const Hit* excluded = nullptr) const;
  /// The packet forms (a SIMD ISA; `rays` a widened copy, every lane initialised, inactive
  /// ones inert; its active lanes and tmax are rewritten): the active lanes walk the top
  /// levels together. Closest: lanes with a nearer hit than hits.t get it; occluded:
  /// returns the lanes blocked.
  void intersect_instances(RayPacket<16>& rays, const std::uint32_t* masks, HitPacket<16>& hits) const;
  std::uint32_t occluded_instances(RayPacket<16>& rays, const std::uint32_t* masks) const;
  /// Every hit through the layers' instances, appended to `out` (inst set).
  void all_hits_instances(const Ray& ray, std::uint32_t mask, std::vector<Hit>& out) const;

  // Queries (accel_query.cpp, stream.cpp): rays see the layers whose mask shares a bit with
  // `mask` (kMaskAll for the queries without a mask); mask 0 sees nothing.
  Hit intersect(const Ray& ray, std::uint32_t mask) const { return built.queries.intersect(*this, ray, mask); }
  /// The closest hit and the occlusion of a ray of every mask (Queries::intersect_unmasked).
  Hit intersect(const Ray& ray) const {
    Hit hit;
    built.queries.intersect_unmasked(built.queries.unmasked_target, ray, hit);
    if (hit.inst == kInvalidId) attribute(hit.prim, hit.geom);
    return hit;
  }
  bool occluded(const Ray& ray) const { return built.queries.occluded_unmasked(built.queries.unmasked_target, ray); }
  bool occluded(const Ray& ray, std::uint32_t mask) const { return built.queries.occluded(*this, ray, mask); }
  /// Packets: masks[i] is lane i's mask; null = kMaskAll for every lane.
  template <int K>
  void intersect(const RayPacket<K>& rays, HitPacket<K>& hits, const std::uint32_t* masks) const;
  template <int K>
  std::uint32_t occluded(const RayPacket<K>& rays, const std::uint32_t* masks) const;
  /// The excluding queries (accel_excluding.cpp): as intersect / occluded with the primitive
  /// `excluded` names (a hit's geom, prim and inst; a miss names none) left out.
  Hit intersect_excluding(const Ray& ray, std::uint32_t mask, const Hit& excluded) const;
  bool occluded_excluding(const Ray& ray, std::uint32_t mask, const Hit& excluded) const;
  /// The internal id of the primitive `excluded` names: kInvalidPrim for a miss or for one
  /// inside an instance (whose prototype is asked then). Throws Error naming `caller` when
  /// it names no primitive of this scene.
  std::uint32_t excluded_id(const char* caller, const Hit& excluded) const;
  /// excluded_id for a primitive inside an instance, or for a hit that names nothing (the error).
  std::uint32_t excluded_elsewhere(const char* caller, const Hit& excluded) const;
  /// excluded_id of excluded[0 .. count), found once for a whole batch before any answer
  /// is written; the error names the index.
  std::vector<std::uint32_t> excluded_ids(const char* caller, const Hit* excluded, std::size_t count) const;
  /// The batch forms (args.excluded not null, `ids` its excluded_ids; args.masks one per ray
  /// or null): by the stream walk where excluding_stream says so, else ray by ray.
  void intersect_excluding(const Ray* rays, const QueryArguments& args, const std::uint32_t* ids, std::size_t count,
                           Hit* hits) const;
  void occluded_excluding(const Ray* rays, const QueryArguments& args, const std::uint32_t* ids, std::size_t count,
                          std::uint8_t* blocked) const;
  /// Whether an excluding batch goes to the stream walk: the scene is one wide BVH, the
  /// batch holds at least kStreamWalkRays rays and every mask (if any) meets the BVH's.
  bool excluding_stream(const QueryArguments& args, std::size_t count) const;
  /// The stream policy (stream.cpp): runs of 16 rays as packets where that pays, the rest
  /// by the stream walk where the scene allows it and enough are left, else one by one.
  /// masks: one per ray, or null. `mixed_packets`: runs of every octant as packets
  /// (batch_runs_share_nodes).
  void intersect(const Ray* rays, const std::uint32_t* masks, std::size_t count, Hit* hits,
                 bool mixed_packets = false) const;
  void occluded(const Ray* rays, const std::uint32_t* masks, std::size_t count, std::uint8_t* blocked,
                bool mixed_packets = false) const;
  /// A stream hands its incoherent runs to the stream walk (queries.wide) when it has at
  /// least this many such rays.
  static constexpr std::size_t kStreamWalkRays = 256;
  /// Whether this batch call's runs go as packets whatever their octants (closest hit, or
  /// `any_hit`): accel::runs_share_nodes (stream_plan.h) where the scene is one wide BVH
  /// whose runs may go as packets and the call has at least accel::kProbeMinRays rays.
  bool batch_runs_share_nodes(const Ray* rays, std::size_t count, bool any_hit) const;
  AccelInfo info() const;
  /// Every hit of the layers `mask` selects, instances included, appended to `out`
  /// attributed (geom, prim, inst) in no particular order (accel_crossings.cpp).
  void all_hits(const Ray& ray, std::uint32_t mask, std::vector<Hit>& out) const;
  /// all_hits of rays[0 .. count) into out[0 .. count) (stream.cpp: runs of 16 as packets
  /// where the stream policy says so).
  void all_hits(const Ray* rays, std::size_t count, std::vector<Hit>* out) const;
  /// The nearest surface point within sqrt(query.d2) (accel_points.cpp). Throws Error
  /// for instances and the plane test.
  ClosestPoint closest_point(core::PointQuery& query) const;
  /// closest_point for `count` points (accel_batches.cpp): in Morton order of their
  /// positions, each search first bounded by its predecessor's answer; out(i, answer).
  void closest_batch(const float* xyz, std::size_t count, int threads, float max_distance,
                     const std::function<void(std::size_t, const ClosestPoint&)>& out) const;
  /// closest_point of p bounded first by the distance to `previous`'s surface point.
  ClosestPoint closest_after(const float* p, float max_d2, const ClosestPoint& previous) const;

 private:
  /// load(): the geometry table into `geometries`, checked against itself and the meta
  /// chunk; `vertex_total` = the triangle geometries' vertices.
  void read_geometries(accel::file::Reader& in, const accel::file::Meta& meta,
                       std::span<const accel::file::GeometryRecord> records, std::uint64_t& vertex_total);
  /// save(): the meta chunk of the committed scene.
  accel::file::Meta meta_record() const;
  /// save(): a layer's record, its wide BVH's figures from `image`.
  static accel::file::LayerRecord layer_record(const Layer& l, const accel::WideImage& image);
  /// load(): the header's options (test, isa, robust, reference_double), checked against
  /// each other and this CPU.
  void read_options(accel::file::Reader& in);
  /// load(): the polygons rebuilt from their outlines (make_polygon checks each again).
  void read_polygons(accel::file::Reader& in, std::span<const std::uint32_t> sizes, std::span<const float> vertices);
  /// load(): one layer's record, excluded flags, nodes and blocks; its engines.
  void read_layer(accel::file::Reader& in, std::uint32_t mask, const std::shared_ptr<const accel::file::Mapping>& mapping);
  /// Whether triangle i has no area (in double with reference_double).
  bool flat(std::size_t i) const;
  /// attribute() for a scene of several geometries: a binary search of the first ids.
  void attribute_search(std::uint32_t& prim, std::uint32_t& geom) const;
  /// The lanes of `active` whose mask shares a bit with `mask`.
  static std::uint32_t lanes_of(std::uint32_t active, const std::uint32_t* masks, std::uint32_t mask) {
    if (!masks) return active;
    std::uint32_t out = 0;
    for (std::uint32_t b = active; b != 0; b &= b - 1) {
      const int i = __builtin_ctz(b);
      if (masks[i] & mask) out |= 1u << i;
    }
    return out;
  }
  /// The packet forms over the layers alone: a full packet without masks by the scene's
  /// own form (Queries), any other lane by lane's mask through widened copies.
  template <int K>
  void trace_packet(const RayPacket<K>& rays, HitPacket<K>& hits, const std::uint32_t* masks) const;
  template <int K>
  std::uint32_t occluded_by_layers(const RayPacket<K>& rays, const std::uint32_t* masks) const;
};

}  // namespace volley
