// Accel's private state: the geometry as added, and at commit one triangle engine (the
// wide SIMD BVH, the scalar oracle or the double reference: engine.h) and one polygon
// engine, each only when the scene has that kind, combined once: triangles, then polygons.
#pragma once
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "accel/accel_file.h"
#include "accel/engine.h"
#include "accel/wide_accel.h"
#include "core/bvh.h"
#include "core/polygon.h"
#include "volley/accel.h"
#include "volley/packet.h"

namespace volley {

struct Accel::Impl {
  /// One add_triangles / add_polygon call: its primitives have the internal ids first ..
  /// first + count (the engines answer with those; attribute() turns one back into the
  /// geometry and the index within it).
  struct Geometry {
    std::uint32_t first;  ///< internal id of its first primitive
    std::uint32_t count;  ///< primitives
    std::size_t index;    ///< its first primitive's place in triangle_ids or polygon_ids
    bool polygon;
    bool enabled = true;
    std::vector<std::uint32_t> indices;  ///< triangles: the vertex indices as added (update_vertices)
    std::size_t vertex_count = 0;        ///< triangles: the vertices the add call gave
    bool moved = false;                  ///< update_vertices was called on it (a deforming mesh)
  };

  // Input, in internal-id order of each kind.
  std::vector<glm::vec3> triangles;  ///< 3 vertices per triangle
  std::vector<std::uint32_t> triangle_ids;
  std::vector<core::Polygon> polygons;
  std::vector<std::uint32_t> polygon_ids;
  std::vector<Geometry> geometries;  ///< by geometry id
  std::uint32_t next_id = 0;

  // Committed state.
  bool committed = false;
  TriangleTest test = TriangleTest::watertight;
  Isa isa = Isa::scalar;
  bool robust = true;             ///< Options::robust: padded slab tests
  bool reference_double = false;  ///< Options::reference_double (isa == scalar only)
  double build_seconds = 0.0;
  std::size_t degenerate = 0;
  core::BvhStats triangle_stats;  ///< of the binary triangle BVH, as built (unit costs)
  std::size_t disabled = 0;       ///< geometries left out at the commit
  bool one_geometry = false;      ///< the committed scene has one geometry (hits need no search)
  // What decides between a refit and a build at the next commit (Options::refit).
  bool topology_changed = true;   ///< a geometry added, enabled or disabled since the last build
  bool vertices_changed = false;  ///< update_vertices since the last commit
  Options built_with;             ///< the options of the last build (isa resolved)
  std::vector<unsigned char> excluded;       ///< per triangle: left out of the BVH at the last build
  std::vector<unsigned char> excluded_flat;  ///< per triangle: left out as degenerate
  double built_sah = 0.0;         ///< triangle SAH cost at the last build
  double sah_now = 0.0;           ///< the same now (after refits)
  bool refitted = false;          ///< the last commit refitted
  std::unique_ptr<accel::TriangleEngine> triangle_engine;
  std::unique_ptr<accel::Engine> polygon_engine;
  std::vector<core::Polygon> enabled_polygons;  ///< what polygon_engine holds (enabled geometries)
  std::vector<std::uint32_t> enabled_polygon_ids;
  /// A loaded Accel's triangle input, still in the mapped file (Accel::load): unpack() copies
  /// it into the vectors above before anything reads them (a query does not).
  struct Packed {
    std::shared_ptr<const accel::file::Mapping> file;
    std::span<const float> vertices;  ///< the triangle geometries' vertices, geometry after geometry
    std::span<const std::uint32_t> indices;
    std::span<const unsigned char> excluded, excluded_flat;
  };
  std::optional<Packed> packed;
  std::size_t loaded_triangles = 0;  ///< the triangles while packed
  bool loaded = false;               ///< the structure came from a file (AccelInfo::loaded)
  double load_seconds = 0.0;

  /// The wide BVH when it holds the whole scene (no polygons), else null: Accel's single-ray
  /// queries and full packets call it directly (a layer of calls less).
  const accel::WideAccel* wide_only = nullptr;

  /// Registers the geometry of the next `count` ids and returns its id; uncommits.
  std::uint32_t new_geometry(std::uint32_t count, bool polygon);
  /// The geometry with id `geometry`; Error naming `caller` when there is none.
  Geometry& geometry_at(const char* caller, std::uint32_t geometry);
  /// An engine's answer (prim = internal id) as the API reports it: the geometry and the
  /// index within it. Leaves a miss as it is.
  void attribute(std::uint32_t& prim, std::uint32_t& geom) const {
    if (prim == kInvalidPrim) return;
    if (one_geometry) {
      geom = 0;
      return;
    }
    attribute_search(prim, geom);
  }

  /// Triangles added (also while packed).
  std::size_t triangle_count() const { return packed ? loaded_triangles : triangle_ids.size(); }
  /// Copies a loaded Accel's input out of the file (a no-op otherwise): called before the
  /// input is changed or built from.
  void unpack();
  /// Writes the committed structure and its input (accel_save.cpp).
  void save_to(const std::string& path) const;
  /// Fills a fresh Impl from a saved file, committed (accel_load.cpp). Throws Error.
  void load_from(const std::string& path);

  /// Builds every engine for the committed options (test, isa, robust, reference_double).
  void build();
  /// Refits the triangle engine to moved vertices when that is allowed and pays (see
  /// Options::refit); false (nothing built) when the caller must build instead.
  bool refit(const Options& options);
  /// Builds the polygon engine over the enabled polygon geometries (none: no engine).
  void build_polygons();
  /// Sets wide_only, one_geometry and the refit state after a build or a load.
  void finish_build();
  Hit intersect(const Ray& ray) const;
  bool occluded(const Ray& ray) const;
  template <int K>
  void intersect(const RayPacket<K>& rays, HitPacket<K>& hits) const;
  template <int K>
  std::uint32_t occluded(const RayPacket<K>& rays) const;
  /// The stream policy (stream.cpp): runs of 16 rays as packets where that pays.
  void intersect(const Ray* rays, std::size_t count, Hit* hits) const;
  void occluded(const Ray* rays, std::size_t count, std::uint8_t* blocked) const;
  AccelInfo info() const;

 private:
  /// load(): the geometry table into `geometries`, checked against itself and the meta
  /// chunk; `vertex_total` = the triangle geometries' vertices.
  void read_geometries(accel::file::Reader& in, const accel::file::Meta& meta,
                       std::span<const accel::file::GeometryRecord> records, std::uint64_t& vertex_total);
  /// Whether triangle i has no area (in double with reference_double).
  bool flat(std::size_t i) const;
  /// attribute() for a scene of several geometries: a binary search of the first ids.
  void attribute_search(std::uint32_t& prim, std::uint32_t& geom) const;
  template <int K>
  void trace_packet(const RayPacket<K>& rays, HitPacket<K>& hits) const;
};

}  // namespace volley
