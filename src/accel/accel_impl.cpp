#include "accel/accel_impl.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/triangle.h"
#include "simd/aligned.h"

namespace volley {
namespace {

core::BBox triangle_box(const glm::vec3* p) {
  core::BBox b;
  for (int k = 0; k < 3; ++k) b.extend(p[k]);
  return b;
}

/// Copies the active lanes of `p` into a 16-lane packet; every other lane is inert and
/// inactive. The kernels load and store whole chunks of lanes, so a packet with inactive
/// lanes reaches them only as this copy: the caller's inactive lanes are never read (they
/// may be uninitialised) nor written (they may be another thread's).
template <int K>
void widen(const RayPacket<K>& p, RayPacket<16>& out) {
  const std::uint32_t active = p.active & lane_bits(K);
  for (int i = 0; i < 16; ++i) {
    if (i < K && (active >> i & 1u)) {
      out.ox[i] = p.ox[i], out.oy[i] = p.oy[i], out.oz[i] = p.oz[i];
      out.dx[i] = p.dx[i], out.dy[i] = p.dy[i], out.dz[i] = p.dz[i];
      out.tmin[i] = p.tmin[i], out.tmax[i] = p.tmax[i];
    } else {
      out.ox[i] = out.oy[i] = out.oz[i] = out.dx[i] = out.dy[i] = out.dz[i] = out.tmin[i] = 0.0f;
      out.tmax[i] = -INFINITY;
    }
  }
  out.active = active;
}

/// Whether the engines may take the caller's packet as it is: 16 lanes, all active.
template <int K>
bool all_lanes_active(const RayPacket<K>& p) {
  return K == 16 && (p.active & lane_bits(K)) == lane_bits(K);
}

}  // namespace

std::uint32_t Accel::Impl::new_geometry(std::uint32_t count, bool polygon) {
  if (geometries.size() >= kInvalidId) throw Error("add: the Accel holds the most geometries it can");
  geometries.push_back({next_id, count, polygon ? polygon_ids.size() : triangle_ids.size(), polygon, true, {}, 0, false});
  committed = false;
  topology_changed = true;
  return static_cast<std::uint32_t>(geometries.size() - 1);
}

Accel::Impl::Geometry& Accel::Impl::geometry_at(const char* caller, std::uint32_t geometry) {
  if (geometry >= geometries.size())
    throw Error(std::string(caller) + ": geometry " + std::to_string(geometry) + " does not exist (ids 0 .. " +
                std::to_string(geometries.size()) + " exclusive were returned by add_triangles / add_polygon)");
  return geometries[geometry];
}

bool Accel::Impl::flat(std::size_t i) const {
  const glm::vec3* p = &triangles[3 * i];
  // The reference keeps what has area in double (a float cross product can round to 0).
  return reference_double ? core::is_degenerate<double>(core::Vec3<double>(p[0]), core::Vec3<double>(p[1]),
                                                        core::Vec3<double>(p[2]))
                          : core::is_degenerate(p[0], p[1], p[2]);
}

void Accel::Impl::attribute_search(std::uint32_t& prim, std::uint32_t& geom) const {
  // The last geometry whose first id is <= prim (empty geometries share their first id with
  // the next one; the search passes them).
  const auto it = std::upper_bound(geometries.begin(), geometries.end(), prim,
                                   [](std::uint32_t id, const Geometry& g) { return id < g.first; });
  const auto g = it - 1;
  geom = static_cast<std::uint32_t>(g - geometries.begin());
  prim -= g->first;
}

void Accel::Impl::build() {
  const std::size_t n = triangle_ids.size();
  triangle_engine.reset();
  polygon_engine.reset();
  wide_only = nullptr;
  triangle_stats = {};
  degenerate = 0;
  disabled = 0;
  // Triangles of disabled geometries keep an empty box: no node holds them. Those of moved
  // geometries (update_vertices) go into the tree even when degenerate, so that a refit
  // finds them where a later move gives them area.
  std::vector<unsigned char> left_out(n, 0), moving(n, 0);
  for (const Geometry& g : geometries) {
    if (g.moved) std::fill_n(moving.begin() + static_cast<std::ptrdiff_t>(g.index), g.count, 1);
    if (g.enabled) continue;
    ++disabled;
    if (!g.polygon) std::fill_n(left_out.begin() + static_cast<std::ptrdiff_t>(g.index), g.count, 1);
  }
  if (n != 0) {
    simd::AlignedVector<core::BBox> boxes(n);  // huge pages: 24 MB for a million triangles
    // Degenerate triangles can never be hit: an empty box keeps them out of traversal
    // (except in moved geometries, above; the kernels never hit them either).
    std::vector<unsigned char> is_degenerate(n, 0);
    excluded.assign(n, 0);
    excluded_flat.assign(n, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i < r.end(); ++i) {
        is_degenerate[i] = flat(i);
        excluded_flat[i] = is_degenerate[i] && !moving[i];
        excluded[i] = excluded_flat[i] | left_out[i];
        if (!excluded[i]) boxes[i] = triangle_box(&triangles[3 * i]);
      }
    });
    degenerate = static_cast<std::size_t>(std::count(is_degenerate.begin(), is_degenerate.end(), 1));
    triangle_engine = isa != Isa::scalar  ? accel::make_wide_engine(test, isa, robust)
                      : reference_double ? accel::make_reference_engine(test)
                                         : accel::make_oracle_engine(test, robust);
    core::Bvh bvh = core::build_bvh(boxes, triangle_engine->bvh_options());
    // Reported with unit costs (AccelInfo: node visit = 1, triangle test = 1).
    triangle_stats = core::bvh_stats(bvh, core::BvhBuildOptions{});
    triangle_engine->build(std::move(bvh), {triangles.data(), triangle_ids.data(), n, excluded.data()});
    built_sah = sah_now = triangle_engine->sah_cost();
  }
  build_polygons();
  finish_build();
}

void Accel::Impl::build_polygons() {
  polygon_engine.reset();
  enabled_polygons.clear();
  enabled_polygon_ids.clear();
  for (const Geometry& g : geometries)
    if (g.enabled && g.polygon) {
      enabled_polygons.push_back(polygons[g.index]);
      enabled_polygon_ids.push_back(polygon_ids[g.index]);
    }
  if (!enabled_polygons.empty())
    polygon_engine = accel::make_polygon_engine(enabled_polygons, enabled_polygon_ids, robust);
}

void Accel::Impl::finish_build() {
  wide_only = triangle_engine && !polygon_engine ? triangle_engine->wide() : nullptr;
  one_geometry = geometries.size() == 1;
  topology_changed = vertices_changed = refitted = false;
  built_with = {test, isa, robust, reference_double};
}

bool Accel::Impl::refit(const Options& options) {
  const bool same = options.test == built_with.test && options.isa == built_with.isa &&
                    options.robust == built_with.robust && options.reference_double == built_with.reference_double;
  if (!options.refit || !same || topology_changed || !vertices_changed || !triangle_engine) return false;
  // A triangle the build left out as degenerate that now has area needs a build (which
  // puts every triangle of a moved geometry into the tree).
  const std::size_t n = triangle_ids.size();
  std::atomic<bool> gained_area{false};
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end() && !gained_area.load(std::memory_order_relaxed); ++i)
      if (excluded_flat[i] && !flat(i)) gained_area = true;
  });
  if (gained_area) return false;
  // The wide BVH's blocks name triangles by internal id: the same as the triangle's place
  // unless polygons came in between (ids rise, so the last one tells).
  std::vector<std::uint32_t> index_of;
  if (triangle_ids.back() != n - 1) {
    index_of.assign(next_id, 0);
    for (std::size_t i = 0; i < n; ++i) index_of[triangle_ids[i]] = static_cast<std::uint32_t>(i);
  }
  sah_now = triangle_engine->refit({triangles.data(), triangle_ids.data(), n, excluded.data()},
                                     index_of.empty() ? nullptr : index_of.data());
  if (!(sah_now <= kRefitRebuildGrowth * built_sah)) return false;
  vertices_changed = false;
  refitted = true;
  return true;
}

Hit Accel::Impl::intersect(const Ray& ray) const {
  Hit hit;
  if (triangle_engine) triangle_engine->intersect(ray, hit);
  if (polygon_engine) polygon_engine->intersect(ray, hit);
  attribute(hit.prim, hit.geom);
  return hit;
}

bool Accel::Impl::occluded(const Ray& ray) const {
  return (triangle_engine && triangle_engine->occluded(ray)) || (polygon_engine && polygon_engine->occluded(ray));
}

template <int K>
void Accel::Impl::intersect(const RayPacket<K>& rays, HitPacket<K>& hits) const {
  // The lanes an engine writes (a nearer hit: t's bits change) get their geometry and
  // index; the others keep what the caller passed. Inactive lanes are not read.
  std::uint32_t before[K];
  if (all_lanes_active(rays) && one_geometry) {
    // Every lane ours and one geometry (prim needs no change): branch-free over all lanes.
    std::memcpy(before, hits.t, sizeof(before));
    trace_packet(rays, hits);
    for (int i = 0; i < K; ++i) {
      std::uint32_t now;
      std::memcpy(&now, &hits.t[i], 4);
      const bool written = now != before[i];
      hits.geom[i] = written ? 0u : hits.geom[i];
      hits.inst[i] = written ? kInvalidId : hits.inst[i];
    }
    return;
  }
  const std::uint32_t active = rays.active & lane_bits(K);
  for (std::uint32_t b = active; b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    std::memcpy(&before[i], &hits.t[i], 4);
  }
  trace_packet(rays, hits);
  for (std::uint32_t b = active; b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    if (std::memcmp(&before[i], &hits.t[i], 4) == 0) continue;
    attribute(hits.prim[i], hits.geom[i]);
    hits.inst[i] = kInvalidId;
  }
}

template <int K>
void Accel::Impl::trace_packet(const RayPacket<K>& rays, HitPacket<K>& hits) const {
  auto trace = [&](const RayPacket<16>& p, HitPacket<16>& h) {
    if (triangle_engine) triangle_engine->intersect(p, h);
    if (polygon_engine) polygon_engine->intersect(p, h);
  };
  if constexpr (K == 16) {
    // A full packet of a triangles-only scene: straight to the wide kernels, as single rays.
    if (wide_only && all_lanes_active(rays)) return wide_only->intersect(rays, hits);
    if (all_lanes_active(rays)) return trace(rays, hits);
  }
  const std::uint32_t active = rays.active & lane_bits(K);
  RayPacket<16> p;
  widen(rays, p);
  HitPacket<16> h;
  reset(h);
  for (std::uint32_t b = active; b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    set_hit(h, i, hit_of(hits, i));
  }
  trace(p, h);
  for (std::uint32_t b = active; b != 0; b &= b - 1) {
    const int i = __builtin_ctz(b);
    set_hit(hits, i, hit_of(h, i));
  }
}

template <int K>
std::uint32_t Accel::Impl::occluded(const RayPacket<K>& rays) const {
  auto trace = [&](const RayPacket<16>& p) {
    std::uint32_t blocked = triangle_engine ? triangle_engine->occluded(p, p.active) : 0u;
    if (polygon_engine && (p.active & ~blocked) != 0) blocked |= polygon_engine->occluded(p, p.active & ~blocked);
    return blocked & p.active;
  };
  if constexpr (K == 16) {
    if (wide_only && all_lanes_active(rays)) return wide_only->occluded(rays);
    if (all_lanes_active(rays)) return trace(rays);
  }
  RayPacket<16> p;
  widen(rays, p);
  return trace(p);
}

template void Accel::Impl::intersect<4>(const RayPacket<4>&, HitPacket<4>&) const;
template void Accel::Impl::intersect<8>(const RayPacket<8>&, HitPacket<8>&) const;
template void Accel::Impl::intersect<16>(const RayPacket<16>&, HitPacket<16>&) const;
template std::uint32_t Accel::Impl::occluded<4>(const RayPacket<4>&) const;
template std::uint32_t Accel::Impl::occluded<8>(const RayPacket<8>&) const;
template std::uint32_t Accel::Impl::occluded<16>(const RayPacket<16>&) const;

AccelInfo Accel::Impl::info() const {
  AccelInfo info;
  info.triangles = triangle_count();
  info.loaded = loaded;
  info.load_seconds = loaded ? load_seconds : 0.0;
  info.degenerate = degenerate;
  info.polygons = polygons.size();
  info.geometries = geometries.size();
  info.disabled = disabled;
  info.refitted = refitted;
  info.sah_growth = built_sah > 0.0 ? sah_now / built_sah : 1.0;
  info.test = test;
  info.isa = isa;
  info.robust = robust;
  info.reference_double = reference_double;
  info.build_seconds = build_seconds;
  if (triangle_engine && triangle_stats.nodes != 0) {
    info.binary_sah_cost = triangle_stats.sah_cost;
    triangle_engine->describe(info);
  }
  if (polygon_engine) polygon_engine->describe(info);
  return info;
}

}  // namespace volley
