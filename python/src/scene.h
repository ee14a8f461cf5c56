// volley.RaycastingScene: Open3D's RaycastingScene API (same names, arguments and answer
// dictionaries) over a volley::Accel, plus volley's own (options, info, instances, refit,
// save/load, pickling). The scene commits itself before the first query after a change,
// as Open3D's does.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>
#include <vector>

#include "volley/accel.h"

namespace volley::python {

namespace py = pybind11;

class RaycastingScene {
 public:
  /// `test`: "watertight" (default), "moller" or "plane"; `isa`: "auto" (default), "scalar",
  /// "sse4.2", "avx2" or "avx512"; `quality`: "medium" (default) or "high" (spatial splits).
  /// ValueError for another name. `build_threads`: the threads that build the structure
  /// (0: all cores; Open3D's constructor argument nthreads).
  RaycastingScene(const std::string& test, const std::string& isa, const std::string& quality = "medium",
                  int build_threads = 0);

  std::uint32_t add_triangles(const py::handle& vertices, const py::handle& triangles);
  std::uint32_t add_instance(const std::shared_ptr<RaycastingScene>& prototype, const py::handle& transform);
  void update_vertices(std::uint32_t geometry, const py::handle& vertices);
  void set_geometry_mask(std::uint32_t geometry, std::uint32_t mask);
  void disable_geometry(std::uint32_t geometry);
  void enable_geometry(std::uint32_t geometry);

  /// The ray queries; `masks`: None, or one uint32 mask per ray (a ray sees a geometry
  /// when their masks share a bit).
  py::dict cast_rays(const py::handle& rays, int nthreads, const py::object& masks, const py::object& exclude);
  py::array test_occlusions(const py::handle& rays, float tnear, float tfar, int nthreads, const py::object& masks,
                            const py::object& exclude);
  py::array count_intersections(const py::handle& rays, int nthreads, const py::object& masks);
  py::dict list_intersections(const py::handle& rays, int nthreads, const py::object& masks);
  py::dict compute_closest_points(const py::handle& points, int nthreads);
  py::array compute_distance(const py::handle& points, int nthreads);
  py::array compute_signed_distance(const py::handle& points, int nthreads, int nsamples);
  py::array compute_occupancy(const py::handle& points, int nthreads, int nsamples);

  py::dict info();
  std::size_t geometry_count() const { return geometries_.size(); }
  void save(const std::string& path);
  static std::shared_ptr<RaycastingScene> load(const std::string& path);
  /// Pickling: the options and every geometry's arrays (the structure is rebuilt).
  py::tuple get_state() const;
  static std::shared_ptr<RaycastingScene> from_state(const py::tuple& state);

 private:
  /// What add_triangles / add_instance was given, for normals and pickling.
  struct Geometry {
    std::vector<float> xyz;             ///< triangles: vertices
    std::vector<std::uint32_t> indices;  ///< triangles: 3 per triangle
    std::shared_ptr<RaycastingScene> prototype;  ///< instances
    float transform[12] = {};                    ///< instances: [A | t] row by row
    std::uint32_t mask = 0xffffffffu;
    bool enabled = true;
  };
  /// The Accel, committed with the options (after a change: built, or refitted).
  const Accel& committed();
  void require_geometry(const char* caller, std::uint32_t geometry) const;

  Options options_;
  int build_threads_ = 0;
  Accel accel_;
  bool dirty_ = true;
  bool loaded_ = false;  ///< from load(): geometry arrays unknown here (not picklable)
  std::vector<Geometry> geometries_;
};

}  // namespace volley::python
