// The API's promises at their edges, on every ISA and triangle test: a reported t lies in
// [tmin, tmax) even when the interval ends sit on the hit itself; rays with subnormal
// direction components (reciprocals that overflow to ±inf) give the oracle's answers in
// every form; and the packet screen keeps the frustum walk for a packet whose first lane
// is rejected.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "accel_test_util.h"
#include "simd/isa/arch.h"
#include "simd/wide/wide_traverse.h"

using namespace accel_test;

namespace {

/// Every ray that hits in `base`, again with its interval ending exactly at the hit and
/// starting just past it (and the one-ulp interval around it): a reported t must still
/// lie inside. Non-finite hits are left out.
std::vector<Ray> interval_edge_rays(const Accel& accel, const std::vector<Ray>& base) {
  std::vector<Ray> out;
  for (const Ray& r : base) {
    const Hit h = accel.intersect(r);
    if (!h.hit() || !std::isfinite(h.t)) continue;
    Ray a = r, b = r, c = r;
    a.tmax = h.t;
    b.tmin = std::nextafter(h.t, kInf);
    c.tmin = h.t, c.tmax = std::nextafter(h.t, kInf);
    out.insert(out.end(), {a, b, c});
  }
  return out;
}

/// Rays whose hits, from every form, leave [tmin, tmax): singles and streams (packets are
/// compared with them by check_forms).
std::size_t outside_interval(const Accel& accel, const std::vector<Ray>& rays) {
  std::size_t bad = 0;
  std::vector<Hit> stream(rays.size());
  accel.intersect(rays.data(), rays.size(), stream.data());
  for (std::size_t i = 0; i < rays.size(); ++i)
    for (const Hit& h : {accel.intersect(rays[i]), stream[i]})
      bad += h.hit() && !(rays[i].tmin <= h.t && h.t < rays[i].tmax);
  return bad;
}

}  // namespace

TEST_CASE("contract: a reported t keeps tmin <= t < tmax when the interval ends on the hit") {
  // Möller decides on det-scaled values; its quotient could land an ulp outside the
  // interval before the quotient was checked too. Every test, every ISA, the oracle.
  const Soup soup = random_soup(600, 31);
  const std::vector<Ray> base = mixed_rays(60, 10.0f, 37);
  const std::vector<Isa> isas = all_isas();
  for (TriangleTest test : kTests) {
    for (Isa isa : isas) {
      const std::string what = std::string(volley::to_string(test)) + " " + std::string(volley::to_string(isa));
      CAPTURE(what);
      const Accel accel = soup.accel(test, isa);
      const std::vector<Ray> rays = interval_edge_rays(accel, base);
      REQUIRE(rays.size() > 300);
      CHECK(outside_interval(accel, rays) == 0);
      // The brute-force oracle obeys it too, and every form agrees with it.
      const std::vector<Hit> want = brute_force_all(soup, test, rays, isa);
      std::size_t oracle_bad = 0;
      for (std::size_t i = 0; i < rays.size(); ++i)
        oracle_bad += want[i].hit() && !(rays[i].tmin <= want[i].t && want[i].t < rays[i].tmax);
      CHECK(oracle_bad == 0);
      report(check_forms(accel, rays, want, 41), what);
    }
  }
}

TEST_CASE("contract: subnormal direction components (1 / d overflows) give the oracle's answers") {
  // A grid of triangles whose boxes have planes at integer x and y, each plane touching a
  // triangle at one vertex only, and rays from origins on those planes: (plane - org) * inf
  // = 0 * inf = NaN slab distances, in the single-ray, per-lane and frustum walks alike.
  // (A ray running along a triangle's edge in a box plane would be no test of the walk: a
  // float triangle test may hit that edge although the exact ray, a subnormal step
  // outside, misses the box.)
  Soup soup;
  for (int i = -4; i < 4; ++i)
    for (int j = -4; j < 4; ++j) {
      const float x = float(i), y = float(j);
      soup.add({x, y + 0.5f, 0.0f}, {x + 1, y + 0.2f, 0.5f}, {x + 0.7f, y + 1, 1.0f});
      soup.add({x + 0.3f, y, 1.5f}, {x + 1, y + 0.6f, 2.0f}, {x, y + 0.9f, 1.0f});
    }
  std::vector<Ray> rays;
  for (const float tiny : {1e-40f, -1e-40f, 1e-45f, -1e-38f}) {
    for (int i = -5; i <= 5; ++i) {
      // Packets of 16 sharing one origin (frustum walk), one octant, subnormal x.
      const glm::vec3 o(float(i), 0.25f * float(i), 6.0f);
      for (int k = 0; k < 16; ++k)
        rays.push_back(make_ray(o, {tiny, 0.05f * float(k % 4) - 0.1f, -1.0f - 0.01f * float(k / 4)}));
      // Spread origins on integer planes in x and y (per-lane walk), subnormal x and y.
      for (int k = 0; k < 16; ++k)
        rays.push_back(make_ray({float(i), float(k % 8 - 4), 5.0f}, {tiny, k < 8 ? tiny : 0.3f, -1.0f}));
    }
  }
  std::vector<Isa> isas = simd_isas();
  for (TriangleTest test : kTests) {
    const std::vector<Hit> want = brute_force_all(soup, test, rays);
    std::size_t hits = 0;
    for (const Hit& h : want) hits += h.hit();
    CHECK(hits > rays.size() / 100);  // hits and misses both
    report(check_forms(soup.accel(test, Isa::scalar), rays, want, 43),
           std::string(volley::to_string(test)) + " scalar");
    for (Isa isa : isas)
      report(check_forms(soup.accel(test, isa), rays, brute_force_all(soup, test, rays, isa), 47),
             std::string(volley::to_string(test)) + " " + std::string(volley::to_string(isa)));
  }
}

namespace {

/// screen()'s verdict for a pinhole packet of 16 lanes whose lane 0 is `first`.
template <class Arch>
volley::simd::detail::PacketWalk screened_walk(const Ray& first) {
  using Kernels = volley::simd::WideKernels<Arch, TriangleTest::watertight>;
  volley::RayPacket<16> p;
  std::vector<Ray> rays;
  rays.push_back(first);
  for (int k = 1; k < 16; ++k)
    rays.push_back(make_ray({1.0f, 2.0f, 3.0f}, {0.1f * float(k % 4) + 0.05f, 0.1f * float(k / 4) + 0.05f, -1.0f}));
  volley::load(p, rays.data(), 16);
  volley::simd::detail::PacketSetup<16> setup;
  Kernels::screen(p, setup);
  CHECK(setup.valid == (std::isnan(first.dir[1]) || std::isinf(first.org[0]) ? 0xfffeu : 0xffffu));
  return setup.walk;
}

}  // namespace

TEST_CASE("contract: a rejected first lane does not take the frustum walk's common origin") {
  // One origin for every valid lane: the frustum walk, whatever lane 0 holds
  // when lane 0 is rejected; a valid lane 0 elsewhere makes the origins differ (the
  // frustum walk only where the query asks for spread origins).
  const Ray nan_dir = make_ray({7.0f, -3.0f, 0.5f}, {0.2f, kNaN, -1.0f});
  const Ray inf_org = make_ray({kInf, 2.0f, 3.0f}, {0.2f, 0.2f, -1.0f});
  const Ray same = make_ray({1.0f, 2.0f, 3.0f}, {0.2f, 0.2f, -1.0f});
  const Ray elsewhere = make_ray({1.5f, 2.0f, 3.0f}, {0.2f, 0.2f, -1.0f});
  using namespace volley::simd;
  constexpr auto kFrustum = detail::PacketWalk::frustum, kSpread = detail::PacketWalk::spread_frustum;
  if (cpu_has(Isa::sse42)) {
    CHECK(screened_walk<Sse42>(nan_dir) == kFrustum);
    CHECK(screened_walk<Sse42>(inf_org) == kFrustum);
    CHECK(screened_walk<Sse42>(same) == kFrustum);
    CHECK(screened_walk<Sse42>(elsewhere) == kSpread);
  }
  if (cpu_has(Isa::avx2)) {
    CHECK(screened_walk<Avx2>(nan_dir) == kFrustum);
    CHECK(screened_walk<Avx2>(elsewhere) == kSpread);
  }
  if (cpu_has(Isa::avx512)) {
    CHECK(screened_walk<Avx512>(nan_dir) == kFrustum);
    CHECK(screened_walk<Avx512>(inf_org) == kFrustum);
    CHECK(screened_walk<Avx512>(elsewhere) == kSpread);
  }
}
