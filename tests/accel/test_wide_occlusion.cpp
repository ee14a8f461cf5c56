// Occlusion packets of the wide BVH (16 rays, and the double packets of 32 that AVX2's
// occlusion streams walk as one) on every ISA this CPU has, against brute force over the
// scalar oracle: coherent shadow packets through triangle vertices (the interval family's
// shortcut and the slab padding), and deferred hand-offs with partial masks and poisoned
// lanes.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "accel/wide/wide_accel.h"
#include "accel_test_util.h"
#include "core/bvh.h"
#include "simd/isa/dispatch.h"
#include "volley/packet.h"

using volley::Hit;
using volley::Isa;
using volley::Ray;
using volley::TriangleTest;

using namespace accel_test;

TEST_CASE("wide: coherent shadow packets through triangle vertices answer as brute force (the family's shortcut)") {
  // Shadow packets as a point light makes them, one octant and nearly parallel: 16 origins
  // on the line from a light through a triangle's vertex, beyond the vertex, some nudged off
  // it, each segment ending at the light. On AVX2 the any-hit walk asks such a packet's
  // interval family first and skips the lanes' own node tests where it settles every child;
  // the segments graze leaf boxes at the vertices (one triangle per leaf), where only the
  // padded tests keep every hit. Unpadded (Robust = false) the packets must miss some, which
  // shows this test can fail.
  const VertexAimed case_ = lone_triangles_vertex_aimed();
  const Soup& soup = case_.soup;
  std::mt19937 rng(29);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), beyond(0.02f, 0.3f);
  std::vector<Ray> rays;
  for (std::size_t t = 0; t < soup.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const glm::vec3 target = soup.vertex(t, k);
      const glm::vec3 light = target + 20.0f * glm::vec3(unit(rng), unit(rng), unit(rng));
      for (int i = 0; i < 16; ++i) {
        glm::vec3 o = target + (target - light) * beyond(rng);
        if (i % 4 == 3) o += 0.01f * glm::vec3(unit(rng), unit(rng), unit(rng));
        rays.push_back(make_ray(o, light - o, 0.0f, 1.0f));
      }
    }
  // Packets of 16, and double packets of 32 (two neighbouring packets: on AVX2 one walk).
  std::size_t unpadded_wrong[2] = {0, 0};  // over the ISAs: on some one alone rounding may not show it
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const std::vector<Hit> want = brute_force_all(soup, TriangleTest::watertight, rays, isa);
    const auto blocked = std::count_if(want.begin(), want.end(), [](const Hit& h) { return h.hit(); });
    CHECK(blocked > static_cast<long>(rays.size() / 4));
    std::size_t wrong[2][2] = {{0, 0}, {0, 0}};  // [double][robust]
    for (bool robust : {true, false}) {
      const auto wide = one_triangle_per_leaf(soup, isa, robust);
      volley::RayPacket<16> p;
      for (std::size_t first = 0; first + 16 <= rays.size(); first += 16) {
        volley::load(p, rays.data() + first, 16);
        const std::uint32_t got = wide->occluded(p);
        for (int i = 0; i < 16; ++i) wrong[0][robust] += ((got >> i) & 1u) != (want[first + i].hit() ? 1u : 0u);
      }
      volley::RayPacket<32> d;
      for (std::size_t first = 0; first + 32 <= rays.size(); first += 32) {
        volley::load(d, rays.data() + first, 32);
        const std::uint32_t got = wide->occluded(d);
        for (int i = 0; i < 32; ++i) wrong[1][robust] += ((got >> i) & 1u) != (want[first + i].hit() ? 1u : 0u);
      }
    }
    MESSAGE(std::string(volley::to_string(isa)), ": ", rays.size(), " shadow rays through vertices, ", blocked,
            " blocked; packets wrong on ", wrong[0][0], " unpadded, ", wrong[0][1], " padded; double packets on ",
            wrong[1][0], " unpadded, ", wrong[1][1], " padded");
    CHECK(wrong[0][1] == 0);
    CHECK(wrong[1][1] == 0);
    unpadded_wrong[0] += wrong[0][0];
    unpadded_wrong[1] += wrong[1][0];
  }
  CHECK(unpadded_wrong[0] > 0);
  CHECK(unpadded_wrong[1] > 0);
}

TEST_CASE("wide: occlusion packets with deferred hand-offs answer as brute force (every ISA and test)") {
  // Trees past kDeferHandoffBytes walk the lanes left to single rays after the packet's own
  // walk; a small soup with the deferral turned on takes that path on every packet that
  // hands lanes off. Shadow-like packets: origins around a point of the soup, segments to
  // one of a few lights, some of them past the soup (one octant, spread origins: the fused
  // per-lane walk); then incoherent ones, partial masks and poisoned lanes.
  const Soup soup = random_soup(3000, 41);
  const auto boxes = soup.boxes();
  const volley::core::Bvh bvh = volley::core::build_bvh(boxes, {});
  std::vector<std::uint32_t> ids(soup.size());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<std::uint32_t>(i);
  std::mt19937 rng(43);
  std::uniform_real_distribution<float> pos(-10.0f, 10.0f), near(-0.6f, 0.6f);
  const glm::vec3 lights[3] = {{25.0f, 30.0f, 20.0f}, {-3.0f, 4.0f, 2.0f}, {-30.0f, 12.0f, -18.0f}};
  std::vector<Ray> rays;
  for (int packet = 0; packet < 240; ++packet) {
    const glm::vec3 centre(pos(rng), pos(rng), pos(rng));
    const glm::vec3 light = lights[packet % 3];
    for (int i = 0; i < 16; ++i) {
      const glm::vec3 o = centre + glm::vec3(near(rng), near(rng), near(rng));
      rays.push_back(make_ray(o, light - o, 0.0f, 1.0f));
    }
  }
  const std::vector<Ray> mixed = mixed_rays(70, 10.0f, 47);
  rays.insert(rays.end(), mixed.begin(), mixed.end());
  against_brute_force(soup, rays, [&](TriangleTest test, Isa isa, const std::vector<Hit>& want) {
    const auto wide = volley::accel::WideAccel::create(test, isa);
    wide->build(bvh, soup.xyz.data(), ids.data());
    for (bool defer : {true, false}) {
      CAPTURE(defer);
      wide->defer_handoffs(defer);
      std::size_t wrong = 0, wrong_partial = 0, wrong_poisoned = 0;
      volley::RayPacket<16> p;
      for (std::size_t first = 0; first + 16 <= rays.size(); first += 16) {
        volley::load(p, rays.data() + first, 16);
        const std::uint32_t all = wide->occluded(p);
        p.active = 0xb5a6u;
        const std::uint32_t partial = wide->occluded(p);
        p.active = 0xffffu;
        for (int i = 1; i < 16; i += 5) p.dz[i] = kNaN;
        const std::uint32_t poisoned = wide->occluded(p);
        for (int i = 0; i < 16; ++i) {
          const bool hit = want[first + i].hit();
          wrong += ((all >> i) & 1u) != (hit ? 1u : 0u);
          wrong_partial += ((partial >> i) & 1u) != ((0xb5a6u >> i) & 1u && hit ? 1u : 0u);
          wrong_poisoned += ((poisoned >> i) & 1u) != (i % 5 != 1 && hit ? 1u : 0u);
        }
      }
      CHECK(wrong == 0);
      CHECK(wrong_partial == 0);
      CHECK(wrong_poisoned == 0);
      // Double packets (32 lanes: on AVX2 one walk, elsewhere two packets), lanes of
      // the upper half inactive or poisoned too.
      constexpr std::uint32_t kSome = 0xc3e1b5a6u;
      std::size_t wrong32 = 0, wrong32_partial = 0, wrong32_poisoned = 0;
      volley::RayPacket<32> d;
      for (std::size_t first = 0; first + 32 <= rays.size(); first += 32) {
        volley::load(d, rays.data() + first, 32);
        const std::uint32_t all = wide->occluded(d);
        d.active = kSome;
        const std::uint32_t partial = wide->occluded(d);
        d.active = ~0u;
        for (int i = 1; i < 32; i += 5) d.dz[i] = kNaN;
        d.tmax[30] = kNaN;
        const std::uint32_t poisoned = wide->occluded(d);
        for (int i = 0; i < 32; ++i) {
          const bool hit = want[first + i].hit();
          wrong32 += ((all >> i) & 1u) != (hit ? 1u : 0u);
          wrong32_partial += ((partial >> i) & 1u) != ((kSome >> i) & 1u && hit ? 1u : 0u);
          wrong32_poisoned += ((poisoned >> i) & 1u) != (i % 5 != 1 && i != 30 && hit ? 1u : 0u);
        }
      }
      CHECK(wrong32 == 0);
      CHECK(wrong32_partial == 0);
      CHECK(wrong32_poisoned == 0);
    }
  });
}
