#include "scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include "arrays.h"
#include "ray_batches.h"

namespace volley::python {
namespace {

void check_threads(int nthreads) {
  if (nthreads < 0) throw py::value_error("nthreads: expected 0 (all cores) or a positive count, got " + std::to_string(nthreads));
}

void check_samples(int nsamples) {
  if (nsamples < 1) throw py::value_error("nsamples: expected 1 or more (volley needs one ray: the extra are ignored)");
}

/// The point queries with one float per point: `points` checked and converted, then
/// fill(accel, xyz, n, out) without the GIL into an array shaped like the points' rows.
template <class Fill>
py::array float_per_point(const py::handle& points, int nthreads, const Accel& accel, Fill&& fill) {
  check_threads(nthreads);
  std::vector<py::ssize_t> lead;
  const FloatArray p = as_float_rows(points, "query_points", 3, lead);
  auto out = new_array<float>(lead);
  {
    py::gil_scoped_release free;
    fill(accel, p.data(), rows_of(lead), out.mutable_data());
  }
  return out;
}

/// A rays argument (..., 6) checked and converted, with its leading shape and row count
/// (nthreads checked too: every ray query takes both).
/// With a mask per ray when `masks` is not None (a C-ordered uint32 array of one per ray:
/// volley/raycasting_scene.py checks the values and the shape).
struct RaysIn {
  FloatArray rows;
  std::vector<py::ssize_t> lead;
  std::size_t n = 0;
  IndexArray mask_array;
  const std::uint32_t* masks = nullptr;
  /// (geometry, primitive, instance) per ray when `exclude` is not None (the excluding forms).
  IndexArray exclude_array;
  const std::uint32_t* exclude = nullptr;
};

RaysIn rays_in(const py::handle& rays, int nthreads, const py::object& masks,
               const py::object& exclude = py::none()) {
  check_threads(nthreads);
  RaysIn in;
  in.rows = as_float_rows(rays, "rays", 6, in.lead);
  in.n = rows_of(in.lead);
  if (!masks.is_none()) {
    in.mask_array = IndexArray::ensure(masks);
    if (!in.mask_array || std::size_t(in.mask_array.size()) != in.n)
      throw py::value_error("masks: expected one uint32 mask per ray (" + std::to_string(in.n) + ")");
    in.masks = in.mask_array.data();
  }
  if (!exclude.is_none()) {
    in.exclude_array = IndexArray::ensure(exclude);
    if (!in.exclude_array || std::size_t(in.exclude_array.size()) != 3 * in.n)
      throw py::value_error("exclude: expected (geometry, primitive, instance) per ray (" + std::to_string(in.n) + ")");
    in.exclude = in.exclude_array.data();
  }
  return in;
}

TriangleTest parse_test(const std::string& s) {
  if (auto t = parse_triangle_test(s)) return *t;
  throw py::value_error("test: expected \"watertight\", \"moller\" or \"plane\", got \"" + s + "\"");
}

Isa parse_isa_name(const std::string& s) {
  if (s == "auto") return Isa::automatic;
  if (auto i = volley::parse_isa(s)) return *i;
  throw py::value_error("isa: expected \"auto\", \"scalar\", \"sse4.2\", \"avx2\" or \"avx512\", got \"" + s + "\"");
}

BuildQuality parse_quality(const std::string& s) {
  if (auto q = parse_build_quality(s)) return *q;
  throw py::value_error("quality: expected \"medium\" or \"high\", got \"" + s + "\"");
}

}  // namespace

RaycastingScene::RaycastingScene(const std::string& test, const std::string& isa, const std::string& quality,
                                 int build_threads)
    : build_threads_(build_threads) {
  check_threads(build_threads);
  options_.test = parse_test(test);
  options_.isa = parse_isa_name(isa);
  options_.quality = parse_quality(quality);
}

void RaycastingScene::require_geometry(const char* caller, std::uint32_t geometry) const {
  if (geometry >= geometries_.size())
    throw py::value_error(std::string(caller) + ": geometry " + std::to_string(geometry) + " does not exist (the scene has " +
                          std::to_string(geometries_.size()) + ")");
}

std::uint32_t RaycastingScene::add_triangles(const py::handle& vertices, const py::handle& triangles) {
  std::vector<py::ssize_t> lead;
  const FloatArray v = as_float_rows(vertices, "vertices", 3, lead);
  if (lead.size() != 1) throw py::value_error("vertices: expected shape (N, 3)");
  const std::size_t nv = rows_of(lead);
  for (std::size_t i = 0; i < 3 * nv; ++i)
    if (!std::isfinite(v.data()[i]))
      throw py::value_error("vertices: row " + std::to_string(i / 3) + " has a NaN or infinite coordinate");
  const IndexArray t = as_triangles(triangles, "triangles", nv);
  Geometry g;
  g.xyz.assign(v.data(), v.data() + 3 * nv);
  g.indices.assign(t.data(), t.data() + t.size());
  const std::uint32_t id = accel_.add_triangles(g.xyz.data(), nv, g.indices.data(), g.indices.size() / 3);
  geometries_.push_back(std::move(g));
  dirty_ = true;
  return id;
}

std::uint32_t RaycastingScene::add_instance(const std::shared_ptr<RaycastingScene>& prototype, const py::handle& transform) {
  if (!prototype) throw py::value_error("prototype: expected a RaycastingScene");
  const py::array_t<float, py::array::c_style | py::array::forcecast> m = py::array::ensure(transform);
  if (!m || m.ndim() != 2 || m.shape(1) != 4 || (m.shape(0) != 3 && m.shape(0) != 4))
    throw py::value_error("transform: expected shape (3, 4) or (4, 4): [A | t] row by row");
  Geometry g;
  std::memcpy(g.transform, m.data(), sizeof g.transform);
  g.prototype = prototype;
  const std::uint32_t id = accel_.add_instance(prototype->committed(), g.transform);
  geometries_.push_back(std::move(g));
  dirty_ = true;
  return id;
}

void RaycastingScene::update_vertices(std::uint32_t geometry, const py::handle& vertices) {
  require_geometry("update_vertices", geometry);
  std::vector<py::ssize_t> lead;
  const FloatArray v = as_float_rows(vertices, "vertices", 3, lead);
  accel_.update_vertices(geometry, v.data(), rows_of(lead));  // Error (count, NaN) -> ValueError
  geometries_[geometry].xyz.assign(v.data(), v.data() + v.size());
  dirty_ = true;
}

void RaycastingScene::set_geometry_mask(std::uint32_t geometry, std::uint32_t mask) {
  require_geometry("set_geometry_mask", geometry);
  accel_.set_geometry_mask(geometry, mask);
  geometries_[geometry].mask = mask;
  dirty_ = true;
}

void RaycastingScene::disable_geometry(std::uint32_t geometry) {
  require_geometry("disable_geometry", geometry);
  accel_.disable_geometry(geometry);
  geometries_[geometry].enabled = false;
  dirty_ = true;
}

void RaycastingScene::enable_geometry(std::uint32_t geometry) {
  require_geometry("enable_geometry", geometry);
  accel_.enable_geometry(geometry);
  geometries_[geometry].enabled = true;
  dirty_ = true;
}

const Accel& RaycastingScene::committed() {
  if (dirty_) {
    // commit builds on the arena it is called in: all cores, or an arena of build_threads_.
    if (build_threads_ > 0) accel::arena_of(build_threads_).execute([&] { accel_.commit(options_); });
    else accel_.commit(options_);
    dirty_ = false;
  }
  return accel_;
}

py::dict RaycastingScene::cast_rays(const py::handle& rays, int nthreads, const py::object& masks,
                                    const py::object& exclude) {
  const RaysIn in = rays_in(rays, nthreads, masks, exclude);
  const std::vector<py::ssize_t>& lead = in.lead;
  const std::size_t n = in.n;
  const Accel& accel = committed();
  auto t = new_array<float>(lead);
  auto geometry_ids = new_array<std::uint32_t>(lead), primitive_ids = new_array<std::uint32_t>(lead);
  auto uvs = new_array<float>(lead, {2}), normals = new_array<float>(lead, {3});
  const HitColumns columns{t.mutable_data(), geometry_ids.mutable_data(), primitive_ids.mutable_data(),
                           uvs.mutable_data(), normals.mutable_data()};
  {
    py::gil_scoped_release free;
    for_ray_pieces(in.rows.data(), n, nthreads, 0.0f, kInf, [&](const Ray* piece, std::size_t b, std::size_t m) {
      // Uninitialised: the stream call writes every hit, misses included.
      alignas(64) unsigned char storage[kPiece * sizeof(Hit)];
      Hit* hits = reinterpret_cast<Hit*>(storage);
      if (in.exclude) {
        Hit excluded[kPiece];
        excluded_hits(in.exclude, b, m, excluded);
        accel.intersect(piece, m, hits, QueryArguments{in.masks ? in.masks + b : nullptr, excluded, 1});
      } else {
        accel.intersect(piece, m, hits, QueryArguments{in.masks ? in.masks + b : nullptr, nullptr, 1});
      }
      write_hits(accel, hits, b, m, columns);
    });
  }
  py::dict out;
  out["t_hit"] = t, out["geometry_ids"] = geometry_ids, out["primitive_ids"] = primitive_ids;
  out["primitive_uvs"] = uvs, out["primitive_normals"] = normals;
  return out;
}

py::array RaycastingScene::test_occlusions(const py::handle& rays, float tnear, float tfar, int nthreads,
                                           const py::object& masks, const py::object& exclude) {
  const RaysIn in = rays_in(rays, nthreads, masks, exclude);
  const std::vector<py::ssize_t>& lead = in.lead;
  const std::size_t n = in.n;
  const Accel& accel = committed();
  auto out = new_array<bool>(lead);
  bool* po = out.mutable_data();
  {
    py::gil_scoped_release free;
    static_assert(sizeof(bool) == 1, "numpy bool is one byte");
    for_ray_pieces(in.rows.data(), n, nthreads, tnear, tfar, [&](const Ray* piece, std::size_t b, std::size_t m) {
      auto* blocked = reinterpret_cast<std::uint8_t*>(po + b);
      Hit excluded[kPiece];
      if (in.exclude) excluded_hits(in.exclude, b, m, excluded);
      accel.occluded(piece, m, blocked, QueryArguments{in.masks ? in.masks + b : nullptr, in.exclude ? excluded : nullptr, 1});
    });
  }
  return out;
}

py::array RaycastingScene::count_intersections(const py::handle& rays, int nthreads, const py::object& masks) {
  const RaysIn in = rays_in(rays, nthreads, masks);
  const std::vector<py::ssize_t>& lead = in.lead;
  const std::size_t n = in.n;
  const Accel& accel = committed();
  auto out = new_array<std::int32_t>(lead);
  std::uint32_t* counts = reinterpret_cast<std::uint32_t*>(out.mutable_data());
  {
    py::gil_scoped_release free;
    for_ray_pieces(in.rows.data(), n, nthreads, 0.0f, kInf, [&](const Ray* piece, std::size_t b, std::size_t m) {
      if (!in.masks) return accel.count_intersections(piece, m, counts + b, 1);
      for (std::size_t i = 0; i < m; ++i) counts[b + i] = accel.count_intersections(piece[i], in.masks[b + i]);
    });
  }
  return out;
}

py::dict RaycastingScene::list_intersections(const py::handle& rays, int nthreads, const py::object& masks) {
  const RaysIn in = rays_in(rays, nthreads, masks);
  const std::size_t n = in.n;
  const Accel& accel = committed();
  HitLists lists;
  {
    py::gil_scoped_release free;
    std::vector<Ray> all(n);  // the whole batch: intersect_all's C++ form takes it at once
    rows_to_rays(in.rows.data(), n, 0, n, 0.0f, kInf, all.data());
    lists = in.masks ? masked_hit_lists(accel, all.data(), in.masks, n, nthreads) : accel.intersect_all(all.data(), n, nthreads);
  }
  const auto k = static_cast<py::ssize_t>(lists.hits.size());
  py::array_t<std::uint32_t> splits(static_cast<py::ssize_t>(n + 1)), ray_ids(k), geometry_ids(k), primitive_ids(k);
  py::array_t<float> t(k), uvs(std::vector<py::ssize_t>{k, 2});
  for (std::size_t i = 0; i <= n; ++i) splits.mutable_data()[i] = static_cast<std::uint32_t>(lists.offsets[i]);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t h = lists.offsets[i]; h < lists.offsets[i + 1]; ++h) ray_ids.mutable_data()[h] = static_cast<std::uint32_t>(i);
  for (py::ssize_t h = 0; h < k; ++h) {
    const Hit& x = lists.hits[h];
    geometry_ids.mutable_data()[h] = x.geom, primitive_ids.mutable_data()[h] = x.prim, t.mutable_data()[h] = x.t;
    uvs.mutable_data()[2 * h] = x.u, uvs.mutable_data()[2 * h + 1] = x.v;
  }
  py::dict out;
  out["ray_splits"] = splits, out["ray_ids"] = ray_ids, out["geometry_ids"] = geometry_ids;
  out["primitive_ids"] = primitive_ids, out["primitive_uvs"] = uvs, out["t_hit"] = t;
  return out;
}

py::dict RaycastingScene::compute_closest_points(const py::handle& points, int nthreads) {
  check_threads(nthreads);
  std::vector<py::ssize_t> lead;
  const FloatArray p = as_float_rows(points, "query_points", 3, lead);
  const Accel& accel = committed();
  const std::size_t n = rows_of(lead);
  auto pts = new_array<float>(lead, {3}), uvs = new_array<float>(lead, {2}), normals = new_array<float>(lead, {3});
  auto geometry_ids = new_array<std::uint32_t>(lead), primitive_ids = new_array<std::uint32_t>(lead);
  float *pp = pts.mutable_data(), *puv = uvs.mutable_data(), *pn = normals.mutable_data();
  std::uint32_t *pg = geometry_ids.mutable_data(), *pprim = primitive_ids.mutable_data();
  {
    py::gil_scoped_release free;
    Scratch<ClosestPoint> scratch(n);
    ClosestPoint* cp = scratch.data();
    accel.closest_points(p.data(), n, cp, kInf, nthreads);
    parallel(n, nthreads, [&](std::size_t b, std::size_t e) {
      Hit hits[kPiece];
      for (std::size_t i = b; i < e; ++i) {
        for (int k = 0; k < 3; ++k) pp[3 * i + k] = cp[i].found() ? cp[i].point[k] : kInf;
        puv[2 * i] = cp[i].u, puv[2 * i + 1] = cp[i].v;
        pg[i] = cp[i].geom, pprim[i] = cp[i].prim;
        hits[i - b] = Hit{cp[i].distance, cp[i].u, cp[i].v, cp[i].prim, cp[i].geom};
      }
      // Open3D's convention: zeros for the normal of nothing found (and, as its cross
      // products give, of a degenerate triangle).
      accel.geometric_normals(hits, e - b, pn + 3 * b, 1);
      for (std::size_t i = 3 * b; i < 3 * e; ++i) pn[i] = std::isnan(pn[i]) ? 0.0f : pn[i];
    });
  }
  py::dict out;
  out["points"] = pts, out["geometry_ids"] = geometry_ids, out["primitive_ids"] = primitive_ids;
  out["primitive_uvs"] = uvs, out["primitive_normals"] = normals;
  return out;
}

py::array RaycastingScene::compute_distance(const py::handle& points, int nthreads) {
  return float_per_point(points, nthreads, committed(), [&](const Accel& a, const float* xyz, std::size_t n, float* out) {
    a.distances(xyz, n, out, false, nthreads);
  });
}

py::array RaycastingScene::compute_signed_distance(const py::handle& points, int nthreads, int nsamples) {
  check_samples(nsamples);
  return float_per_point(points, nthreads, committed(), [&](const Accel& a, const float* xyz, std::size_t n, float* out) {
    a.distances(xyz, n, out, true, nthreads);
  });
}

py::array RaycastingScene::compute_occupancy(const py::handle& points, int nthreads, int nsamples) {
  check_samples(nsamples);
  return float_per_point(points, nthreads, committed(), [&](const Accel& a, const float* xyz, std::size_t n, float* out) {
    std::vector<std::uint8_t> inside(n);
    a.contains(xyz, n, inside.data(), nthreads);
    for (std::size_t i = 0; i < n; ++i) out[i] = inside[i] ? 1.0f : 0.0f;
  });
}

py::dict RaycastingScene::info() {
  const AccelInfo i = committed().info();
  py::dict d;
  d["triangles"] = i.triangles, d["degenerate"] = i.degenerate, d["geometries"] = i.geometries;
  d["instances"] = i.instances, d["instanced_triangles"] = i.instanced_triangles, d["layers"] = i.layers;
  d["nodes"] = i.nodes, d["leaves"] = i.leaves, d["depth"] = i.depth, d["bytes"] = i.bytes;
  d["sah_cost"] = i.sah_cost, d["build_seconds"] = i.build_seconds, d["load_seconds"] = i.load_seconds;
  d["loaded"] = i.loaded, d["refitted"] = i.refitted, d["width"] = i.width, d["block_width"] = i.block_width;
  d["test"] = std::string(to_string(i.test)), d["isa"] = std::string(to_string(i.isa)), d["robust"] = i.robust;
  d["quality"] = std::string(to_string(i.quality)), d["references"] = i.references;
  return d;
}

void RaycastingScene::save(const std::string& path) { committed().save(path); }

std::shared_ptr<RaycastingScene> RaycastingScene::load(const std::string& path) {
  auto s = std::make_shared<RaycastingScene>("watertight", "auto");
  s->accel_ = Accel::load(path);
  const AccelInfo i = s->accel_.info();
  s->options_.test = i.test, s->options_.isa = i.isa, s->options_.quality = i.quality;
  s->geometries_.resize(i.geometries);
  s->loaded_ = true;
  s->dirty_ = false;
  return s;
}

py::tuple RaycastingScene::get_state() const {
  if (loaded_) throw py::value_error("a scene from load() keeps no arrays to pickle: pickle the scene it was saved from");
  py::list geometries;
  for (const Geometry& g : geometries_) {
    py::dict d;
    if (g.prototype) {
      d["prototype"] = g.prototype;
      d["transform"] = py::array_t<float>(std::vector<py::ssize_t>{3, 4}, g.transform);
    } else {
      d["vertices"] = py::array_t<float>(std::vector<py::ssize_t>{py::ssize_t(g.xyz.size() / 3), 3}, g.xyz.data());
      d["triangles"] = py::array_t<std::uint32_t>(std::vector<py::ssize_t>{py::ssize_t(g.indices.size() / 3), 3}, g.indices.data());
    }
    d["mask"] = g.mask, d["enabled"] = g.enabled;
    geometries.append(d);
  }
  const std::string isa = options_.isa == Isa::automatic ? "auto" : std::string(to_string(options_.isa));
  return py::make_tuple(1, std::string(to_string(options_.test)), isa, geometries,
                        std::string(to_string(options_.quality)));
}

std::shared_ptr<RaycastingScene> RaycastingScene::from_state(const py::tuple& state) {
  // Version 1 with the build quality as a fifth item (pickles from before it have four: medium).
  if ((state.size() != 4 && state.size() != 5) || state[0].cast<int>() != 1)
    throw py::value_error("not a pickled volley.RaycastingScene (version 1)");
  auto s = std::make_shared<RaycastingScene>(state[1].cast<std::string>(), state[2].cast<std::string>(),
                                             state.size() == 5 ? state[4].cast<std::string>() : "medium");
  for (const py::handle& item : state[3].cast<py::list>()) {
    const py::dict d = item.cast<py::dict>();
    const std::uint32_t id = d.contains("prototype")
                                 ? s->add_instance(d["prototype"].cast<std::shared_ptr<RaycastingScene>>(), d["transform"])
                                 : s->add_triangles(d["vertices"], d["triangles"]);
    if (d["mask"].cast<std::uint32_t>() != 0xffffffffu) s->set_geometry_mask(id, d["mask"].cast<std::uint32_t>());
    if (!d["enabled"].cast<bool>()) s->disable_geometry(id);
  }
  return s;
}

}  // namespace volley::python
