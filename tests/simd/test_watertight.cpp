// Watertightness of the SIMD watertight kernel, every ISA and form, with the flags it ships
// with (FMA enabled in the AVX2 and AVX-512 objects): closed meshes, rays from inside aimed
// exactly at shared vertices, edge midpoints and diagonals, also with the mesh moved far
// from the origin; axis-aligned rays on an integer heightfield (the double fallback).
#include "simd_test_util.h"

#include "core/triangle_watertight.h"
#include "simd/testing/prepare_ray.h"
#include "simd/triangle/watertight.h"

namespace {

using namespace simd_test;

/// Rays from a few interior points of grid_box(n, offset) to every half-integer point of
/// its faces (vertices, edge midpoints, diagonal midpoints, square centres).
std::vector<Ray> rays_at_shared_points(int n, float offset) {
  std::vector<Ray> rays;
  // Interior points: the centre region, near faces, near edges and corners.
  std::vector<V3> origins = {V3(0.5f * n + 0.1234f, 0.5f * n - 0.0567f, 0.5f * n + 0.0089f),
                             V3(0.3f, 0.25f * n, 0.7f * n), V3(n - 0.21f, n - 0.33f, 0.4f)};
  Generator g(17);
  for (int k = 0; k < 9; ++k) origins.push_back(V3(g.uniform(0.05f, n - 0.05f), g.uniform(0.05f, n - 0.05f), g.uniform(0.05f, n - 0.05f)));
  for (V3& o : origins) o = o + offset;
  for (const V3& o : origins)
    for (int axis = 0; axis < 3; ++axis)
      for (float level : {0.0f, float(n)})
        for (int i = 0; i <= 2 * n; ++i)
          for (int j = 0; j <= 2 * n; ++j) {
            float p[3];
            p[axis] = level + offset;
            p[(axis + 1) % 3] = 0.5f * float(i) + offset;
            p[(axis + 2) % 3] = 0.5f * float(j) + offset;
            const V3 d = V3(p[0], p[1], p[2]) - o;
            rays.push_back(Ray{{o.x, o.y, o.z}, 0.0f, {d.x, d.y, d.z}, kInf});
          }
  return rays;
}

/// Rays of `rays` that no triangle stops, per kernel form.
struct Leaks {
  std::size_t single = 0, single_occluded = 0, packet = 0, packet_triangle = 0, packet_occluded = 0;
  std::size_t total() const { return single + single_occluded + packet + packet_triangle + packet_occluded; }
};

template <class Arch, TriangleTest Test>
Leaks count_leaks(const Soup& soup, const std::vector<Ray>& rays) {
  constexpr int W = kLanes<Arch>;
  constexpr int K = 16;
  const auto blocks = pack<Arch, Test>(soup);
  const auto nblocks = static_cast<std::uint32_t>(blocks.size());
  Leaks leaks;
  for (const Ray& r : rays) {
    const auto pr = volley::simd::prepare_ray(r, Test == TriangleTest::watertight);
    Hit h;
    RayBlockKernels<Arch, Test>::intersect(pr, blocks.data(), nblocks, h);
    leaks.single += h.prim == kInvalidPrim;
    leaks.single_occluded += !RayBlockKernels<Arch, Test>::occluded(pr, blocks.data(), nblocks);
  }
  for (std::size_t first = 0; first < rays.size(); first += K) {
    const int count = static_cast<int>(std::min<std::size_t>(K, rays.size() - first));
    RayPacket<K> packet;
    volley::simd::load(packet, rays.data() + first, count);
    HitPacket<K> hits, hits_tri;
    volley::simd::reset(hits);
    volley::simd::reset(hits_tri);
    volley::simd::PreparedPacket<K> prepared;
    PacketKernels<Arch, Test, K>::prepare(packet, prepared);
    PacketKernels<Arch, Test, K>::intersect(prepared, blocks.data(), nblocks, hits);
    for (std::uint32_t b = 0; b < nblocks; ++b)
      for (int j = 0; j < W; ++j) PacketKernels<Arch, Test, K>::intersect_triangle(prepared, blocks[b], j, hits_tri);
    const std::uint32_t occ = PacketKernels<Arch, Test, K>::occluded(prepared, blocks.data(), nblocks, packet.active);
    for (int i = 0; i < count; ++i) {
      leaks.packet += hits.prim[i] == kInvalidPrim;
      leaks.packet_triangle += hits_tri.prim[i] == kInvalidPrim;
      leaks.packet_occluded += !(occ >> i & 1);
    }
  }
  return leaks;
}

}  // namespace

TEST_CASE_TEMPLATE("watertight kernel: no leaks at shared vertices and edges of closed meshes", Arch,
                   VOLLEY_TEST_ARCHES) {
  if (skip_isa<Arch>()) return;
  for (float offset : {0.0f, 1e3f, 1e5f, 1e6f}) {
    const int n = 4;
    const Soup soup = grid_box(n, offset);
    const auto rays = rays_at_shared_points(n, offset);
    const Leaks w = count_leaks<Arch, TriangleTest::watertight>(soup, rays);
    INFO("offset ", offset, ": ", rays.size(), " rays; leaks single ", w.single, ", single occluded ",
         w.single_occluded, ", packet ", w.packet, ", packet x triangle ", w.packet_triangle, ", packet occluded ",
         w.packet_occluded);
    CHECK(w.total() == 0);
    // For the record: Moller-Trumbore is not watertight on the same rays.
    const Leaks m = count_leaks<Arch, TriangleTest::moller>(soup, rays);
    MESSAGE(volley::to_string(volley::simd::kIsaOf<Arch>), " offset ", offset, ": watertight leaks ", w.single,
            " of ", rays.size(), ", moller leaks ", m.single);
  }
}

TEST_CASE_TEMPLATE("watertight kernel: axis-aligned rays on an integer heightfield never miss, fallback counted", Arch,
                   VOLLEY_TEST_ARCHES) {
  if (skip_isa<Arch>()) return;
  // Heightfield over [0, 8]^2 with integer heights; quads split on alternating diagonals.
  const int n = 8;
  Generator g(3);
  std::vector<float> h((n + 1) * (n + 1));
  for (float& x : h) x = float(g.integer(0, 3));
  Soup soup;
  const auto at = [&](int i, int j) { return V3(float(i), float(j), h[i * (n + 1) + j]); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      if ((i + j) % 2) soup.add(at(i, j), at(i + 1, j), at(i + 1, j + 1)), soup.add(at(i, j), at(i + 1, j + 1), at(i, j + 1));
      else soup.add(at(i, j), at(i + 1, j), at(i, j + 1)), soup.add(at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
    }
  // Straight down (also with signed zeros) at every integer and half-integer point strictly
  // inside the domain.
  std::vector<Ray> rays;
  for (int i = 1; i < 2 * n; ++i)
    for (int j = 1; j < 2 * n; ++j)
      for (float zero : {0.0f, -0.0f})
        rays.push_back(Ray{{0.5f * i, 0.5f * j, 10.0f}, 0.0f, {zero, -zero, -1.0f}, kInf});
  const Leaks w = count_leaks<Arch, TriangleTest::watertight>(soup, rays);
  CHECK(w.total() == 0);
  // Frequency of the double fallback in the single-ray closest-hit form: every ray through a
  // vertex or an edge makes an edge function exactly 0.
  const auto blocks = pack<Arch, TriangleTest::watertight>(soup);
  const std::uint64_t before = volley::simd::watertight_fallback_lanes;
  for (const Ray& r : rays) {
    Hit hit;
    RayBlockKernels<Arch, TriangleTest::watertight>::intersect(volley::simd::prepare_ray(r), blocks.data(),
                                                               static_cast<std::uint32_t>(blocks.size()), hit);
  }
  const std::uint64_t fallbacks = volley::simd::watertight_fallback_lanes - before;
  CHECK(fallbacks > 0);
  MESSAGE(volley::to_string(volley::simd::kIsaOf<Arch>), ": double fallback in ", fallbacks, " of ",
          rays.size() * soup.size(), " ray-triangle tests (",
          100.0 * double(fallbacks) / double(rays.size() * soup.size()), "%)");
  // And the answers are the oracle's.
  const Agreement a = compare_all_forms<Arch, TriangleTest::watertight>(soup, rays, "heightfield");
  INFO(a.first);
  CHECK(a.mismatches == 0);
}
