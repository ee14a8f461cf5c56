// The stream walk (simd/wide/stream_walk.h): a batch of rays walking the tree together,
// each node's list split by its children's boxes. Its kernel forms against brute force over
// the scalar oracle on every ISA this CPU has (Accel takes it on AVX-512 and AVX2), across
// batch boundaries, with bad rays and entry bounds; the padding of its box test (mutation
// check); and Accel's stream policy, which hands it runs of incoherent rays.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "accel/wide_accel.h"
#include "accel_test_util.h"
#include "core/bvh.h"
#include "simd/dispatch.h"
#include "simd/stream_scratch.h"
#include "volley/accel.h"

using namespace accel_test;

namespace {

/// Bounce-like rays: from random points of the soup's box in random directions, each run
/// of 16 spread across every axis plane; every fourth ray a segment (finite tmax), bad rays
/// (NaN, Inf, an empty interval) and zero direction components among them.
std::vector<Ray> bounce_rays(std::size_t count, float extent, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-extent, extent), unit(-1.0f, 1.0f);
  std::vector<Ray> rays;
  for (std::size_t i = 0; i < count; ++i) {
    const glm::vec3 o(pos(rng), pos(rng), pos(rng));
    glm::vec3 d(unit(rng), unit(rng), unit(rng));
    if (i % 37 == 5) d.y = (i % 2) ? 0.0f : -0.0f;
    Ray ray = make_ray(o, d, 0.0f, i % 4 == 1 ? 0.5f + 4.0f * (unit(rng) + 1.0f) : kInf);
    if (i % 101 == 7) ray.dir[0] = kNaN;
    if (i % 103 == 9) ray.org[2] = -kInf;
    if (i % 107 == 11) ray.tmin = 3.0f, ray.tmax = 2.0f;
    rays.push_back(ray);
  }
  return rays;
}

/// Triangle ids 0 .. n - 1 and the binned-SAH tree of `soup` (what Accel would build).
struct Built {
  volley::core::Bvh bvh;
  std::vector<std::uint32_t> ids;
};
Built build(const Soup& soup, volley::core::BvhBuildOptions options = {}) {
  Built b{volley::core::build_bvh(soup.boxes(), options), std::vector<std::uint32_t>(soup.size())};
  for (std::size_t i = 0; i < b.ids.size(); ++i) b.ids[i] = static_cast<std::uint32_t>(i);
  return b;
}

}  // namespace

TEST_CASE("stream walk: the kernels' stream forms equal brute force on every ISA and test") {
  const Soup soup = random_soup(2500, 31);
  // More rays than one batch of the walk, so that batches follow one another.
  std::vector<Ray> rays = bounce_rays(volley::simd::kStreamBatch + 1500, 11.0f, 5);
  const std::vector<Ray> mixed = mixed_rays(40, 10.0f, 9);
  rays.insert(rays.end(), mixed.begin(), mixed.end());
  const Built built = build(soup);
  for (TriangleTest test : kTests)
    for (Isa isa : simd_isas()) {
      CAPTURE(std::string(volley::to_string(test)));
      CAPTURE(std::string(volley::to_string(isa)));
      const std::vector<Hit> want = brute_force_all(soup, test, rays, isa);
      const auto hits_wanted = std::count_if(want.begin(), want.end(), [](const Hit& h) { return h.hit(); });
      CHECK(hits_wanted > static_cast<long>(rays.size() / 10));
      CHECK(hits_wanted < static_cast<long>(rays.size() * 9 / 10));
      const auto wide = volley::accel::WideAccel::create(test, isa);
      wide->build(built.bvh, soup.xyz.data(), built.ids.data());

      std::vector<Hit> hits(rays.size());
      wide->intersect(rays.data(), rays.size(), hits.data());
      std::vector<std::uint8_t> blocked(rays.size(), 7);
      wide->occluded(rays.data(), rays.size(), blocked.data());
      std::size_t wrong = 0, wrong_blocked = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        wrong += !agree(hits[i], want[i]);
        wrong_blocked += blocked[i] != (want[i].hit() ? 1 : 0);
      }
      CHECK(wrong == 0);
      CHECK(wrong_blocked == 0);

      // hits[i].t on entry bounds the search: a bound at the wanted hit finds nothing nearer
      // (the entry stays as it was), a bound beyond it finds the wanted hit.
      std::vector<Hit> bounded(rays.size());
      for (std::size_t i = 0; i < rays.size(); ++i) {
        bounded[i].prim = 0xdeadbeefu;
        bounded[i].t = want[i].hit() ? (i % 2 ? want[i].t : want[i].t * 1.5f + 1.0f) : 1e30f;
      }
      wide->intersect(rays.data(), rays.size(), bounded.data());
      std::size_t wrong_bounded = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        const bool at_hit = want[i].hit() && i % 2;
        wrong_bounded += at_hit ? bounded[i].prim != 0xdeadbeefu : !(want[i].hit() ? agree(bounded[i], want[i])
                                                                                   : bounded[i].prim == 0xdeadbeefu);
      }
      CHECK(wrong_bounded == 0);

      // Short streams and odd lengths (below a group of lanes, one ray, none).
      for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{15}, std::size_t{17}, std::size_t{300}}) {
        std::vector<Hit> few(n);
        wide->intersect(rays.data() + 100, n, few.data());
        std::size_t wrong_few = 0;
        for (std::size_t i = 0; i < n; ++i) wrong_few += !agree(few[i], want[100 + i]);
        CHECK(wrong_few == 0);
      }
    }
}

TEST_CASE("stream walk: rays touching leaf boxes at vertices need its slab padding (mutation check)") {
  // As the wide walks' check: one triangle per leaf, rays aimed exactly at vertices. The
  // padded stream walk finds every hit brute force finds; unpadded it misses some, which
  // shows that the stream walk's own box test decides (and that this test can fail).
  VertexAimed case_ = lone_triangles_vertex_aimed();
  // Consecutive rays aim at one vertex from all around: runs of mixed octants.
  volley::core::BvhBuildOptions one_per_leaf;
  one_per_leaf.max_leaf_size = 1;
  const Built built = build(case_.soup, one_per_leaf);
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const std::vector<Hit> want = brute_force_all(case_.soup, TriangleTest::watertight, case_.rays, isa);
    std::size_t missed[2] = {0, 0};
    for (bool robust : {false, true}) {
      const auto wide = volley::accel::WideAccel::create(TriangleTest::watertight, isa, robust);
      wide->build(built.bvh, case_.soup.xyz.data(), built.ids.data());
      std::vector<Hit> hits(case_.rays.size());
      wide->intersect(case_.rays.data(), case_.rays.size(), hits.data());
      for (std::size_t i = 0; i < hits.size(); ++i) missed[robust] += !agree(hits[i], want[i]);
    }
    MESSAGE(std::string(volley::to_string(isa)), ": ", case_.rays.size(), " vertex-aimed rays in one stream; unpadded ",
            missed[0], " wrong, padded ", missed[1]);
    CHECK(missed[1] == 0);
    CHECK(missed[0] > 0);
  }
}

TEST_CASE("stream walk: Accel's streams of bounce rays answer as single rays, masks and a short tail included") {
  // On the SIMD ISAs Accel hands these runs (directions across two or more axis planes) to the
  // stream walk; on the scalar oracle they go ray by ray. Either way every answer is the
  // single ray's.
  const Soup soup = random_soup(2000, 41);
  const std::vector<Ray> rays = bounce_rays(3000 + 7, 11.0f, 13);
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    Accel accel;
    std::vector<std::uint32_t> idx(3 * soup.size());
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
    const std::uint32_t geometry = accel.add_triangles(soup.xyz.data(), 3 * soup.size(), idx.data(), soup.size());
    accel.set_geometry_mask(geometry, 0x6u);
    accel.commit(volley::Options{TriangleTest::watertight, isa});
    std::vector<std::uint32_t> masks(rays.size());
    for (std::size_t i = 0; i < rays.size(); ++i) masks[i] = i % 5 == 0 ? 0x1u : volley::kMaskAll;
    // Without masks every run (bounce rays) goes to the stream walk, which then traces the
    // caller's arrays in place: answers stale on entry must not survive.
    std::vector<Hit> hits(rays.size(), Hit{1e-3f, 0.5f, 0.5f, 3, 0, 0}), masked(rays.size());
    std::vector<std::uint8_t> blocked(rays.size(), 7), blocked_masked(rays.size(), 7);
    accel.intersect(rays.data(), rays.size(), hits.data());
    accel.occluded(rays.data(), rays.size(), blocked.data());
    accel.intersect(rays.data(), masks.data(), rays.size(), masked.data());
    accel.occluded(rays.data(), masks.data(), rays.size(), blocked_masked.data());
    std::size_t wrong = 0, wrong_masked = 0, hit = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const Hit want = accel.intersect(rays[i]);
      const Hit want_masked = accel.intersect(rays[i], masks[i]);
      hit += want.hit();
      wrong += !agree(hits[i], want) || blocked[i] != (accel.occluded(rays[i]) ? 1 : 0);
      wrong_masked += !agree(masked[i], want_masked) || blocked_masked[i] != (accel.occluded(rays[i], masks[i]) ? 1 : 0);
      if (masks[i] == 0x1u) wrong_masked += masked[i].hit() || blocked_masked[i] != 0;
    }
    CHECK(hit > rays.size() / 10);
    CHECK(wrong == 0);
    CHECK(wrong_masked == 0);
  }
}
