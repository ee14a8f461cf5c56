// The wide BVH and its traversals (single ray, packets of 4, 8, 16, streams), on every ISA
// this CPU has and every triangle test, against brute force over the scalar oracle (its
// variant for the ISA: moller fuses on AVX2/AVX-512 only), ray by ray: same prim, or the
// same t where two triangles tie.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "accel/wide/wide_accel.h"
#include "accel_test_util.h"
#include "common/slab_grid.h"
#include "core/bvh.h"
#include "core/triangle.h"
#include "io/obj_loader.h"
#include "io/scene_desc.h"
#include "simd/isa/dispatch.h"
#include "volley/accel.h"
#include "volley/packet.h"

using volley::Accel;
using volley::Hit;
using volley::Isa;
using volley::Ray;
using volley::TriangleTest;

using namespace accel_test;

TEST_CASE("wide: every query form equals brute force on random soups (every ISA, test, K)") {
  const Soup soup = random_soup(1500, 11);
  const std::vector<Ray> rays = mixed_rays(120, 10.0f, 5);
  for (TriangleTest test : kTests) {
    const std::vector<Hit> want = brute_force_all(soup, test, rays);
    const std::size_t hits =
        static_cast<std::size_t>(std::count_if(want.begin(), want.end(), [](const Hit& h) { return h.hit(); }));
    // The generator produces hits and misses.
    CHECK(hits > rays.size() / 5);
    CHECK(hits < rays.size() * 4 / 5);
    for (Isa isa : simd_isas()) {
      const Accel accel = soup.accel(test, isa);
      report(check_forms(accel, rays, brute_force_all(soup, test, rays, isa), 3),
             std::string(volley::to_string(test)) + " " + std::string(volley::to_string(isa)));
    }
    // The scalar oracle's own packet and stream forms.
    report(check_forms(soup.accel(test, Isa::scalar), rays, want, 4), std::string(volley::to_string(test)) + " scalar");
  }
}

TEST_CASE("wide: directions with tied magnitudes and signed zeros pick the oracle's shear axes") {
  // The single-ray entries form the watertight shear themselves (core::kWoopAxes indexed by
  // vector compares); ties between |d| components and -0 components exercise every table
  // row that a sign or an order decides. Every form must give the oracle's exact t.
  const Soup soup = random_soup(800, 17);
  std::vector<Ray> rays;
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> pos(-8.0f, 8.0f);
  const float z = -0.0f;
  const glm::vec3 dirs[] = {{1, 1, 1},  {-1, 1, 1}, {1, -1, 1}, {1, 1, -1},  {-1, -1, -1},
                            {1, 1, 0},  {1, 1, z},  {-1, 1, z}, {z, 1, -1},  {z, -1, 1},
                            {1, z, -1}, {-1, z, 1}, {2, 2, 1},  {2, -1, -2}, {-1, 2, 2},
                            {z, z, -1}, {z, 1, z},  {-1, z, z}, {3, -3, 3},  {0.5f, -0.5f, 0.25f}};
  for (const glm::vec3& d : dirs)
    for (int i = 0; i < 24; ++i) {
      const glm::vec3 target(pos(rng), pos(rng), pos(rng));
      rays.push_back(make_ray(target - 3.0f * d, d));
    }
  const std::vector<Hit> want = brute_force_all(soup, TriangleTest::watertight, rays);
  const auto hits = std::count_if(want.begin(), want.end(), [](const Hit& h) { return h.hit(); });
  MESSAGE(hits << " of " << rays.size() << " rays hit");
  CHECK(hits > 100);
  for (Isa isa : simd_isas()) {
    const Accel accel = soup.accel(TriangleTest::watertight, isa);
    report(check_forms(accel, rays, brute_force_all(soup, TriangleTest::watertight, rays, isa), 9),
           "watertight " + std::string(volley::to_string(isa)));
  }
}

TEST_CASE("wide: NaN and Inf lanes miss without disturbing the other lanes of their packet") {
  const Soup soup = random_soup(300, 2);
  std::vector<Ray> rays = mixed_rays(10, 10.0f, 9);
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const Accel accel = soup.accel(TriangleTest::watertight, isa);
    volley::RayPacket<16> clean, dirty;
    volley::HitPacket<16> h_clean, h_dirty;
    for (std::size_t first = 0; first + 16 <= rays.size(); first += 16) {
      volley::load(clean, rays.data() + first, 16);
      dirty = clean;
      for (int i = 0; i < 16; i += 3) {  // poison every third lane in a different way
        if (i % 2)
          dirty.dx[i] = kNaN;
        else
          dirty.oy[i] = -kInf;
      }
      volley::reset(h_clean);
      volley::reset(h_dirty);
      accel.intersect(clean, h_clean);
      accel.intersect(dirty, h_dirty);
      const std::uint32_t m_clean = accel.occluded(clean), m_dirty = accel.occluded(dirty);
      for (int i = 0; i < 16; ++i) {
        if (i % 3 == 0) {
          CHECK(!volley::hit_of(h_dirty, i).hit());
          CHECK(((m_dirty >> i) & 1u) == 0u);
        } else {
          CHECK(agree(volley::hit_of(h_dirty, i), volley::hit_of(h_clean, i)));
          CHECK(((m_dirty >> i) & 1u) == ((m_clean >> i) & 1u));
        }
        CHECK(!std::isnan(h_dirty.t[i]));
      }
    }
  }
}

TEST_CASE("wide: flat axis-aligned geometry, origins on slab planes, zero direction components (stress 4)") {
  // 0 * inf = NaN in a slab test must keep the node.
  Soup soup;
  const std::vector<Ray> rays =
      volley::test::slab_plane_grid<Ray>(12, soup, [](glm::vec3 o, glm::vec3 d) { return make_ray(o, d); });
  for (TriangleTest test : kTests) {
    const std::vector<Hit> want = brute_force_all(soup, test, rays);
    CHECK(std::count_if(want.begin(), want.end(), [](const Hit& h) { return h.hit(); }) >
          std::ptrdiff_t(rays.size() / 2));
    for (Isa isa : simd_isas())
      report(check_forms(soup.accel(test, isa), rays, brute_force_all(soup, test, rays, isa), 8),
             std::string("grid ") + std::string(volley::to_string(test)) + " " + std::string(volley::to_string(isa)));
  }
}

TEST_CASE("wide: rays touching leaf boxes at triangle vertices need the slab padding (mutation check)") {
  // Lone triangles, one per leaf, and rays from all around aimed exactly at their vertices:
  // many rays only touch a leaf box at a corner or an edge, where entry = exit in exact
  // arithmetic and rounding decides. The padded traversal must find every hit brute force
  // finds; the unpadded variant (WideKernels<..., Robust = false>) must miss some, which
  // shows this test can fail.
  const VertexAimed case_ = lone_triangles_vertex_aimed();
  const Soup& soup = case_.soup;
  const std::vector<Ray>& rays = case_.rays;
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const std::vector<Hit> want = brute_force_all(soup, TriangleTest::watertight, rays, isa);
    std::size_t missed[2] = {0, 0}, packet_missed[2] = {0, 0};
    for (bool robust : {true, false}) {
      const auto wide = one_triangle_per_leaf(soup, isa, robust);
      for (std::size_t i = 0; i < rays.size(); ++i) {
        Hit h;
        wide->intersect(rays[i], h);
        missed[robust] += !agree(h, want[i]);
      }
      volley::RayPacket<16> p;
      volley::HitPacket<16> h;
      for (std::size_t first = 0; first + 16 <= rays.size(); first += 16) {
        volley::load(p, rays.data() + first, 16);
        volley::reset(h);
        wide->intersect(p, h);
        for (int i = 0; i < 16; ++i) packet_missed[robust] += !agree(volley::hit_of(h, i), want[first + i]);
      }
    }
    MESSAGE(std::string(volley::to_string(isa)), ": ", rays.size(), " vertex-aimed rays; unpadded traversal wrong on ",
            missed[0], " (single) and ", packet_missed[0], " (packets), padded on ", missed[1], " and ",
            packet_missed[1]);
    CHECK(missed[1] == 0);
    CHECK(packet_missed[1] == 0);
    CHECK(missed[0] > 0);
  }
}

TEST_CASE("wide: shared meshes against the scalar oracle's traversal") {
  const std::filesystem::path dir = VOLLEY_SHARED_SCENES;
  for (const char* name : {"teapot.obj", "stanford-bunny.obj"}) {
    const std::filesystem::path file = dir / name;
    if (!std::filesystem::exists(file)) {
      MESSAGE("skipped: " << file.string() << " not found");
      continue;
    }
    volley::io::SceneDesc desc;
    volley::io::load_obj(file, glm::mat4(1.0f), std::nullopt, desc);
    const auto& m = desc.mesh;
    std::vector<float> xyz;
    for (const glm::vec3& p : m.positions) xyz.insert(xyz.end(), {p.x, p.y, p.z});
    glm::vec3 lo(kInf), hi(-kInf);
    for (const glm::vec3& p : m.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
    const glm::vec3 center = 0.5f * (lo + hi);
    const float extent = 0.5f * glm::length(hi - lo);
    std::vector<Ray> rays = mixed_rays(200, extent, 17);
    for (Ray& r : rays)
      for (int a = 0; a < 3; ++a) r.org[a] += center[a];
    Accel oracle;
    oracle.add_triangles(xyz.data(), m.positions.size(), m.indices.data(), m.triangle_count());
    oracle.commit({TriangleTest::watertight, Isa::scalar});
    std::vector<Hit> want(rays.size());
    std::size_t hits = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) hits += (want[i] = oracle.intersect(rays[i])).hit();
    CHECK(hits > rays.size() / 10);
    // AVX2 and AVX-512 fuse the watertight shear (core::watertight_fused_for): their oracle
    // is the fused variant, by brute force.
    std::vector<Hit> want_fused;
    for (Isa isa : simd_isas()) {
      Accel accel;
      accel.add_triangles(xyz.data(), m.positions.size(), m.indices.data(), m.triangle_count());
      accel.commit({TriangleTest::watertight, isa});
      if (volley::core::watertight_fused_for(isa) && want_fused.empty()) {
        Soup soup;
        for (std::size_t t = 0; t < m.triangle_count(); ++t)
          soup.add(m.positions[m.indices[3 * t]], m.positions[m.indices[3 * t + 1]], m.positions[m.indices[3 * t + 2]]);
        want_fused = brute_force_all(soup, TriangleTest::watertight, rays, isa);
      }
      report(check_forms(accel, rays, volley::core::watertight_fused_for(isa) ? want_fused : want, 12),
             std::string(name) + " " + std::string(volley::to_string(isa)));
    }
  }
}

TEST_CASE("wide: AccelInfo describes the wide BVH") {
  const Soup soup = random_soup(5000, 3);
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const auto info = soup.accel(TriangleTest::watertight, isa).info();
    CHECK(info.width == volley::simd::kWideN);
    // AVX-512 leaves hold blocks of 8, as AVX2's (simd/isa/arch.h, SingleRayArch).
    CHECK(info.block_width == (isa == Isa::sse42 ? 4 : 8));
    CHECK(info.blocks * std::size_t(info.block_width) >= info.triangles - info.degenerate);
    CHECK(info.leaves > 0);
    CHECK(info.nodes > 0);
    CHECK(info.nodes < info.leaves);
    CHECK(info.mean_children > 2.0);
    CHECK(info.mean_children <= 8.0);
    CHECK(info.block_fill > 0.0);
    CHECK(info.block_fill <= 1.0);
    CHECK(std::isfinite(info.sah_cost));
    CHECK(info.sah_cost < info.binary_sah_cost);
    CHECK(info.bytes >= info.nodes * sizeof(volley::simd::WideNode<8>));
  }
  const auto scalar = soup.accel(TriangleTest::watertight, Isa::scalar).info();
  CHECK(scalar.width == 2);
  CHECK(scalar.block_width == 1);
  CHECK(scalar.sah_cost == scalar.binary_sah_cost);
}

TEST_CASE("wide: empty scenes, one triangle, degenerate-only scenes") {
  const Ray down = make_ray({0.2f, 0.2f, 5}, {0, 0, -1});
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    Accel empty;
    empty.commit({TriangleTest::watertight, isa});
    CHECK(!empty.intersect(down).hit());
    volley::RayPacket<16> p;
    volley::load(p, &down, 1);
    volley::HitPacket<16> h;
    volley::reset(h);
    empty.intersect(p, h);
    CHECK(!volley::hit_of(h, 0).hit());
    CHECK(empty.occluded(p) == 0u);

    Soup one;
    one.add({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
    const Accel a = one.accel(TriangleTest::watertight, isa);
    CHECK(a.intersect(down).prim == 0);
    volley::reset(h);
    a.intersect(p, h);
    CHECK(h.prim[0] == 0);
    CHECK(h.t[0] == doctest::Approx(5.0f));
    CHECK(a.occluded(p) == 1u);

    Soup flat;  // only zero-area triangles
    flat.add({0, 0, 0}, {1, 0, 0}, {2, 0, 0});
    flat.add({0, 0, 0}, {0, 0, 0}, {0, 1, 0});
    const Accel d = flat.accel(TriangleTest::watertight, isa);
    CHECK(d.info().degenerate == 2);
    CHECK(!d.intersect(down).hit());
    CHECK(!d.occluded(down));
  }
}

TEST_CASE("wide: packets and streams see polygons as single rays do") {
  // Two triangles at z = 5 and z = 3 (geometry 0), a square polygon at z = 4 (geometry 1).
  const float tris[] = {-1, -1, 5, 1, -1, 5, 0, 1, 5, -1, -1, 3, 1, -1, 3, 0, 1, 3};
  const std::uint32_t idx[] = {0, 1, 2, 3, 4, 5};
  const float square[] = {-2, -2, 4, 2, -2, 4, 2, 2, 4, -2, 2, 4};
  std::vector<Ray> rays;
  for (int i = 0; i < 48; ++i) {
    const float x = -2.5f + 0.11f * float(i), y = 0.05f * float(i % 7) - 0.1f;
    rays.push_back(make_ray({x, y, 0}, {0, 0, 1}, i % 3 == 0 ? 3.5f : 0.0f));
  }
  for (Isa isa : all_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    for (TriangleTest test : kTests) {
      Accel accel;
      accel.add_triangles(tris, 6, idx, 2);
      accel.add_polygon(square, 4);
      accel.commit({test, isa});
      std::vector<Hit> want(rays.size());
      std::size_t polygon_hits = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) polygon_hits += (want[i] = accel.intersect(rays[i])).geom == 1;
      CHECK(polygon_hits > 5);
      report(check_forms(accel, rays, want, 13), std::string("polygons ") + std::string(volley::to_string(test)));
    }
  }
}

TEST_CASE("wide: walk_counts counts the single walk's nodes, leaves and triangles without changing answers") {
  // One triangle: a root node over one leaf (the root box is tested, as the oracle's).
  Soup one;
  one.add({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  const Ray through{{0.2f, 0.2f, 1.0f}, 0.0f, {0.0f, 0.0f, -1.0f}, INFINITY};
  const Ray away{{0.2f, 0.2f, 1.0f}, 0.0f, {0.0f, 0.0f, 1.0f}, INFINITY};
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const Accel accel = one.accel(TriangleTest::watertight, isa);
    for (const bool any_hit : {false, true}) {
      const volley::WalkCounts c = accel.walk_counts(through, any_hit);
      CHECK(c.nodes == 1);
      CHECK(c.leaves == 1);
      CHECK(c.triangles == 1);
    }
    const volley::WalkCounts missed = accel.walk_counts(away);
    CHECK((missed.nodes == 1 && missed.leaves == 0 && missed.triangles == 0));
    CHECK(accel.intersect(through).hit());
  }
  // A soup: every ray that hits opened a leaf and tested a triangle; the tree culls most.
  const Soup soup = random_soup(1500, 17);
  const std::vector<Ray> rays = mixed_rays(200, 10.0f, 19);
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const Accel accel = soup.accel(TriangleTest::watertight, isa);
    std::uint64_t nodes = 0, leaves = 0, triangles = 0;
    for (const Ray& r : rays) {
      const volley::WalkCounts c = accel.walk_counts(r);
      if (accel.intersect(r).hit()) CHECK((c.leaves >= 1 && c.triangles >= 1));
      CHECK(c.triangles >= c.leaves);
      CHECK(c.triangles <= 8 * 15 * c.leaves);  // blocks of 8, at most 15 per leaf
      nodes += c.nodes, leaves += c.leaves, triangles += c.triangles;
    }
    CHECK(nodes > rays.size());
    CHECK(triangles < soup.size() * rays.size() / 4);  // the tree culls
  }
  CHECK_THROWS_AS(soup.accel(TriangleTest::watertight, Isa::scalar).walk_counts(rays[0]), volley::Error);
}
