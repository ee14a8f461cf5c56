// The _volley extension module: volley.RaycastingScene and the mesh loader, with volley's
// C++ errors turned into Python's (volley::Error -> ValueError, OutOfMemory -> MemoryError,
// a file that cannot be read -> OSError).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <limits>

#include "io/load_error.h"
#include "io/scene_loader.h"
#include "files.h"
#include "scene.h"
#include "volley/volley.h"

namespace py = pybind11;
using volley::python::RaycastingScene;

namespace {

/// The triangles of a mesh file (.obj, .ply) or scene (.json) through volley's loaders:
/// (vertices (N, 3) float32, triangles (M, 3) uint32), every object merged.
py::tuple read_triangle_mesh(const std::string& path) {
  const volley::io::SceneDesc desc = volley::io::load_scene(path, "");
  const auto& m = desc.mesh;
  py::array_t<float> v(std::vector<py::ssize_t>{py::ssize_t(m.positions.size()), 3});
  for (std::size_t i = 0; i < m.positions.size(); ++i)
    for (int k = 0; k < 3; ++k) v.mutable_data()[3 * i + k] = m.positions[i][k];
  py::array_t<std::uint32_t> t(std::vector<py::ssize_t>{py::ssize_t(m.indices.size() / 3), 3});
  std::copy(m.indices.begin(), m.indices.end(), t.mutable_data());
  return py::make_tuple(v, t);
}

}  // namespace

PYBIND11_MODULE(_volley, m) {
  m.doc() = "volley: a SIMD ray tracing kernel (closest hits, occlusion, every hit, inside/outside, distances)";
  m.attr("INVALID_ID") = py::int_(0xffffffffu);
  m.attr("__version__") = std::string(volley_version());

  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const volley::OutOfMemory& e) {
      PyErr_SetString(PyExc_MemoryError, e.what());
    } catch (const volley::io::LoadError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    } catch (const volley::Error& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });

  volley::python::bind_files(m);
  m.def("read_triangle_mesh", &read_triangle_mesh, py::arg("path"),
        "Reads a mesh (.obj, .ply) or scene (.json) with volley's loaders: (vertices (N, 3) float32, triangles (M, 3) uint32).");

  const float inf = std::numeric_limits<float>::infinity();
  // The engine under volley.RaycastingScene (python/volley/raycasting_scene.py, which gives
  // it Open3D's exact surface: keywords, overloads, signatures and docstrings).
  py::class_<RaycastingScene, std::shared_ptr<RaycastingScene>>(m, "Engine", R"doc(
The engine of volley.RaycastingScene (use that class): ray casting and point queries on triangle meshes, with Open3D's RaycastingScene API:
add meshes, then cast rays or query points; the scene builds itself before the first query
after a change. Rays are arrays (..., 6) of origin and direction, points (..., 3), of any
real dtype (converted to float32 once). Misses: t_hit inf, ids INVALID_ID. Batch calls
release the GIL and use all cores (nthreads=0) or nthreads threads.)doc")
      .def(py::init<const std::string&, const std::string&, const std::string&, int>(), py::arg("test") = "watertight",
           py::arg("isa") = "auto", py::arg("quality") = "medium", py::arg("build_threads") = 0,
           "test: 'watertight' (default), 'moller' or 'plane'; isa: 'auto', 'scalar', 'sse4.2', 'avx2', 'avx512'; "
           "quality: 'medium' (binned SAH, default) or 'high' (also spatial splits: slower to build, faster rays "
           "where triangles are long; medium's answers but for ties that rounding decides)")
      .def("add_triangles", &RaycastingScene::add_triangles, py::arg("vertices"), py::arg("triangles"),
           "Adds a mesh: vertices (N, 3), triangles (M, 3) vertex indices. Returns its geometry id.")
      .def("add_instance", &RaycastingScene::add_instance, py::arg("prototype"), py::arg("transform"),
           "Places another scene under an affine transform ((3, 4) or (4, 4) [A | t]). Returns its geometry id.")
      .def("update_vertices", &RaycastingScene::update_vertices, py::arg("geometry"), py::arg("vertices"),
           "Moves a mesh's vertices (same count); the next query refits the structure.")
      .def("set_geometry_mask", &RaycastingScene::set_geometry_mask, py::arg("geometry"), py::arg("mask"))
      .def("disable_geometry", &RaycastingScene::disable_geometry, py::arg("geometry"))
      .def("enable_geometry", &RaycastingScene::enable_geometry, py::arg("geometry"))
      .def("cast_rays", &RaycastingScene::cast_rays, py::arg("rays"), py::arg("nthreads") = 0, py::arg("masks") = py::none(),
           py::arg("exclude") = py::none(),
           "Closest hits: dict of t_hit, geometry_ids, primitive_ids, primitive_uvs, primitive_normals.")
      .def("test_occlusions", &RaycastingScene::test_occlusions, py::arg("rays"), py::arg("tnear") = 0.0f,
           py::arg("tfar") = inf, py::arg("nthreads") = 0, py::arg("masks") = py::none(),
           py::arg("exclude") = py::none(), "Whether anything lies on each ray in [tnear, tfar): bool array.")
      .def("count_intersections", &RaycastingScene::count_intersections, py::arg("rays"), py::arg("nthreads") = 0,
           py::arg("masks") = py::none(),
           "Every surface crossing along each ray, each shared edge or vertex counted once: int32 array.")
      .def("list_intersections", &RaycastingScene::list_intersections, py::arg("rays"), py::arg("nthreads") = 0,
           py::arg("masks") = py::none(),
           "Every hit: dict of ray_splits (rays + 1), ray_ids, geometry_ids, primitive_ids, primitive_uvs, t_hit.")
      .def("compute_closest_points", &RaycastingScene::compute_closest_points, py::arg("query_points"),
           py::arg("nthreads") = 0,
           "Nearest surface points: dict of points, geometry_ids, primitive_ids, primitive_uvs, primitive_normals.")
      .def("compute_distance", &RaycastingScene::compute_distance, py::arg("query_points"), py::arg("nthreads") = 0)
      .def("compute_signed_distance", &RaycastingScene::compute_signed_distance, py::arg("query_points"),
           py::arg("nthreads") = 0, py::arg("nsamples") = 1,
           "Distance, negative inside (one ray's crossing parity; nsamples is accepted for Open3D's API and not needed).")
      .def("compute_occupancy", &RaycastingScene::compute_occupancy, py::arg("query_points"), py::arg("nthreads") = 0,
           py::arg("nsamples") = 1, "1.0 inside, 0.0 outside (float32), by one ray's crossing parity.")
      .def("geometry_count", &RaycastingScene::geometry_count, "Geometries added (ids 0 to count - 1).")
      .def("info", &RaycastingScene::info, "Facts about the built structure (triangles, nodes, bytes, ISA, ...).")
      .def("save", &RaycastingScene::save, py::arg("path"), "Writes the built structure (RaycastingScene.load maps it back).")
      .def_static("load", &RaycastingScene::load, py::arg("path"))
      .def(py::pickle([](const RaycastingScene& s) { return s.get_state(); },
                      [](const py::tuple& t) { return RaycastingScene::from_state(t); }));
}
