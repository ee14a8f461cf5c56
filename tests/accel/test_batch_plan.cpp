// The batch form's choice for incoherent closest-hit runs (accel/stream_plan.h): packets
// when the rays of a run share the nodes they visit, else the stream walk. The choice from
// the probe's counts on scenes built to fall clearly on either side, and a batch call's
// answers on both sides equal to single rays' on every ISA, at one thread and two, with
// masks, a tail and calls too short to be probed.
#include <doctest/doctest.h>

#include <random>
#include <string>
#include <vector>

#include "accel/stream_plan.h"
#include "accel/wide/wide_accel.h"
#include "accel_test_util.h"
#include "core/bvh.h"
#include "volley/accel.h"

using namespace accel_test;

namespace {

/// Rays from a sphere of radius `radius` around the origin in random directions (every run
/// of 16 spread across the axis planes), one in `aimed` of them sent at a random point of
/// the [-10, 10] box instead: most leave a scene inside that box at its root.
std::vector<Ray> outside_rays(std::size_t count, float radius, std::size_t aimed, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(-1.0f, 1.0f), inside(-10.0f, 10.0f);
  std::vector<Ray> rays;
  for (std::size_t i = 0; i < count; ++i) {
    glm::vec3 o(unit(rng), unit(rng), unit(rng));
    o = radius * glm::normalize(o + glm::vec3(1e-3f));
    const glm::vec3 d = i % aimed == 0 ? glm::vec3(inside(rng), inside(rng), inside(rng)) - o
                                       : glm::vec3(unit(rng), unit(rng), unit(rng));
    rays.push_back(make_ray(o, d));
  }
  return rays;
}

/// The six walls of the box [-e, e]^3 as 12 triangles: a room every bounce ray inside hits.
Soup room(float e) {
  Soup soup;
  for (int axis = 0; axis < 3; ++axis)
    for (float side : {-e, e}) {
      glm::vec3 c[4];
      for (int k = 0; k < 4; ++k) {
        c[k][axis] = side;
        c[k][(axis + 1) % 3] = (k == 1 || k == 2) ? e : -e;
        c[k][(axis + 2) % 3] = k >= 2 ? e : -e;
      }
      soup.add(c[0], c[1], c[2]);
      soup.add(c[0], c[2], c[3]);
    }
  return soup;
}

/// The mean leaves a ray of `rays` reaches in `wide` (the single-ray walk's counts).
double leaves_per_ray(const volley::accel::WideAccel& wide, const std::vector<Ray>& rays) {
  double leaves = 0;
  for (const Ray& r : rays) leaves += static_cast<double>(wide.walk_counts(r, false).leaves);
  return leaves / static_cast<double>(rays.size());
}

std::unique_ptr<volley::accel::WideAccel> wide_of(const Soup& soup, Isa isa) {
  std::vector<std::uint32_t> ids(soup.size());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<std::uint32_t>(i);
  auto wide = volley::accel::WideAccel::create(TriangleTest::watertight, isa);
  wide->build(volley::core::build_bvh(soup.boxes(), {}), soup.xyz.data(), ids.data());
  return wide;
}

/// A batch call's closest hits (with and without masks, on `threads`) against single rays.
void check_batch(const Soup& soup, Isa isa, const std::vector<Ray>& rays, int threads) {
  const Accel accel = soup.accel(TriangleTest::watertight, isa);
  std::vector<std::uint32_t> masks(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) masks[i] = i % 5 == 0 ? 0u : volley::kMaskAll;
  std::vector<Hit> hits(rays.size(), Hit{1e-3f, 0.5f, 0.5f, 3, 0, 0}), masked(rays.size());
  accel.intersect(rays.data(), rays.size(), hits.data(), threads);
  accel.intersect(rays.data(), masks.data(), rays.size(), masked.data(), threads);
  std::size_t wrong = 0, wrong_masked = 0, hit = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const Hit want = accel.intersect(rays[i]);
    hit += want.hit();
    wrong += !agree(hits[i], want);
    wrong_masked += masks[i] ? !agree(masked[i], want) : masked[i].hit();
  }
  CHECK(hit > rays.size() / 200);
  CHECK(wrong == 0);
  CHECK(wrong_masked == 0);
}

}  // namespace

TEST_CASE("batch plan: rays leaving near the root and trees of few leaves go as packets, rays deep in a mesh do not") {
  const Soup dense = random_soup(2000, 41), walls = room(12.0f);
  const std::vector<Ray> deep = bounce_rays(6000, 11.0f, 13), leaving = outside_rays(6000, 60.0f, 64, 17);
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    const auto wide = wide_of(dense, isa);
    // Far from the threshold either way, so that the probe's 64 rays decide as all would.
    CHECK(leaves_per_ray(*wide, deep) > 3 * volley::accel::kSharedLeavesPerRay);
    CHECK(leaves_per_ray(*wide, leaving) < volley::accel::kSharedLeavesPerRay / 3);
    CHECK(wide->stats().leaves > 16);
    CHECK_FALSE(volley::accel::runs_share_nodes(*wide, deep.data(), deep.size(), false));
    CHECK(volley::accel::runs_share_nodes(*wide, leaving.data(), leaving.size(), false));

    const auto small = wide_of(walls, isa);
    CHECK(small->stats().leaves <= 16);
    CHECK(volley::accel::runs_share_nodes(*small, deep.data(), deep.size(), false));
  }
}

TEST_CASE("batch plan: a batch answers as single rays whichever form its runs take") {
  const Soup dense = random_soup(2000, 41), walls = room(12.0f);
  // 6000 + 7 rays: probed, pieces of the call on two threads, and a tail shorter than a run.
  const std::vector<Ray> deep = bounce_rays(6007, 11.0f, 13), leaving = outside_rays(6007, 60.0f, 64, 17);
  const std::vector<Ray> unprobed(leaving.begin(), leaving.begin() + 1000);
  for (Isa isa : all_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    for (int threads : {1, 2}) {
      CAPTURE(threads);
      check_batch(dense, isa, deep, threads);
      check_batch(dense, isa, leaving, threads);
      check_batch(dense, isa, unprobed, threads);
      check_batch(walls, isa, deep, threads);
    }
  }
}
