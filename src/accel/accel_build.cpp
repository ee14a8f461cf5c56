// Accel::Impl at commit: the layers (one per geometry mask) built or refitted, and the
// facts info() reports.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "accel/accel_impl.h"
#include "core/triangle.h"
#include "simd/aligned.h"

namespace volley {
namespace {

core::BBox triangle_box(const glm::vec3* p) {
  core::BBox b;
  for (int k = 0; k < 3; ++k) b.extend(p[k]);
  return b;
}

}  // namespace

std::uint32_t Accel::Impl::new_geometry(std::uint32_t count, Kind kind) {
  if (added.geometries.size() >= kInvalidId) throw Error("add: the Accel holds the most geometries it can");
  const std::size_t index = kind == Kind::polygon    ? added.polygon_ids.size()
                            : kind == Kind::instance ? added.instances.size()
                                                     : added.triangle_ids.size();
  added.geometries.push_back({added.next_id, count, index, kind, true, {}, 0, false});
  built.committed = false;
  added.topology_changed = true;
  return static_cast<std::uint32_t>(added.geometries.size() - 1);
}

Accel::Impl::Geometry& Accel::Impl::geometry_at(const char* caller, std::uint32_t geometry) {
  if (geometry >= added.geometries.size())
    throw Error(std::string(caller) + ": geometry " + std::to_string(geometry) + " does not exist (ids 0 .. " +
                std::to_string(added.geometries.size()) + " exclusive were returned by add_triangles / add_polygon)");
  return added.geometries[geometry];
}

bool Accel::Impl::flat(std::size_t i) const {
  const glm::vec3* p = &added.triangles[3 * i];
  // The reference keeps what has area in double (a float cross product can round to 0).
  return built.reference_double
             ? core::is_degenerate<double>(core::Vec3<double>(p[0]), core::Vec3<double>(p[1]), core::Vec3<double>(p[2]))
             : core::is_degenerate(p[0], p[1], p[2]);
}

void Accel::Impl::attribute_search(std::uint32_t& prim, std::uint32_t& geom) const {
  // The last geometry with primitives whose first id is <= prim.
  const auto it =
      std::upper_bound(built.id_starts.begin(), built.id_starts.end(), prim,
                       [](std::uint32_t id, const std::pair<std::uint32_t, std::uint32_t>& s) { return id < s.first; });
  geom = (it - 1)->second;
  prim -= (it - 1)->first;
}

std::vector<std::uint32_t> Accel::Impl::layer_masks() const {
  std::vector<std::uint32_t> masks;
  for (const Geometry& g : added.geometries)
    if (g.enabled && g.mask != 0) masks.push_back(g.mask);
  std::sort(masks.begin(), masks.end(), std::greater<>());
  masks.erase(std::unique(masks.begin(), masks.end()), masks.end());
  return masks;
}

void Accel::Impl::exclude_others(Layer& layer) const {
  layer.excluded = built.excluded_flat;
  for (const Geometry& g : added.geometries)
    if (g.kind != Kind::polygon && (!g.enabled || g.mask != layer.mask))
      std::fill_n(layer.excluded.begin() + static_cast<std::ptrdiff_t>(g.index), g.count, 1);
}

void Accel::Impl::build() {
  const std::size_t n = added.triangle_ids.size();
  built.layers.clear();
  choose_queries();  // none of the old layers' engines is called from here on
  built.degenerate = 0;
  built.disabled = 0;
  // Triangles of moved geometries (update_vertices) go into the tree even when degenerate,
  // so that a refit finds them where a later move gives them area.
  std::vector<unsigned char> moving(n, 0);
  for (const Geometry& g : added.geometries) {
    if (g.moved) std::fill_n(moving.begin() + static_cast<std::ptrdiff_t>(g.index), g.count, 1);
    built.disabled += !g.enabled;
  }
  std::vector<unsigned char> is_degenerate(n, 0);
  built.excluded_flat.assign(n, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      is_degenerate[i] = flat(i);
      built.excluded_flat[i] = is_degenerate[i] && !moving[i];
    }
  });
  built.degenerate = static_cast<std::size_t>(std::count(is_degenerate.begin(), is_degenerate.end(), 1));

  for (const std::uint32_t mask : layer_masks()) {
    Layer& layer = built.layers.emplace_back();
    layer.mask = mask;
    build_layer(layer);
  }
  finish_build();
}

void Accel::Impl::build_layer(Layer& layer) {
  build_triangles(layer);
  build_polygons(layer);
}

void Accel::Impl::build_triangles(Layer& layer) {
  const bool has_triangles = std::any_of(added.geometries.begin(), added.geometries.end(), [&](const Geometry& g) {
    return g.enabled && g.kind == Kind::triangles && g.mask == layer.mask;
  });
  if (!has_triangles) return;
  const std::size_t n = added.triangle_ids.size();
  exclude_others(layer);
  // Triangles outside the layer and degenerate ones keep an empty box: no node holds them.
  simd::AlignedVector<core::BBox> boxes(n);  // huge pages: 24 MB for a million triangles
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i)
      if (!layer.excluded[i]) boxes[i] = triangle_box(&added.triangles[3 * i]);
  });
  accel::TriangleEngine* engine = layer.triangle_engine =
      layer.add(built.isa != Isa::scalar ? accel::make_wide_engine(built.test, built.isa, built.robust)
                : built.reference_double ? accel::make_reference_engine(built.test)
                                         : accel::make_oracle_engine(built.test, built.robust));
  core::Bvh bvh = built.quality == BuildQuality::high
                      ? core::build_bvh_spatial(boxes, added.triangles.data(), engine->bvh_options())
                      : core::build_bvh(boxes, engine->bvh_options());
  // Reported with unit costs (AccelInfo: node visit = 1, triangle test = 1).
  layer.triangle_stats = core::bvh_stats(bvh, core::BvhBuildOptions{});
  engine->build(std::move(bvh), {added.triangles.data(), added.triangle_ids.data(), n, layer.excluded.data()});
  layer.built_sah = layer.sah_now = engine->sah_cost();
}

void Accel::Impl::build_polygons(Layer& layer) {
  std::vector<core::Polygon> held;
  std::vector<std::uint32_t> ids;
  for (const Geometry& g : added.geometries)
    if (g.enabled && g.kind == Kind::polygon && g.mask == layer.mask) {
      held.push_back(added.polygons[g.index]);
      ids.push_back(added.polygon_ids[g.index]);
    }
  if (!held.empty()) layer.add(accel::make_polygon_engine(std::move(held), std::move(ids), built.robust));
}

void Accel::Impl::finish_build() {
  build_instances();
  compute_bound_parts();
  built.one_geometry = added.geometries.size() == 1 && added.geometries[0].kind != Kind::instance;
  built.id_starts.clear();
  for (std::size_t g = 0; g < added.geometries.size(); ++g)
    if (added.geometries[g].kind != Kind::instance && added.geometries[g].count != 0)
      built.id_starts.emplace_back(added.geometries[g].first, static_cast<std::uint32_t>(g));
  choose_queries();
  added.topology_changed = added.vertices_changed = built.refitted = false;
  built.built_with = Options{};
  built.built_with.test = built.test, built.built_with.isa = built.isa, built.built_with.robust = built.robust;
  built.built_with.reference_double = built.reference_double, built.built_with.quality = built.quality;
}

double Accel::Impl::built_sah() const {
  double sum = 0.0;
  for (const Layer& l : built.layers) sum += l.built_sah;
  return sum;
}

double Accel::Impl::sah_now() const {
  double sum = 0.0;
  for (const Layer& l : built.layers) sum += l.sah_now;
  return sum;
}

bool Accel::Impl::refit(const Options& options) {
  const bool same = options.test == built.built_with.test && options.isa == built.built_with.isa &&
                    options.robust == built.built_with.robust &&
                    options.reference_double == built.built_with.reference_double &&
                    options.quality == built.built_with.quality;
  const bool any_triangles = std::any_of(built.layers.begin(), built.layers.end(),
                                         [](const Layer& l) { return l.triangle_engine != nullptr; });
  if (!options.refit || !same || added.topology_changed || !added.vertices_changed || !any_triangles) return false;
  // A triangle the build left out as degenerate that now has area needs a build (which
  // puts every triangle of a moved geometry into the tree).
  const std::size_t n = added.triangle_ids.size();
  std::atomic<bool> gained_area{false};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end() && !gained_area.load(std::memory_order_relaxed); ++i)
      if (built.excluded_flat[i] && !flat(i)) gained_area = true;
  });
  if (gained_area) return false;
  // The wide BVH's blocks name triangles by internal id: the same as the triangle's place
  // unless polygons came in between (ids rise, so the last one tells).
  std::vector<std::uint32_t> index_of;
  if (added.triangle_ids.back() != n - 1) {
    index_of.assign(added.next_id, 0);
    for (std::size_t i = 0; i < n; ++i) index_of[added.triangle_ids[i]] = static_cast<std::uint32_t>(i);
  }
  for (Layer& l : built.layers)
    if (l.triangle_engine)
      l.sah_now = l.triangle_engine->refit({added.triangles.data(), added.triangle_ids.data(), n, l.excluded.data()},
                                           index_of.empty() ? nullptr : index_of.data());
  if (!(sah_now() <= kRefitRebuildGrowth * built_sah())) return false;
  compute_bound_parts();
  added.vertices_changed = false;
  built.refitted = true;
  return true;
}

AccelInfo Accel::Impl::info() const {
  AccelInfo info;
  info.triangles = triangle_count();
  info.loaded = mapped.loaded;
  info.load_seconds = mapped.loaded ? mapped.load_seconds : 0.0;
  info.degenerate = built.degenerate;
  info.polygons = added.polygons.size();
  info.geometries = added.geometries.size();
  info.disabled = built.disabled;
  info.layers = built.layers.size();
  info.instances = added.instances.size();
  for (const Instance& in : added.instances) info.instanced_triangles += in.prototype->triangle_count();
  info.refitted = built.refitted;
  info.sah_growth = built_sah() > 0.0 ? sah_now() / built_sah() : 1.0;
  info.test = built.test;
  info.isa = built.isa;
  info.robust = built.robust;
  info.reference_double = built.reference_double;
  info.quality = built.quality;
  info.build_seconds = built.build_seconds;
  // One layer as its engines describe it; several: the counts summed, the costs and the
  // shape of the layer with the most nodes.
  std::size_t most_nodes = 0;
  for (const Layer& l : built.layers) {
    AccelInfo part = info;
    part.nodes = part.leaves = part.depth = part.bytes = part.blocks = part.references = 0;
    if (l.triangle_stats.nodes != 0) part.binary_sah_cost = l.triangle_stats.sah_cost;
    for (const auto& engine : l.engines)
      if (engine.get() != l.triangle_engine || l.triangle_stats.nodes != 0) engine->describe(part);
    const std::size_t nodes = info.nodes + part.nodes, leaves = info.leaves + part.leaves,
                      bytes = info.bytes + part.bytes, blocks = info.blocks + part.blocks,
                      references = info.references + part.references;
    const std::size_t depth = std::max(info.depth, part.depth);
    if (part.nodes >= most_nodes) {
      most_nodes = part.nodes;
      info = part;
    }
    info.nodes = nodes, info.leaves = leaves, info.bytes = bytes, info.blocks = blocks, info.depth = depth;
    info.references = references;
  }
  // Instances: their records and BVHs (the prototypes' structures are theirs, shared).
  info.bytes += added.instances.size() * (sizeof(Instance) + sizeof(Geometry));
  for (const Layer& l : built.layers) info.bytes += l.instance_tree.bytes();
  return info;
}

}  // namespace volley
