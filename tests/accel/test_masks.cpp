// Ray and geometry masks (Accel::set_geometry_mask, the query forms with masks): a ray
// with mask m answers as the same scene with every geometry whose mask shares no bit with
// m disabled, in every query form, at every ISA and test; a scene that sets no mask keeps
// one BVH; masked scenes refit, save and load.
#include <doctest/doctest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "accel_test_util.h"
#include "simd/isa/dispatch.h"
#include "volley/accel.h"

using volley::Accel;
using volley::Hit;
using volley::Isa;
using volley::kMaskAll;
using volley::Ray;
using volley::TriangleTest;
using accel_test::agree;
using accel_test::report;

namespace {

/// Five triangle geometries and a polygon, with the masks below (geometry 4's 0: never hit).
const std::uint32_t kGeometryMasks[] = {0x1u, 0x2u, 0x3u, kMaskAll, 0x0u, 0x2u};
const std::uint32_t kRayMasks[] = {0x0u, 0x1u, 0x2u, 0x4u, 0x80000000u, 0x3u, kMaskAll};

struct MaskedScene {
  std::vector<accel_test::Soup> soups;
  MaskedScene() {
    for (std::uint32_t seed = 0; seed < 5; ++seed) soups.push_back(accel_test::random_soup(150, 40 + seed));
  }
  /// The scene; with `only` set, the geometries whose mask shares no bit with *only are
  /// disabled instead of masked (the reference for rays of that mask).
  Accel make(const volley::Options& options, const std::uint32_t* only = nullptr) const {
    Accel accel;
    for (const accel_test::Soup& s : soups) {
      std::vector<std::uint32_t> idx(3 * s.size());
      for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
      accel.add_triangles(s.xyz.data(), 3 * s.size(), idx.data(), s.size());
    }
    const float square[] = {-12, -12, 0.5f, 12, -12, 0.5f, 12, 12, 0.5f, -12, 12, 0.5f};
    accel.add_polygon(square, 4);
    for (std::uint32_t g = 0; g < 6; ++g) {
      if (!only) accel.set_geometry_mask(g, kGeometryMasks[g]);
      else if (!(kGeometryMasks[g] & *only)) accel.disable_geometry(g);
    }
    accel.commit(options);
    return accel;
  }
};

template <int K>
void check_packets(const Accel& accel, const std::vector<Ray>& rays, const std::vector<std::uint32_t>& masks,
                   const std::vector<Hit>& want, std::mt19937& rng, accel_test::FormCheck& c) {
  for (std::size_t first = 0; first + K <= rays.size(); first += K) {
    volley::RayPacket<K> p;
    volley::load(p, rays.data() + first, K);
    p.active = static_cast<std::uint32_t>(rng()) & volley::lane_bits(K);
    volley::HitPacket<K> h;
    volley::reset(h);
    accel.intersect(p, h, masks.data() + first);
    const std::uint32_t blocked = accel.occluded(p, masks.data() + first);
    for (int i = 0; i < K; ++i) {
      if (!(p.active >> i & 1u)) continue;
      const Hit& w = want[first + static_cast<std::size_t>(i)];
      c.packet += !agree(volley::hit_of(h, i), w);
      c.packet_occluded += ((blocked >> i) & 1u) != (w.hit() ? 1u : 0u);
    }
  }
}

}  // namespace

TEST_CASE("masks: a ray sees the geometries its mask shares a bit with, every ISA, test and query form") {
  const MaskedScene scene;
  const std::vector<Ray> rays = accel_test::mixed_rays(40, 12.0f, 3);
  accel_test::for_each_isa_and_test([&](Isa isa, TriangleTest test) {
    const Accel masked = scene.make({test, isa});
    CHECK(masked.info().layers == 4);  // 0xffffffff, 0x3, 0x2, 0x1 (0 is in none)
    // Every ray with every mask: the answers of the scene with the others disabled.
    std::vector<std::uint32_t> masks(rays.size());
    std::vector<Hit> want(rays.size());
    std::mt19937 rng(17);
    for (std::size_t i = 0; i < rays.size(); ++i) masks[i] = kRayMasks[rng() % std::size(kRayMasks)];
    std::size_t hits = 0;
    for (const std::uint32_t m : kRayMasks) {
      const Accel only = scene.make({test, isa}, &m);
      for (std::size_t i = 0; i < rays.size(); ++i)
        if (masks[i] == m) hits += (want[i] = only.intersect(rays[i])).hit();
    }
    CHECK(hits > rays.size() / 5);
    accel_test::FormCheck c;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      c.single += !agree(masked.intersect(rays[i], masks[i]), want[i]);
      c.occluded += masked.occluded(rays[i], masks[i]) != want[i].hit();
    }
    check_packets<4>(masked, rays, masks, want, rng, c);
    check_packets<8>(masked, rays, masks, want, rng, c);
    check_packets<16>(masked, rays, masks, want, rng, c);
    std::vector<Hit> stream(rays.size());
    std::vector<std::uint8_t> blocked(rays.size());
    masked.intersect(rays.data(), masks.data(), rays.size(), stream.data());
    masked.occluded(rays.data(), masks.data(), rays.size(), blocked.data());
    for (std::size_t i = 0; i < rays.size(); ++i) {
      c.stream += !agree(stream[i], want[i]);
      c.stream_occluded += blocked[i] != (want[i].hit() ? 1 : 0);
    }
    report(c, "masked forms against the scene with the hidden geometries disabled");
    // The forms without a mask (full packets among them: every layer without a copy):
    // every geometry but the mask-0 one.
    const Accel all = scene.make({test, isa}, &kMaskAll);
    std::vector<Hit> want_all(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) want_all[i] = all.intersect(rays[i]);
    report(accel_test::check_forms(masked, rays, want_all, 5), "forms without a mask against the scene of mask ~0");
  });
}

TEST_CASE("masks: a scene without masks has one layer, masked scenes refit, save and load") {
  const MaskedScene scene;
  const Isa isa = volley::simd::cpu_has(Isa::avx2) ? Isa::avx2 : Isa::sse42;
  const std::vector<Ray> rays = accel_test::mixed_rays(20, 12.0f, 8);
  {
    Accel plain;
    const accel_test::Soup& s = scene.soups[0];
    std::vector<std::uint32_t> idx(3 * s.size());
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
    plain.add_triangles(s.xyz.data(), 3 * s.size(), idx.data(), s.size());
    plain.commit({TriangleTest::watertight, isa});
    CHECK(plain.info().layers == 1);
    // One mask for all: still one layer, and rays of other masks miss.
    plain.set_geometry_mask(0, 0x10);
    plain.commit({TriangleTest::watertight, isa});
    CHECK(plain.info().layers == 1);
    int hits_all = 0, hits_other = 0;
    for (const Ray& r : rays) hits_all += plain.intersect(r, 0x30).hit(), hits_other += plain.intersect(r, 0x20).hit();
    CHECK(hits_all > 0);
    CHECK(hits_other == 0);
  }
  Accel masked = scene.make({TriangleTest::watertight, isa});
  // Refit: every geometry moved a little; the answers of a fresh build of the moved scene.
  std::vector<std::vector<float>> moved;
  for (std::uint32_t g = 0; g < 5; ++g) {
    moved.push_back(scene.soups[g].xyz);
    for (float& x : moved.back()) x *= 1.01f;
    masked.update_vertices(g, moved.back().data(), moved.back().size() / 3);
  }
  masked.commit({TriangleTest::watertight, isa});
  CHECK(masked.info().refitted);
  MaskedScene moved_scene;
  for (std::uint32_t g = 0; g < 5; ++g) moved_scene.soups[g].xyz = moved[g];
  const Accel fresh = moved_scene.make({TriangleTest::watertight, isa});
  const std::string path = (std::filesystem::temp_directory_path() / "volley_test_masks.vacc").string();
  masked.save(path);
  const Accel loaded = Accel::load(path);
  CHECK(loaded.info().layers == 4);
  int differ = 0, differ_loaded = 0;
  for (const Ray& r : rays)
    for (const std::uint32_t m : kRayMasks) {
      const Hit want = fresh.intersect(r, m);
      differ += !agree(masked.intersect(r, m), want);
      const Hit a = masked.intersect(r, m), b = loaded.intersect(r, m);
      differ_loaded += std::memcmp(&a, &b, sizeof a) != 0;
    }
  CHECK(differ == 0);
  CHECK(differ_loaded == 0);
  std::remove(path.c_str());
}

TEST_CASE("masks: bad calls") {
  Accel accel;
  CHECK_THROWS_WITH_AS(accel.set_geometry_mask(0, 1), doctest::Contains("geometry 0 does not exist"), volley::Error);
  const float tri[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const std::uint32_t idx[] = {0, 1, 2};
  accel.add_triangles(tri, 3, idx, 1);
  accel.commit();
  volley::RayPacket<8> p{};
  volley::HitPacket<8> h;
  volley::reset(h);
  CHECK_THROWS_WITH_AS(accel.intersect(p, h, nullptr), doctest::Contains("masks is null"), volley::Error);
  CHECK_THROWS_WITH_AS(accel.occluded(p, nullptr), doctest::Contains("masks is null"), volley::Error);
  const Ray r{{0.2f, 0.2f, 1}, 0, {0, 0, -1}, 10};
  Hit hit;
  CHECK_THROWS_WITH_AS(accel.intersect(&r, nullptr, 1, &hit), doctest::Contains("masks is null"), volley::Error);
  CHECK(accel.intersect(r, 1).hit());
  CHECK(!accel.intersect(r, 0).hit());
  accel.set_geometry_mask(0, 1);
  CHECK_THROWS_WITH_AS(accel.intersect(r, 1), doctest::Contains("commit"), volley::Error);
}

TEST_CASE("masks: polygons in the first of several layers are hit after the later layers are built") {
  // Layers are built in descending mask order; the polygons' layer comes first here, and the
  // two after it grow the list of layers (the polygon engine keeps its own polygons).
  Accel accel;
  const float square[] = {-1, -1, 2, 1, -1, 2, 1, 1, 2, -1, 1, 2};
  accel.add_polygon(square, 4);
  accel.set_geometry_mask(0, 0x4);
  const float tri[] = {-1, -1, 1, 1, -1, 1, 0, 1, 1};
  const std::uint32_t idx[] = {0, 1, 2};
  for (std::uint32_t mask : {0x2u, 0x1u}) accel.set_geometry_mask(accel.add_triangles(tri, 3, idx, 1), mask);
  accel.commit();
  CHECK(accel.info().layers == 3);
  const Ray down{{0.1f, 0.1f, 5}, 0, {0, 0, -1}, 10};
  const Hit polygon = accel.intersect(down, 0x4);
  CHECK(polygon.geom == 0);
  CHECK(polygon.t == doctest::Approx(3.0f));
  CHECK(accel.intersect(down).geom == 0);  // the polygon is nearer than the triangles
  CHECK(accel.intersect(down, 0x3).t == doctest::Approx(4.0f));
}
