// Accel::load: maps a file Accel::save wrote and checks it as untrusted input (accel_file.h
// checks the header and the checksum; here every count, id and index is checked against
// the others before anything uses it) before the wide BVH is queried where it lies.
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "accel/accel_file.h"
#include "accel/accel_impl.h"
#include "accel/wide/wide_accel.h"
#include "core/polygon.h"
#include "simd/isa/dispatch.h"

namespace volley {
namespace {

bool is_bool(std::uint32_t x) { return x <= 1; }

}  // namespace

void Accel::Impl::read_geometries(accel::file::Reader& in, const accel::file::Meta& meta,
                                  std::span<const accel::file::GeometryRecord> records, std::uint64_t& vertex_total) {
  std::vector<Geometry>& out = added.geometries;
  if (records.size() != meta.geometries) in.fail("the geometry table does not match the meta chunk");
  std::uint64_t id = 0, triangles = 0, polygons = 0, disabled = 0;
  vertex_total = 0;
  out.reserve(records.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    const accel::file::GeometryRecord& r = records[i];
    const std::string which = "geometry " + std::to_string(i);
    if (!is_bool(r.polygon) || !is_bool(r.enabled) || !is_bool(r.moved) || (r.polygon && r.moved))
      in.fail(which + " has invalid flags");
    if (r.first != id) in.fail(which + " starts at id " + std::to_string(r.first) + ", expected " + std::to_string(id));
    if (r.count > std::uint64_t{kInvalidPrim} - 1 - id) in.fail(which + " has too many primitives");
    if (r.polygon ? (r.count != 1 || r.index != polygons || r.vertex_count != 0)
                  : (r.index != triangles || r.vertex_count > (std::uint64_t{1} << 40)))
      in.fail(which + " does not follow the ones before it");
    (r.polygon ? polygons : triangles) += r.count;
    disabled += !r.enabled;
    id += r.count;
    out.push_back({r.first, r.count, static_cast<std::size_t>(r.index), r.polygon != 0 ? Kind::polygon : Kind::triangles, r.enabled != 0, {},
                   static_cast<std::size_t>(r.vertex_count), r.moved != 0, r.mask});
    out.back().packed_vertices = static_cast<std::size_t>(vertex_total);
    if (!r.polygon) vertex_total += r.vertex_count;
  }
  if (triangles != meta.triangles || polygons != meta.polygons || id != meta.next_id || disabled != meta.disabled ||
      meta.degenerate > meta.triangles)
    in.fail("the geometry table's counts do not match the meta chunk");
}

void Accel::Impl::read_options(accel::file::Reader& in) {
  const accel::file::Header& h = in.header();
  if (h.test > static_cast<std::uint32_t>(TriangleTest::watertight) || h.isa > static_cast<std::uint32_t>(Isa::avx512) ||
      h.isa == static_cast<std::uint32_t>(Isa::automatic) || !is_bool(h.robust) || !is_bool(h.reference_double))
    in.fail("the header's options are not valid");
  built.test = static_cast<TriangleTest>(h.test);
  built.isa = static_cast<Isa>(h.isa);
  built.robust = h.robust != 0;
  built.reference_double = h.reference_double != 0;
  if (built.reference_double && (built.isa != Isa::scalar || !built.robust))
    in.fail("reference_double with a SIMD ISA or plain slabs");
  if (!simd::cpu_has(built.isa))
    in.fail("built for " + std::string(to_string(built.isa)) +
            ", which this CPU lacks (build the structure here, or save it with an ISA this CPU has)");
}

void Accel::Impl::read_polygons(accel::file::Reader& in, std::span<const std::uint32_t> sizes,
                                std::span<const float> vertices) {
  std::size_t at = 0;
  for (const Geometry& g : added.geometries) {
    if (g.kind != Kind::polygon) continue;
    const std::uint32_t n = sizes[added.polygons.size()];
    if (n > (vertices.size() - at) / 3) in.fail("the polygon outlines run past their chunk");
    std::vector<glm::vec3> outline(n);
    for (std::uint32_t i = 0; i < n; ++i, at += 3) outline[i] = {vertices[at], vertices[at + 1], vertices[at + 2]};
    try {
      added.polygons.push_back(core::make_polygon(std::move(outline)));
    } catch (const std::invalid_argument& e) {
      in.fail("polygon geometry " + std::to_string(&g - added.geometries.data()) + ": " + e.what());
    }
  }
  if (at != vertices.size()) in.fail("the polygon outlines do not fill their chunk");
}

void Accel::Impl::load_from(const std::string& path) {
  namespace file = accel::file;
  auto mapping = std::make_shared<const file::Mapping>(path);
  file::Reader in(mapping, path);
  read_options(in);

  const file::Meta& meta = in.one<file::Meta>(file::Tag::meta);
  if (meta.quality > static_cast<std::uint32_t>(BuildQuality::high)) in.fail("the build quality is not valid");
  built.quality = static_cast<BuildQuality>(meta.quality);
  std::uint64_t vertex_total = 0;
  read_geometries(in, meta, in.next<file::GeometryRecord>(file::Tag::geometries), vertex_total);
  const auto vertices = in.next<float>(file::Tag::vertices, [&](std::span<const float> slab) {
    for (const float x : slab)
      if (!std::isfinite(x)) in.fail("a triangle vertex is not finite");
  });
  // The indices, geometry after geometry, each below its geometry's vertex count.
  auto geometry = added.geometries.begin();
  std::uint64_t left = 0;  // indices of *geometry still to come
  const auto indices = in.next<std::uint32_t>(file::Tag::indices, [&](std::span<const std::uint32_t> slab) {
    for (std::size_t k = 0; k < slab.size();) {
      while (left == 0) {
        if (geometry == added.geometries.end()) in.fail("more triangle indices than triangles");
        if (geometry->kind == Kind::triangles && geometry->count != 0) {
          left = 3 * std::uint64_t{geometry->count};
        } else {
          ++geometry;
        }
      }
      const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(left, slab.size() - k));
      std::uint32_t largest = 0;
      for (std::size_t i = k; i < k + n; ++i) largest = std::max(largest, slab[i]);
      if (n != 0 && largest >= geometry->vertex_count)
        in.fail("geometry " + std::to_string(geometry - added.geometries.begin()) + " has a vertex index out of range");
      k += n, left -= n;
      if (left == 0) ++geometry;
    }
  });
  const auto polygon_sizes = in.next<std::uint32_t>(file::Tag::polygon_sizes);
  const auto polygon_vertices = in.next<float>(file::Tag::polygon_vertices);
  const auto excluded_flat_in = in.next<unsigned char>(file::Tag::excluded_flat);
  if (vertices.size() != 3 * vertex_total || indices.size() != 3 * meta.triangles ||
      polygon_sizes.size() != meta.polygons || excluded_flat_in.size() != meta.triangles)
    in.fail("the input chunks' sizes do not match the geometry table");
  for (const Geometry& g : added.geometries)
    if (g.kind == Kind::polygon) added.polygon_ids.push_back(g.first);
  added.next_id = static_cast<std::uint32_t>(meta.next_id);

  read_polygons(in, polygon_sizes, polygon_vertices);

  // The layers: the masks of the geometry table, in the order a build makes them.
  const std::vector<std::uint32_t> masks = layer_masks();
  if (meta.layers != masks.size()) in.fail("the layer count does not match the geometries' masks");
  for (const std::uint32_t mask : masks) read_layer(in, mask, mapping);
  in.finish();

  built.degenerate = meta.degenerate;
  built.disabled = meta.disabled;
  mapped.packed = Packed{mapping, vertices, indices, excluded_flat_in};
  mapped.loaded_triangles = meta.triangles;
  if (built.isa == Isa::scalar) {
    // The oracle's structures are for checking, not speed: rebuilt from the input.
    unpack();
    build();
  } else {
    for (Layer& l : built.layers) build_polygons(l);
    finish_build();
  }
  built.refitted = meta.refitted != 0;
  built.build_seconds = meta.build_seconds;
  mapped.loaded = true;
  built.committed = true;
}

void Accel::Impl::read_layer(accel::file::Reader& in, std::uint32_t mask,
                             const std::shared_ptr<const accel::file::Mapping>& mapping) {
  namespace file = accel::file;
  const file::Header& h = in.header();
  const file::LayerRecord& r = in.one<file::LayerRecord>(file::Tag::layer);
  const bool has_triangles = std::any_of(added.geometries.begin(), added.geometries.end(), [&](const Geometry& g) {
    return g.enabled && g.kind != Kind::polygon && g.mask == mask;
  });
  if (r.mask != mask || r.has_triangles != (has_triangles ? 1u : 0u))
    in.fail("a layer record does not match the geometries' masks");
  // The wide BVH: its blocks' triangle ids checked while they are read, its tree after.
  std::unique_ptr<accel::WideAccel> wide;
  if (built.isa != Isa::scalar && has_triangles) {
    wide = accel::WideAccel::create(built.test, built.isa, built.robust);
    if (h.node_bytes != sizeof(simd::WideNode<simd::kWideN>) || h.block_bytes != wide->block_bytes())
      in.fail("the wide BVH's node or block size does not match this build of volley");
  }
  const auto nodes = in.next<unsigned char>(file::Tag::nodes);
  const std::size_t block_bytes = wide ? wide->block_bytes() : 1;
  std::size_t blocks_seen = 0;
  const accel::ImageIds ids{added.next_id, &added.polygon_ids};
  const auto blocks = in.next_items(file::Tag::blocks, block_bytes, [&](std::span<const unsigned char> slab) {
    if (!wide) in.fail("triangle blocks in a layer that has none");
    const std::size_t count = slab.size() / block_bytes;
    try {
      accel::check_block_ids(slab.data(), count, blocks_seen, *wide, ids);
    } catch (const std::invalid_argument& e) {
      in.fail(e.what());
    }
    blocks_seen += count;
  });
  if (!wide && (!nodes.empty() || !blocks.empty())) in.fail("wide nodes in a layer that has none");
  if (nodes.size() % sizeof(simd::WideNode<simd::kWideN>) != 0) in.fail("the nodes chunk holds part of a node");
  if (built.isa == Isa::scalar) return;  // rebuilt

  Layer& layer = built.layers.emplace_back();
  layer.mask = mask;
  layer.built_sah = r.built_sah;
  layer.sah_now = r.sah_now;
  if (!wide) return;
  accel::WideImage image;
  image.nodes = nodes.data(), image.node_count = nodes.size() / sizeof(simd::WideNode<simd::kWideN>);
  image.blocks = blocks.data(), image.block_count = blocks.size() / block_bytes;
  image.block_bytes = block_bytes;
  image.root = r.root;
  image.stats = {r.wide_nodes,     r.wide_leaves,        r.wide_depth,    r.wide_blocks,        r.wide_triangles,
                 r.wide_mean_children, r.wide_sah_cost, r.wide_block_sah_cost, r.wide_bytes};
  image.owner = mapping;
  try {
    wide->adopt(std::move(image));
  } catch (const std::invalid_argument& e) {
    in.fail(e.what());
  }
  layer.triangle_engine = layer.add(accel::make_wide_engine(std::move(wide)));
  layer.triangle_stats = {r.bvh_nodes, r.bvh_leaves, r.bvh_depth, r.bvh_sah_cost, r.bvh_mean_leaf_size, r.bvh_bytes};
}

}  // namespace volley
