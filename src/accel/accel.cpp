// Accel: the embeddable kernel. Holds triangles and polygons, builds one BVH per
// primitive kind at commit (none for a kind the scene lacks), answers queries.
#include "volley/accel.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "accel/accel_impl.h"
#include "accel/parallel.h"
#include "simd/isa/dispatch.h"

namespace volley {

Accel::Accel() : impl_(std::make_shared<Impl>()) {}
Accel::~Accel() = default;
Accel::Accel(Accel&&) noexcept = default;
Accel& Accel::operator=(Accel&&) noexcept = default;

std::uint32_t Accel::add_triangles(const float* xyz, std::size_t vertex_count,
                                   const std::uint32_t* indices, std::size_t triangle_count) {
  for (std::size_t i = 0; i < 3 * vertex_count; ++i)
    if (!std::isfinite(xyz[i]))
      throw Error("add_triangles: vertex " + std::to_string(i / 3) + " has a non-finite coordinate");
  // Validate every index first, so a rejected call adds nothing.
  for (std::size_t i = 0; i < 3 * triangle_count; ++i)
    if (indices[i] >= vertex_count)
      throw Error("add_triangles: triangle " + std::to_string(i / 3) + " uses vertex index " +
                  std::to_string(indices[i]) + ", but there are only " + std::to_string(vertex_count) +
                  " vertices");
  if (triangle_count > std::size_t{kInvalidPrim} - 1 - impl_->added.next_id)
    throw Error("add_triangles: " + std::to_string(triangle_count) + " triangles more than the " +
                std::to_string(kInvalidPrim - 1) + " primitives an Accel holds (it has " +
                std::to_string(impl_->added.next_id) + ")");
  impl_->unpack();
  const std::uint32_t geometry = impl_->new_geometry(static_cast<std::uint32_t>(triangle_count), Impl::Kind::triangles);
  impl_->added.geometries.back().indices.assign(indices, indices + 3 * triangle_count);
  impl_->added.geometries.back().vertex_count = vertex_count;
  auto& tris = impl_->added.triangles;
  tris.reserve(tris.size() + 3 * triangle_count);
  impl_->added.triangle_ids.reserve(impl_->added.triangle_ids.size() + triangle_count);
  for (std::size_t t = 0; t < triangle_count; ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t idx = indices[3 * t + k];
      tris.emplace_back(xyz[3 * idx], xyz[3 * idx + 1], xyz[3 * idx + 2]);
    }
    impl_->added.triangle_ids.push_back(impl_->added.next_id++);
  }
  return geometry;
}

std::uint32_t Accel::add_polygon(const float* xyz, std::size_t vertex_count) {
  if (impl_->added.next_id >= kInvalidPrim - 1)
    throw Error("add_polygon: the Accel holds " + std::to_string(impl_->added.next_id) +
                " primitives, the most it can");
  std::vector<glm::vec3> verts(vertex_count);
  for (std::size_t i = 0; i < vertex_count; ++i) verts[i] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
  core::Polygon polygon;
  try {
    polygon = core::make_polygon(std::move(verts));
  } catch (const std::invalid_argument& e) {
    throw Error(std::string("add_polygon: ") + e.what());
  }
  const std::uint32_t geometry = impl_->new_geometry(1, Impl::Kind::polygon);
  impl_->added.polygons.push_back(std::move(polygon));
  impl_->added.polygon_ids.push_back(impl_->added.next_id++);
  return geometry;
}

void Accel::disable_geometry(std::uint32_t geometry) {
  Impl::Geometry& g = impl_->geometry_at("disable_geometry", geometry);
  impl_->added.topology_changed |= g.enabled;
  g.enabled = false;
  impl_->built.committed = false;
}

void Accel::enable_geometry(std::uint32_t geometry) {
  Impl::Geometry& g = impl_->geometry_at("enable_geometry", geometry);
  impl_->added.topology_changed |= !g.enabled;
  g.enabled = true;
  impl_->built.committed = false;
}

void Accel::set_geometry_mask(std::uint32_t geometry, std::uint32_t mask) {
  Impl::Geometry& g = impl_->geometry_at("set_geometry_mask", geometry);
  impl_->added.topology_changed |= g.mask != mask;
  g.mask = mask;
  impl_->built.committed = false;
}

void Accel::update_vertices(std::uint32_t geometry, const float* xyz, std::size_t vertex_count) {
  Impl::Geometry& g = impl_->geometry_at("update_vertices", geometry);
  if (g.kind != Impl::Kind::triangles)
    throw Error("update_vertices: geometry " + std::to_string(geometry) + " is " +
                (g.kind == Impl::Kind::polygon ? "a polygon" : "an instance") + ", not triangles");
  if (vertex_count != g.vertex_count)
    throw Error("update_vertices: geometry " + std::to_string(geometry) + " was added with " +
                std::to_string(g.vertex_count) + " vertices, got " + std::to_string(vertex_count) +
                " (the topology stays: add a new geometry to change it)");
  for (std::size_t i = 0; i < 3 * vertex_count; ++i)
    if (!std::isfinite(xyz[i]))
      throw Error("update_vertices: vertex " + std::to_string(i / 3) + " has a non-finite coordinate");
  impl_->unpack();
  glm::vec3* out = impl_->added.triangles.data() + 3 * g.index;
  for (std::size_t k = 0; k < g.indices.size(); ++k) {
    const std::uint32_t idx = g.indices[k];
    out[k] = {xyz[3 * idx], xyz[3 * idx + 1], xyz[3 * idx + 2]};
  }
  g.moved = true;
  impl_->added.vertices_changed = true;
  impl_->built.committed = false;
}

void Accel::commit(const Options& options) {
  const auto start = std::chrono::steady_clock::now();
  Isa isa = Isa::scalar;
  try {
    isa = simd::resolve_isa(options.isa);
  } catch (const std::invalid_argument& e) {
    throw Error(e.what());
  }
  // Checked before anything changes, so a rejected commit leaves the Accel as it was.
  if (options.reference_double && isa != Isa::scalar)
    throw Error("commit: reference_double runs the scalar oracle in double precision and needs Isa::scalar, got " +
                std::string(to_string(isa)) + (options.isa == Isa::automatic ? " (from Isa::automatic)" : ""));
  if (options.quality != BuildQuality::medium && options.quality != BuildQuality::high)
    throw Error("commit: quality is not a BuildQuality (medium or high)");
  if (options.reference_double && !options.robust)
    throw Error("commit: reference_double traverses with robust slabs; robust = false contradicts it");
  Options resolved = options;
  resolved.isa = isa;
  impl_->built.isa = isa;
  impl_->built.test = options.test;
  impl_->built.robust = options.robust;
  impl_->built.reference_double = options.reference_double;
  impl_->built.quality = options.quality;
  // A build that fails half way leaves no structure to query: uncommitted until it is done.
  impl_->built.committed = false;
  try {
    impl_->unpack();
    if (!impl_->refit(resolved)) impl_->build();
  } catch (const std::bad_alloc&) {
    throw OutOfMemory("commit: out of memory building the structure of " + std::to_string(impl_->triangle_count()) +
                      " triangles and " + std::to_string(impl_->added.polygons.size()) +
                      " polygons; the Accel stays uncommitted (free memory, then commit again)");
  }
  impl_->built.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  impl_->mapped.loaded = false;
  impl_->built.committed = true;
}

Hit Accel::intersect(const Ray& ray) const {
  if (!impl_->built.committed) throw Error("intersect: call commit() after adding geometry");
  return impl_->intersect(ray);
}

bool Accel::occluded(const Ray& ray) const {
  if (!impl_->built.committed) throw Error("occluded: call commit() after adding geometry");
  return impl_->occluded(ray);
}

Hit Accel::intersect(const Ray& ray, std::uint32_t mask) const {
  if (!impl_->built.committed) throw Error("intersect: call commit() after adding geometry");
  return impl_->intersect(ray, mask);
}

bool Accel::occluded(const Ray& ray, std::uint32_t mask) const {
  if (!impl_->built.committed) throw Error("occluded: call commit() after adding geometry");
  return impl_->occluded(ray, mask);
}

template <int K>
void Accel::intersect(const RayPacket<K>& rays, HitPacket<K>& hits) const {
  if (!impl_->built.committed) throw Error("intersect: call commit() after adding geometry");
  impl_->intersect(rays, hits, nullptr);
}

template <int K>
std::uint32_t Accel::occluded(const RayPacket<K>& rays) const {
  if (!impl_->built.committed) throw Error("occluded: call commit() after adding geometry");
  return impl_->occluded(rays, nullptr);
}

template <int K>
void Accel::intersect(const RayPacket<K>& rays, HitPacket<K>& hits, const std::uint32_t* masks) const {
  if (!impl_->built.committed) throw Error("intersect: call commit() after adding geometry");
  if (!masks) throw Error("intersect: masks is null (pass K ray masks, or use the call without masks)");
  impl_->intersect(rays, hits, masks);
}

template <int K>
std::uint32_t Accel::occluded(const RayPacket<K>& rays, const std::uint32_t* masks) const {
  if (!impl_->built.committed) throw Error("occluded: call commit() after adding geometry");
  if (!masks) throw Error("occluded: masks is null (pass K ray masks, or use the call without masks)");
  return impl_->occluded(rays, masks);
}

namespace {

/// Runs trace(begin, end) over a stream of `count` rays on `threads` (Accel's batch rule),
/// in pieces of whole runs of 16 (the stream policy's runs stay as on one thread), each
/// thread's share handed on at most kPiece rays at a time: the rays the stream policy
/// copies aside and their answers then stay in cache, on one thread as on many.
template <class Trace>
void stream_pieces(const char* caller, std::size_t count, int threads, Trace&& trace) {
  constexpr std::size_t kRun = 16;
  constexpr std::size_t kPiece = 4096;
  accel::for_chunks(
      caller, (count + kRun - 1) / kRun, threads,
      [&](std::size_t r0, std::size_t r1) {
        const std::size_t end = std::min(count, r1 * kRun);
        for (std::size_t b = r0 * kRun; b < end; b += kPiece) trace(b, std::min(end, b + kPiece));
      },
      64);
}

/// The arguments of the rays from `first` on.
QueryArguments offset(const QueryArguments& args, std::size_t first) {
  QueryArguments out = args;
  if (out.masks) out.masks += first;
  if (out.excluded) out.excluded += first;
  return out;
}

}  // namespace

void Accel::intersect(const Ray* rays, std::size_t count, Hit* hits, int threads) const {
  if (!impl_->built.committed) throw Error("intersect: call commit() after adding geometry");
  const bool mixed = impl_->batch_runs_share_nodes(rays, count, false);
  stream_pieces("intersect", count, threads,
                [&](std::size_t b, std::size_t e) { impl_->intersect(rays + b, nullptr, e - b, hits + b, mixed); });
}

void Accel::occluded(const Ray* rays, std::size_t count, std::uint8_t* blocked, int threads) const {
  if (!impl_->built.committed) throw Error("occluded: call commit() after adding geometry");
  const bool mixed = impl_->batch_runs_share_nodes(rays, count, true);
  stream_pieces("occluded", count, threads,
                [&](std::size_t b, std::size_t e) { impl_->occluded(rays + b, nullptr, e - b, blocked + b, mixed); });
}

void Accel::intersect(const Ray* rays, const std::uint32_t* masks, std::size_t count, Hit* hits, int threads) const {
  if (!impl_->built.committed) throw Error("intersect: call commit() after adding geometry");
  if (!masks && count != 0) throw Error("intersect: masks is null (pass one mask per ray, or use the call without masks)");
  const bool mixed = impl_->batch_runs_share_nodes(rays, count, false);
  stream_pieces("intersect", count, threads,
                [&](std::size_t b, std::size_t e) { impl_->intersect(rays + b, masks + b, e - b, hits + b, mixed); });
}

void Accel::occluded(const Ray* rays, const std::uint32_t* masks, std::size_t count, std::uint8_t* blocked,
                     int threads) const {
  if (!impl_->built.committed) throw Error("occluded: call commit() after adding geometry");
  if (!masks && count != 0) throw Error("occluded: masks is null (pass one mask per ray, or use the call without masks)");
  const bool mixed = impl_->batch_runs_share_nodes(rays, count, true);
  stream_pieces("occluded", count, threads,
                [&](std::size_t b, std::size_t e) { impl_->occluded(rays + b, masks + b, e - b, blocked + b, mixed); });
}

void Accel::intersect(const Ray* rays, std::size_t count, Hit* hits, const QueryArguments& args) const {
  if (!args.excluded) {
    if (args.masks) return intersect(rays, args.masks, count, hits, args.threads);
    return intersect(rays, count, hits, args.threads);
  }
  if (!impl_->built.committed) throw Error("intersect: call commit() after adding geometry");
  if (count != 0 && (!rays || !hits)) throw Error("intersect: rays or hits is null (pass count of each)");
  const std::vector<std::uint32_t> ids = impl_->excluded_ids("intersect", args.excluded, count);
  stream_pieces("intersect", count, args.threads, [&](std::size_t b, std::size_t e) {
    impl_->intersect_excluding(rays + b, offset(args, b), ids.data() + b, e - b, hits + b);
  });
}

void Accel::occluded(const Ray* rays, std::size_t count, std::uint8_t* blocked, const QueryArguments& args) const {
  if (!args.excluded) {
    if (args.masks) return occluded(rays, args.masks, count, blocked, args.threads);
    return occluded(rays, count, blocked, args.threads);
  }
  if (!impl_->built.committed) throw Error("occluded: call commit() after adding geometry");
  if (count != 0 && (!rays || !blocked)) throw Error("occluded: rays or blocked is null (pass count of each)");
  const std::vector<std::uint32_t> ids = impl_->excluded_ids("occluded", args.excluded, count);
  stream_pieces("occluded", count, args.threads, [&](std::size_t b, std::size_t e) {
    impl_->occluded_excluding(rays + b, offset(args, b), ids.data() + b, e - b, blocked + b);
  });
}

WalkCounts Accel::walk_counts(const Ray& ray, bool any_hit) const {
  if (!impl_->built.committed) throw Error("walk_counts: call commit() after adding geometry");
  const accel::WideAccel* wide = impl_->built.queries.wide;
  if (!wide) throw Error("walk_counts: only for a scene of triangles in one layer, without instances, on a SIMD ISA");
  return wide->walk_counts(ray, any_hit);
}

// The packet widths of the API.
template void Accel::intersect<4>(const RayPacket<4>&, HitPacket<4>&) const;
template void Accel::intersect<8>(const RayPacket<8>&, HitPacket<8>&) const;
template void Accel::intersect<16>(const RayPacket<16>&, HitPacket<16>&) const;
template std::uint32_t Accel::occluded<4>(const RayPacket<4>&) const;
template std::uint32_t Accel::occluded<8>(const RayPacket<8>&) const;
template std::uint32_t Accel::occluded<16>(const RayPacket<16>&) const;
template void Accel::intersect<4>(const RayPacket<4>&, HitPacket<4>&, const std::uint32_t*) const;
template void Accel::intersect<8>(const RayPacket<8>&, HitPacket<8>&, const std::uint32_t*) const;
template void Accel::intersect<16>(const RayPacket<16>&, HitPacket<16>&, const std::uint32_t*) const;
template std::uint32_t Accel::occluded<4>(const RayPacket<4>&, const std::uint32_t*) const;
template std::uint32_t Accel::occluded<8>(const RayPacket<8>&, const std::uint32_t*) const;
template std::uint32_t Accel::occluded<16>(const RayPacket<16>&, const std::uint32_t*) const;

AccelInfo Accel::info() const { return impl_->info(); }

void Accel::save(const std::string& path) const {
  if (!impl_->built.committed) throw Error("save: call commit() first (only a committed structure is saved)");
  if (!impl_->added.instances.empty())
    throw Error("save: this Accel holds instances, which are not saved: save each prototype, and add the instances "
                "to a new Accel after loading them");
  impl_->save_to(path);
}

Accel Accel::load(const std::string& path) {
  const auto start = std::chrono::steady_clock::now();
  Accel accel;
  try {
    accel.impl_->load_from(path);
  } catch (const std::bad_alloc&) {
    throw OutOfMemory("load: " + path + ": out of memory");
  }
  accel.impl_->mapped.load_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return accel;
}

}  // namespace volley
