// The stream walk (simd/wide/stream_walk.h): a batch of rays walking the tree together,
// each node's list split by its children's boxes. Its kernel forms against brute force over
// the scalar oracle on every ISA this CPU has (Accel takes it on AVX-512 and AVX2), across
// batch boundaries, with bad rays and entry bounds; the padding of its box test (mutation
// check); and Accel's stream policy, which hands it runs of incoherent rays.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "accel/wide/wide_accel.h"
#include "accel_test_util.h"
#include "core/bvh.h"
#include "simd/isa/dispatch.h"
#include "simd/stream_scratch.h"
#include "volley/accel.h"

using namespace accel_test;

namespace {

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

/// hits[i].t on entry bounds the search: a bound at the wanted hit finds nothing nearer
/// (the entry stays as it was), a bound beyond it finds the wanted hit. The wrong answers.
std::size_t wrong_with_bounds(const volley::accel::WideAccel& wide, const std::vector<Ray>& rays,
                              const std::vector<Hit>& want) {
  std::vector<Hit> bounded(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    bounded[i].prim = 0xdeadbeefu;
    bounded[i].t = want[i].hit() ? (i % 2 ? want[i].t : want[i].t * 1.5f + 1.0f) : 1e30f;
  }
  wide.intersect(rays.data(), rays.size(), bounded.data());
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const bool at_hit = want[i].hit() && i % 2;
    wrong += at_hit ? bounded[i].prim != 0xdeadbeefu
                    : (want[i].hit() ? !agree(bounded[i], want[i]) : bounded[i].prim != 0xdeadbeefu);
  }
  return wrong;
}

}  // namespace

TEST_CASE("stream walk: the kernels' stream forms equal brute force on every ISA and test") {
  const Soup soup = random_soup(2500, 31);
  // More rays than one batch of the walk, so that batches follow one another.
  std::vector<Ray> rays = bounce_rays(volley::simd::kStreamBatch + 1500, 11.0f, 5);
  const std::vector<Ray> mixed = mixed_rays(40, 10.0f, 9);
  rays.insert(rays.end(), mixed.begin(), mixed.end());
  const Built built = build(soup);
  against_brute_force(soup, rays, [&](TriangleTest test, Isa isa, const std::vector<Hit>& want) {
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

    CHECK(wrong_with_bounds(*wide, rays, want) == 0);

    // Short streams and odd lengths (below a group of lanes, one ray, none).
    for (std::size_t n : {std::size_t{0}, std::size_t{1}, std::size_t{15}, std::size_t{17}, std::size_t{300}}) {
      std::vector<Hit> few(n);
      wide->intersect(rays.data() + 100, n, few.data());
      std::size_t wrong_few = 0;
      for (std::size_t i = 0; i < n; ++i) wrong_few += !agree(few[i], want[100 + i]);
      CHECK(wrong_few == 0);
    }
  });
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

TEST_CASE("Accel's occlusion streams of shadow rays: double packets, a run held back, a tail, as single rays") {
  // Runs of 16 shadow rays (one light, one octant) go as packets; on AVX2 two neighbouring
  // runs as one double packet of 32. Here an odd number of shadow runs, one bounce run (to
  // the stream walk or ray by ray) between two of them, a run with NaN lanes, and a tail of
  // 7: a run held back for its neighbour must still be answered, and once only.
  const Soup soup = random_soup(2000, 43);
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> pos(-10.0f, 10.0f), near(-0.8f, 0.8f);
  const glm::vec3 light(30.0f, 24.0f, 18.0f);
  const std::vector<Ray> bounce = bounce_rays(16, 11.0f, 19);
  std::vector<Ray> rays;
  for (int run = 0; run < 41; ++run) {
    if (run == 6) rays.insert(rays.end(), bounce.begin(), bounce.end());
    const glm::vec3 centre(pos(rng), pos(rng), pos(rng));
    for (int i = 0; i < 16; ++i) {
      const glm::vec3 o = centre + glm::vec3(near(rng), near(rng), near(rng));
      rays.push_back(make_ray(o, light - o, 0.0f, 1.0f));
    }
    if (run == 9) rays.back().dir[2] = kNaN, rays[rays.size() - 5].tmax = kNaN;
  }
  for (int i = 0; i < 7; ++i) rays.push_back(rays[3 * i]);
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    Accel accel;
    std::vector<std::uint32_t> idx(3 * soup.size());
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
    accel.add_triangles(soup.xyz.data(), 3 * soup.size(), idx.data(), soup.size());
    accel.commit(volley::Options{TriangleTest::watertight, isa});
    std::vector<std::uint8_t> blocked(rays.size(), 7);
    accel.occluded(rays.data(), rays.size(), blocked.data());
    std::size_t wrong = 0, hit = 0;
    for (std::size_t i = 0; i < rays.size(); ++i) {
      const bool want = accel.occluded(rays[i]);
      hit += want;
      wrong += blocked[i] != (want ? 1 : 0);
    }
    CHECK(hit > rays.size() / 10);
    CHECK(hit < rays.size() * 9 / 10);
    CHECK(wrong == 0);
  }
}

TEST_CASE("stream walk: long leaf lists tested in lanes give the single ray's hit bit for bit") {
  // A grid of 6 x 3 unit squares (two triangles each, shared edges and vertices) and a tilted copy
  // above it, in one leaf (the root) or in leaves of at most eight: the leaves' lists are
  // long, so the walk tests them L rays at a time in lanes, with mixed shear permutations
  // (rays from all sides) and lists that are not whole groups of lanes. Every ray aims
  // exactly at a vertex or an edge midpoint. t, u, v and prim must equal the single-ray
  // walk's, bit for bit (across leaves a tie between triangles at one t may go to either);
  // bounds on entry and bad rays as in the stream forms' test.
  Soup soup;
  for (int y = -2; y < 1; ++y)
    for (int x = -3; x < 3; ++x) {
      const glm::vec3 a(x, y, 0), b(x + 1, y, 0), c(x + 1, y + 1, 0), d(x, y + 1, 0);
      soup.add(a, b, c);
      soup.add(a, c, d);
      soup.add(a + glm::vec3(0, 0, 2) + 0.25f * glm::vec3(0, 0, x), b + glm::vec3(0, 0, 2 + 0.25f * (x + 1)),
               c + glm::vec3(0, 0, 2 + 0.25f * (x + 1)));
    }
  std::mt19937 rng(77);
  std::uniform_real_distribution<float> side(-9.0f, 9.0f);
  std::uniform_int_distribution<int> grid(-8, 8), row(-4, 4);
  std::vector<Ray> rays;
  for (int i = 0; i < 3 * 1024 + 5; ++i) {
    const glm::vec3 target(0.5f * static_cast<float>(grid(rng)), 0.5f * static_cast<float>(row(rng)),
                           i % 3 == 0 ? 0.0f : 0.5f * static_cast<float>(grid(rng) % 3));
    const glm::vec3 o(side(rng), side(rng), side(rng));
    Ray ray = make_ray(o, target - o, 0.0f, i % 5 == 1 ? 0.8f : kInf);
    if (i % 97 == 3) ray.dir[1] = kNaN;
    rays.push_back(ray);
  }
  for (int leaf : {54, 8}) {  // (one leaf: 54 triangles, 14 blocks of 4 on SSE4.2)
    volley::core::BvhBuildOptions options;
    options.max_leaf_size = leaf;
    options.min_leaf_size = leaf;
    const Built built = build(soup, options);
    for (Isa isa : simd_isas()) {
      CAPTURE(leaf);
      CAPTURE(std::string(volley::to_string(isa)));
      const auto wide = volley::accel::WideAccel::create(TriangleTest::watertight, isa);
      wide->build(built.bvh, soup.xyz.data(), built.ids.data());
      std::vector<Hit> want(rays.size());
      for (std::size_t i = 0; i < rays.size(); ++i) wide->intersect(rays[i], want[i]);
      std::vector<Hit> hits(rays.size());
      wide->intersect(rays.data(), rays.size(), hits.data());
      std::size_t wrong = 0, hit = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        hit += want[i].hit();
        // In one leaf the tie rule (the first triangle in block order) picks the same prim;
        // across leaves a tie at one t goes to the leaf visited first, which the two walks
        // order differently.
        const bool tie = leaf != 54 && hits[i].hit() && want[i].hit() && hits[i].t == want[i].t;
        wrong += hits[i].prim == want[i].prim ? std::memcmp(&hits[i], &want[i], 3 * sizeof(float)) != 0 : !tie;
      }
      CHECK(hit > rays.size() / 3);
      CHECK(wrong == 0);
      // The brute-force oracle agrees (prim, or t at a tie).
      const std::vector<Hit> oracle = brute_force_all(soup, TriangleTest::watertight, rays, isa);
      std::size_t disagree = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) disagree += !agree(hits[i], oracle[i]);
      CHECK(disagree == 0);
CHECK(wrong_with_bounds(*wide, rays, want) == 0);  // bounds on entry
    }
  }
}
