#include "accel/accel_impl.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/bvh_traverse.h"
#include "simd/aligned.h"

namespace volley {
namespace {

static_assert(sizeof(glm::vec3) == 3 * sizeof(float), "triangles are read as packed xyz floats");

core::BBox triangle_box(const glm::vec3* p) {
  core::BBox b;
  for (int k = 0; k < 3; ++k) b.extend(p[k]);
  return b;
}

core::RayT<float> to_core(const Ray& r) {
  return {{r.org[0], r.org[1], r.org[2]}, r.tmin, {r.dir[0], r.dir[1], r.dir[2]}, r.tmax};
}

/// Binary-BVH options for the wide BVH with leaf blocks of W triangles. The SAH keeps up
/// to 16 triangles in a leaf when splitting does not pay, pricing a triangle test at
/// `intersection_cost` node visits: a block tests W triangles at about the cost of one node
/// visit for a single ray, but packets test every triangle of a leaf against all their lanes,
/// so the measured best lies above 1/W. Measured on Sponza and conference, primary rays,
/// single and packet (Mrays/s within noise of the best while the blocks fill up):
///   W = 16: cost 0.15 (0.25: +7% packet speed, +50% memory; 0.1: -20% packets);
///   W = 4, 8: cost 0.25 (1.0 with leaves of at most W: +5% speed, twice the memory).
/// W >= 8: an empty block slot priced at 0.4 triangle tests fills the blocks (perf/build.md):
///   W = 16: 57-62% -> 71-83% of lanes (Sponza 79 -> 63 bytes/triangle, packets 0..-3%;
///   1.0: 80%, but packets -10..-55%); W = 8 (AVX2, and AVX-512 since its leaves hold
///   blocks of 8): Sponza 64% -> 79%, 72 -> 59 bytes/triangle, Embree ratios within
///   +-2.5% (AVX2, perf/embree.md).
core::BvhBuildOptions wide_build_options(int w) {
  core::BvhBuildOptions o;
  o.max_leaf_size = 16;
  o.intersection_cost = w >= 16 ? 0.15f : 0.25f;
  if (w >= 8) {
    o.leaf_block_width = w;
    o.padding_cost = 0.4f;
  }
  return o;
}

/// Lane i of a packet as a ray.
template <int K>
Ray lane_ray(const RayPacket<K>& p, int i) {
  return Ray{{p.ox[i], p.oy[i], p.oz[i]}, p.tmin[i], {p.dx[i], p.dy[i], p.dz[i]}, p.tmax[i]};
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

/// Whether the kernels may take the caller's packet as it is: 16 lanes, all active.
template <int K>
bool all_lanes_active(const RayPacket<K>& p) {
  return K == 16 && (p.active & lane_bits(K)) == lane_bits(K);
}

/// True when the directions of rays[0 .. n) share one octant (sign bits; -0 negative):
/// the stream policy's test for tracing them as one packet below AVX-512 (see accel.h).
bool same_octant(const Ray* rays, std::size_t n) {
  std::uint32_t all = 7, any = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t oct = (std::signbit(rays[i].dir[0]) ? 1u : 0u) | (std::signbit(rays[i].dir[1]) ? 2u : 0u) |
                              (std::signbit(rays[i].dir[2]) ? 4u : 0u);
    all &= oct;
    any |= oct;
  }
  return all == any;
}

}  // namespace

void Accel::Impl::build() {
  const std::size_t n = triangle_ids.size();
  simd::AlignedVector<core::BBox> boxes(n);  // huge pages: 24 MB for a million triangles
  // Degenerate triangles can never be hit: an empty box keeps them out of traversal.
  std::vector<unsigned char> is_degenerate(n, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const glm::vec3* p = &triangles[3 * i];
      // The reference keeps what has area in double (a float cross product can round to 0).
      const bool flat = reference_double
                            ? core::is_degenerate<double>(core::Vec3<double>(p[0]), core::Vec3<double>(p[1]),
                                                          core::Vec3<double>(p[2]))
                            : core::is_degenerate(p[0], p[1], p[2]);
      if (flat) {
        is_degenerate[i] = 1;
        continue;
      }
      boxes[i] = triangle_box(p);
    }
  });
  degenerate = static_cast<std::size_t>(std::count(is_degenerate.begin(), is_degenerate.end(), 1));

  wide.reset();
  wide_only = nullptr;
  plane_triangles.clear();
  plane_triangles_double.clear();
  if (isa != Isa::scalar) {
    wide = accel::WideAccel::create(test, isa, robust);
    build_options = wide_build_options(wide->block_width());
  } else {
    build_options = core::BvhBuildOptions{};
  }
  triangle_bvh = n ? core::build_bvh(boxes, build_options) : core::Bvh{};
  // Reported with unit costs (AccelInfo: node visit = 1, triangle test = 1).
  triangle_stats = core::bvh_stats(triangle_bvh, core::BvhBuildOptions{});

  if (wide) {
    // data(), not &triangles[0]: a scene without triangles (empty or polygons only) has none.
    wide->build(triangle_bvh, reinterpret_cast<const float*>(triangles.data()), triangle_ids.data());
    triangle_bvh = core::Bvh{};
  } else if (test == TriangleTest::plane && reference_double) {
    plane_triangles_double.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      const glm::vec3* p = &triangles[3 * i];
      plane_triangles_double.push_back(core::PlaneTriangle<double>::from(
          core::Vec3<double>(p[0]), core::Vec3<double>(p[1]), core::Vec3<double>(p[2])));
    }
  } else if (test == TriangleTest::plane) {
    plane_triangles.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      const glm::vec3* p = &triangles[3 * i];
      plane_triangles.push_back(core::PlaneTriangle<float>::from(p[0], p[1], p[2]));
    }
  }

  std::vector<core::BBox> poly_boxes;
  for (const auto& poly : polygons) {
    core::BBox b;
    for (const auto& v : poly.vertices) b.extend(v);
    poly_boxes.push_back(b);
  }
  polygon_bvh = polygons.empty() ? core::Bvh{} : core::build_bvh(poly_boxes, core::BvhBuildOptions{});
  wide_only = wide && polygon_bvh.nodes.empty() ? wide.get() : nullptr;
}

template <bool AnyHit, bool Robust>
bool Accel::Impl::trace_triangles_scalar(const core::RayT<float>& r, Hit& hit) const {
  const core::WoopRay<float> woop = core::make_woop_ray(r.dir);
  return core::traverse<AnyHit, Robust>(triangle_bvh, r, [&](std::uint32_t prim, float& tmax) {
    const glm::vec3* p = &triangles[3 * prim];
    core::RayT<float> q = r;
    q.tmax = tmax;
    core::TriHit<float> h;
    bool ok = false;
    switch (test) {
      case TriangleTest::plane:
        ok = core::intersect_plane(q, plane_triangles[prim], h);
        break;
      case TriangleTest::moller:
        ok = core::intersect_moller<float, core::moller_fused_for(Isa::scalar)>(q, p[0], p[1], p[2], h);
        break;
      case TriangleTest::watertight:
        ok = core::intersect_watertight(q, woop, p[0], p[1], p[2], h);
        break;
    }
    if (!ok) return false;
    tmax = h.t;
    hit = {h.t, h.u, h.v, triangle_ids[prim]};
    return true;
  });
}

template <bool AnyHit>
bool Accel::Impl::trace_triangles_double(const core::RayT<float>& r, Hit& hit) const {
  // The widened ray; q.tmax is the nearest double t so far, so triangles closer together
  // than a float ulp are still ordered by their double distances.
  core::RayT<double> q = core::ray_cast<double>(r);
  const core::WoopRay<double> woop = core::make_woop_ray(q.dir);
  // Robust slabs: the float traversal's tmax is the rounded t, within the padding's margin.
  return core::traverse<AnyHit, true>(triangle_bvh, r, [&](std::uint32_t prim, float& tmax) {
    const glm::vec3* p = &triangles[3 * prim];
    const core::Vec3<double> p0(p[0]), p1(p[1]), p2(p[2]);
    core::TriHit<double> h;
    bool ok = false;
    switch (test) {
      case TriangleTest::plane:
        ok = core::intersect_plane(q, plane_triangles_double[prim], h);
        break;
      case TriangleTest::moller:
        ok = core::intersect_moller(q, p0, p1, p2, h);
        break;
      case TriangleTest::watertight:
        ok = core::intersect_watertight(q, woop, p0, p1, p2, h);
        break;
    }
    // A double t just below tmax can round onto it: [tmin, tmax) holds for the float t.
    const float t = static_cast<float>(h.t);
    if (!ok || !(t < r.tmax)) return false;
    q.tmax = h.t;
    tmax = t;
    hit = {t, static_cast<float>(h.u), static_cast<float>(h.v), triangle_ids[prim]};
    return true;
  });
}

template <bool AnyHit>
bool Accel::Impl::trace_polygons(const core::RayT<float>& r, Hit& hit) const {
  return robust ? trace_polygons_as<AnyHit, true>(r, hit) : trace_polygons_as<AnyHit, false>(r, hit);
}

template <bool AnyHit, bool Robust>
bool Accel::Impl::trace_polygons_as(const core::RayT<float>& r, Hit& hit) const {
  return core::traverse<AnyHit, Robust>(polygon_bvh, r, [&](std::uint32_t prim, float& tmax) {
    core::RayT<float> q = r;
    q.tmax = tmax;
    float t;
    if (!core::intersect_polygon(q, polygons[prim], t)) return false;
    tmax = t;
    hit = {t, 0.0f, 0.0f, polygon_ids[prim]};
    return true;
  });
}

template <bool AnyHit>
bool Accel::Impl::trace(const Ray& ray, Hit& hit) const {
  // Triangles only on the wide BVH (the common case): straight to its kernels.
  if (wide_only) {
    if constexpr (AnyHit) {
      return wide_only->occluded(ray);
    } else {
      wide_only->intersect(ray, hit);
      return hit.hit();
    }
  }
  core::RayT<float> r = to_core(ray);
  bool found = false;
  if (wide) {
    if constexpr (AnyHit) {
      if (wide->occluded(ray)) return true;
    } else {
      wide->intersect(ray, hit);
      found = hit.hit();
    }
  } else if (!triangle_bvh.nodes.empty()) {
    found = reference_double ? trace_triangles_double<AnyHit>(r, hit)
            : robust         ? trace_triangles_scalar<AnyHit, true>(r, hit)
                             : trace_triangles_scalar<AnyHit, false>(r, hit);
  }
  if (AnyHit && found) return true;
  if (!polygon_bvh.nodes.empty()) {
    r.tmax = found ? hit.t : r.tmax;
    found |= trace_polygons<AnyHit>(r, hit);
  }
  return found;
}

Hit Accel::Impl::intersect(const Ray& ray) const {
  Hit hit;
  trace<false>(ray, hit);
  return hit;
}

bool Accel::Impl::occluded(const Ray& ray) const {
  Hit hit;
  return trace<true>(ray, hit);
}

template <int K>
void Accel::Impl::intersect(const RayPacket<K>& rays, HitPacket<K>& hits) const {
  const std::uint32_t active = rays.active & lane_bits(K);
  if (!wide) {
    // The oracle, lane by lane, each bounded by its current hit.
    for (std::uint32_t b = active; b != 0; b &= b - 1) {
      const int i = __builtin_ctz(b);
      Ray r = lane_ray(rays, i);
      r.tmax = hits.t[i] < r.tmax ? hits.t[i] : r.tmax;
      Hit h;
      if (trace<false>(r, h)) hits.t[i] = h.t, hits.u[i] = h.u, hits.v[i] = h.v, hits.prim[i] = h.prim;
    }
    return;
  }
  if constexpr (K == 16) {
    if (all_lanes_active(rays)) wide->intersect(rays, hits);
  }
  if (!all_lanes_active(rays)) {
    RayPacket<16> p;
    widen(rays, p);
    HitPacket<16> h;
    reset(h);
    for (std::uint32_t b = active; b != 0; b &= b - 1) {
      const int i = __builtin_ctz(b);
      h.t[i] = hits.t[i], h.u[i] = hits.u[i], h.v[i] = hits.v[i], h.prim[i] = hits.prim[i];
    }
    wide->intersect(p, h);
    for (std::uint32_t b = active; b != 0; b &= b - 1) {
      const int i = __builtin_ctz(b);
      hits.t[i] = h.t[i], hits.u[i] = h.u[i], hits.v[i] = h.v[i], hits.prim[i] = h.prim[i];
    }
  }
  if (!polygon_bvh.nodes.empty()) {
    for (std::uint32_t b = active; b != 0; b &= b - 1) {
      const int i = __builtin_ctz(b);
      core::RayT<float> r = to_core(lane_ray(rays, i));
      r.tmax = hits.t[i] < r.tmax ? hits.t[i] : r.tmax;
      Hit h;
      if (trace_polygons<false>(r, h)) hits.t[i] = h.t, hits.u[i] = h.u, hits.v[i] = h.v, hits.prim[i] = h.prim;
    }
  }
}

template <int K>
std::uint32_t Accel::Impl::occluded(const RayPacket<K>& rays) const {
  const std::uint32_t active = rays.active & lane_bits(K);
  std::uint32_t blocked = 0;
  if (wide) {
    if constexpr (K == 16) {
      if (all_lanes_active(rays)) blocked = wide->occluded(rays);
    }
    if (!all_lanes_active(rays)) {
      RayPacket<16> p;
      widen(rays, p);
      blocked = wide->occluded(p);
    }
  }
  // The oracle lane by lane (scalar), or the polygons of the lanes still open.
  if (!wide || !polygon_bvh.nodes.empty()) {
    for (std::uint32_t b = active & ~blocked; b != 0; b &= b - 1) {
      const int i = __builtin_ctz(b);
      Hit h;
      const Ray r = lane_ray(rays, i);
      const bool hit = wide ? trace_polygons<true>(to_core(r), h) : trace<true>(r, h);
      if (hit) blocked |= 1u << i;
    }
  }
  return blocked & active;
}

void Accel::Impl::intersect(const Ray* rays, std::size_t count, Hit* hits) const {
  for (std::size_t first = 0; first < count; first += 16) {
    const std::size_t n = std::min<std::size_t>(16, count - first);
    if (wide && n == 16 && (isa == Isa::avx512 || same_octant(rays + first, n))) {
      RayPacket<16> p;
      load(p, rays + first, 16);
      HitPacket<16> h;
      reset(h);
      intersect(p, h);
      store(h, hits + first, 16);
    } else {
      for (std::size_t i = first; i < first + n; ++i) hits[i] = intersect(rays[i]);
    }
  }
}

void Accel::Impl::occluded(const Ray* rays, std::size_t count, std::uint8_t* blocked) const {
  for (std::size_t first = 0; first < count; first += 16) {
    const std::size_t n = std::min<std::size_t>(16, count - first);
    if (wide && n == 16 && (isa == Isa::avx512 || same_octant(rays + first, n))) {
      RayPacket<16> p;
      load(p, rays + first, 16);
      const std::uint32_t mask = occluded(p);
      for (std::size_t i = 0; i < 16; ++i) blocked[first + i] = static_cast<std::uint8_t>((mask >> i) & 1u);
    } else {
      for (std::size_t i = first; i < first + n; ++i) blocked[i] = occluded(rays[i]) ? 1 : 0;
    }
  }
}

template void Accel::Impl::intersect<4>(const RayPacket<4>&, HitPacket<4>&) const;
template void Accel::Impl::intersect<8>(const RayPacket<8>&, HitPacket<8>&) const;
template void Accel::Impl::intersect<16>(const RayPacket<16>&, HitPacket<16>&) const;
template std::uint32_t Accel::Impl::occluded<4>(const RayPacket<4>&) const;
template std::uint32_t Accel::Impl::occluded<8>(const RayPacket<8>&) const;
template std::uint32_t Accel::Impl::occluded<16>(const RayPacket<16>&) const;

AccelInfo Accel::Impl::info() const {
  AccelInfo info;
  info.triangles = triangle_ids.size();
  info.degenerate = degenerate;
  info.polygons = polygons.size();
  info.test = test;
  info.isa = isa;
  info.robust = robust;
  info.reference_double = reference_double;
  info.build_seconds = build_seconds;
  if (triangle_stats.nodes != 0) {
    info.binary_sah_cost = triangle_stats.sah_cost;
    if (wide) {
      const simd::WideStats& w = wide->stats();
      info.width = simd::kWideN;
      info.block_width = wide->block_width();
      info.nodes = w.nodes;
      info.leaves = w.leaves;
      info.depth = w.depth;
      info.sah_cost = w.sah_cost;
      info.mean_leaf_size = w.leaves ? double(w.triangles) / double(w.leaves) : 0.0;
      info.bytes = w.bytes;
      info.blocks = w.blocks;
      info.mean_children = w.mean_children;
      info.block_fill = w.blocks ? double(w.triangles) / double(w.blocks * std::size_t(info.block_width)) : 0.0;
    } else {
      info.nodes = triangle_stats.nodes;
      info.leaves = triangle_stats.leaves;
      info.depth = triangle_stats.depth;
      info.sah_cost = triangle_stats.sah_cost;
      info.mean_leaf_size = triangle_stats.mean_leaf_size;
      info.bytes = triangle_stats.bytes;
      info.mean_children = 2.0;
      // The triangle layout of the test in use (the input copy kept for re-commits not counted).
      info.bytes += test == TriangleTest::plane
                        ? plane_triangles.size() * sizeof(core::PlaneTriangle<float>) +
                              plane_triangles_double.size() * sizeof(core::PlaneTriangle<double>)
                        : triangles.size() * sizeof(glm::vec3);
    }
  }
  if (!polygon_bvh.nodes.empty()) {
    const core::BvhStats s = core::bvh_stats(polygon_bvh);
    info.nodes += s.nodes;
    info.leaves += s.leaves;
    info.depth = std::max(info.depth, s.depth);
    info.bytes += s.bytes;
  }
  return info;
}

}  // namespace volley
