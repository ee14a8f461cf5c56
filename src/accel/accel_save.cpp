// Accel::save: the committed structure and the input it was built from, as accel_file.h
// lays them out; and unpack(), which brings a loaded Accel's input back into its vectors.
#include <cstring>
#include <vector>

#include "accel/accel_file.h"
#include "accel/accel_impl.h"
#include "accel/wide/wide_accel.h"

namespace volley {

accel::file::Meta Accel::Impl::meta_record() const {
  accel::file::Meta meta{};
  meta.geometries = added.geometries.size();
  meta.triangles = triangle_count();
  meta.polygons = added.polygons.size();
  meta.next_id = added.next_id;
  meta.degenerate = built.degenerate;
  meta.disabled = built.disabled;
  meta.layers = built.layers.size();
  meta.build_seconds = built.build_seconds;
  meta.refitted = built.refitted;
  meta.quality = static_cast<std::uint32_t>(built.quality);
  return meta;
}

accel::file::LayerRecord Accel::Impl::layer_record(const Layer& l, const accel::WideImage& image) {
  accel::file::LayerRecord r{};
  r.mask = l.mask;
  r.root = image.root;
  r.has_triangles = l.triangle_engine != nullptr;
  r.built_sah = l.built_sah;
  r.sah_now = l.sah_now;
  r.bvh_nodes = l.triangle_stats.nodes, r.bvh_leaves = l.triangle_stats.leaves;
  r.bvh_depth = l.triangle_stats.depth, r.bvh_bytes = l.triangle_stats.bytes;
  r.bvh_sah_cost = l.triangle_stats.sah_cost, r.bvh_mean_leaf_size = l.triangle_stats.mean_leaf_size;
  const simd::WideStats& w = image.stats;
  r.wide_nodes = w.nodes, r.wide_leaves = w.leaves, r.wide_depth = w.depth;
  r.wide_blocks = w.blocks, r.wide_triangles = w.triangles, r.wide_bytes = w.bytes;
  r.wide_mean_children = w.mean_children, r.wide_sah_cost = w.sah_cost, r.wide_block_sah_cost = w.block_sah_cost;
  return r;
}

void Accel::Impl::save_to(const std::string& path) const {
  namespace file = accel::file;
  const file::Meta meta = meta_record();

  std::vector<file::GeometryRecord> records;
  std::vector<std::uint32_t> polygon_sizes;
  std::vector<float> polygon_vertices;
  for (const Geometry& g : added.geometries) {
    records.push_back({g.first, g.count, g.index, g.vertex_count, g.kind == Kind::polygon, g.enabled, g.moved, g.mask});
    if (g.kind != Kind::polygon) continue;
    const std::vector<glm::vec3>& v = added.polygons[g.index].vertices;
    polygon_sizes.push_back(static_cast<std::uint32_t>(v.size()));
    for (const glm::vec3& p : v) polygon_vertices.insert(polygon_vertices.end(), {p.x, p.y, p.z});
  }

  // The triangle input: each geometry's vertex array (rebuilt from its triangles: a vertex
  // no triangle uses is 0) and its indices.
  std::vector<float> vertices;
  std::vector<std::uint32_t> indices;
  std::span<const float> vertices_out;
  std::span<const std::uint32_t> indices_out;
  std::span<const unsigned char> excluded_flat_out(built.excluded_flat);
  if (mapped.packed) {
    vertices_out = mapped.packed->vertices, indices_out = mapped.packed->indices,
    excluded_flat_out = mapped.packed->excluded_flat;
  } else {
    for (const Geometry& g : added.geometries) {
      if (g.kind == Kind::polygon) continue;
      const std::size_t base = vertices.size();
      vertices.resize(base + 3 * g.vertex_count, 0.0f);
      for (std::size_t k = 0; k < g.indices.size(); ++k)
        std::memcpy(&vertices[base + 3 * std::size_t{g.indices[k]}], &added.triangles[3 * g.index + k],
                    3 * sizeof(float));
      indices.insert(indices.end(), g.indices.begin(), g.indices.end());
    }
    vertices_out = vertices, indices_out = indices;
  }

  file::Header header{};
  header.test = static_cast<std::uint32_t>(built.test);
  header.isa = static_cast<std::uint32_t>(built.isa);
  header.robust = built.robust;
  header.reference_double = built.reference_double;
  header.node_bytes = built.isa != Isa::scalar ? sizeof(simd::WideNode<simd::kWideN>) : 0;
  header.block_bytes = 0;

  file::Writer out(path);
  out.chunk(file::Tag::meta, &meta, sizeof meta);
  out.chunk(file::Tag::geometries, std::span<const file::GeometryRecord>(records));
  out.chunk(file::Tag::vertices, vertices_out);
  out.chunk(file::Tag::indices, indices_out);
  out.chunk(file::Tag::polygon_sizes, std::span<const std::uint32_t>(polygon_sizes));
  out.chunk(file::Tag::polygon_vertices, std::span<const float>(polygon_vertices));
  out.chunk(file::Tag::excluded_flat, excluded_flat_out);
  for (const Layer& l : built.layers) {
    const accel::WideAccel* wide = l.triangle_engine ? l.triangle_engine->wide() : nullptr;
    const accel::WideImage image = wide ? wide->image() : accel::WideImage{};
    if (wide) header.block_bytes = static_cast<std::uint32_t>(image.block_bytes);
    const file::LayerRecord r = layer_record(l, image);
    out.chunk(file::Tag::layer, &r, sizeof r);
    out.chunk(file::Tag::nodes, image.nodes, image.node_count * sizeof(simd::WideNode<simd::kWideN>));
    out.chunk(file::Tag::blocks, image.blocks, image.block_count * image.block_bytes);
  }
  out.finish(header);
}

void Accel::Impl::unpack() {
  if (!mapped.packed) return;
  const Packed p = *mapped.packed;
  const std::size_t n = mapped.loaded_triangles;
  added.triangles.resize(3 * n);
  added.triangle_ids.resize(n);
  const float* v = p.vertices.data();
  const std::uint32_t* idx = p.indices.data();
  for (Geometry& g : added.geometries) {
    if (g.kind == Kind::polygon) continue;
    g.indices.assign(idx, idx + 3 * std::size_t{g.count});
    for (std::size_t k = 0; k < g.indices.size(); ++k) {
      const float* x = v + 3 * std::size_t{g.indices[k]};
      added.triangles[3 * g.index + k] = {x[0], x[1], x[2]};
    }
    for (std::uint32_t t = 0; t < g.count; ++t) added.triangle_ids[g.index + t] = g.first + t;
    idx += 3 * std::size_t{g.count};
    v += 3 * g.vertex_count;
  }
  built.excluded_flat.assign(p.excluded_flat.begin(), p.excluded_flat.end());
  mapped.packed.reset();
  for (Layer& l : built.layers)
    if (l.triangle_engine) exclude_others(l);
}

}  // namespace volley
