// The scalar oracle's boxes: BBox's extend, emptiness, area and containment, and the
// slab test (core::intersect_box) on slab planes, zero direction components and the exit
// padding. The BVH built over them is tested in test_bvh.cpp.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "core/bbox.h"
#include "core/bvh_traverse.h"
#include "core/geometry.h"

namespace {

using namespace volley::core;
using Ray = volley::core::RayT<float>;

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

}  // namespace

TEST_CASE("bvh: BBox extend, emptiness, area and containment") {
  BBox b;
  CHECK(b.empty());
  CHECK(b.half_area() == 0.0f);
  b.extend(glm::vec3(1, 2, 3));
  CHECK(!b.empty());
  CHECK(b.half_area() == 0.0f);  // a point
  b.extend(glm::vec3(2, 4, 7));
  CHECK(b.lo == glm::vec3(1, 2, 3));
  CHECK(b.hi == glm::vec3(2, 4, 7));
  CHECK(b.center() == glm::vec3(1.5f, 3, 5));
  CHECK(b.half_area() == 1 * 2 + 2 * 4 + 4 * 1);
  CHECK(b.largest_axis() == 2);
  CHECK(b.contains(glm::vec3(2, 2, 3)));
  CHECK(!b.contains(glm::vec3(2.5f, 2, 3)));
  CHECK(b.contains(BBox{}));  // the empty box is inside every box
  // NaN coordinates are ignored by extend; a box of NaN points stays empty.
  BBox n;
  n.extend(glm::vec3(kNaN, 1, kNaN));
  CHECK(n.empty());
  n.extend(glm::vec3(0, 0, 0));
  CHECK(n.lo == glm::vec3(0, 0, 0));
  CHECK(n.hi == glm::vec3(0, 1, 0));
  CHECK(BBox{glm::vec3(kNaN), glm::vec3(kNaN)}.empty());
  // center() does not overflow near FLT_MAX.
  const float big = std::numeric_limits<float>::max();
  CHECK(std::isfinite(BBox{glm::vec3(big), glm::vec3(big)}.center().x));
}

TEST_CASE("bvh: slab test keeps rays on a slab plane with a zero direction component") {
  // Flat box z = 0 over [0,1]^2; rays lying in its plane or on its side planes.
  const BBox flat{glm::vec3(0, 0, 0), glm::vec3(1, 1, 0)};
  float entry = 0.0f;
  for (float zero : {0.0f, -0.0f}) {
    // In the plane z = 0 (lo.z = hi.z = org.z, dir.z = ±0: both z distances NaN).
    const Ray in_plane{{-1, 0.5f, 0}, 0, {1, 0.25f, zero}, kInf};
    CHECK(volley::core::intersect_box(flat, volley::core::make_box_ray(in_plane), kInf, entry));
    CHECK(entry == 1.0f);
    // On the side plane x = 0 (= lo.x), dir.x = ±0; and on x = 1 (= hi.x).
    for (float x : {0.0f, 1.0f}) {
      const Ray down{{x, 0.5f, 2}, 0, {zero, 0, -1}, kInf};
      CHECK(volley::core::intersect_box(flat, volley::core::make_box_ray(down), kInf, entry));
      CHECK(entry == 2.0f);
    }
    // Parallel to the plane but off it: culled.
    const Ray above{{-1, 0.5f, 0.5f}, 0, {1, 0, zero}, kInf};
    CHECK(!volley::core::intersect_box(flat, volley::core::make_box_ray(above), kInf, entry));
    // Next to the box, zero x component, outside the x slab: culled.
    const Ray beside{{1.5f, 0.5f, 2}, 0, {zero, 0, -1}, kInf};
    CHECK(!volley::core::intersect_box(flat, volley::core::make_box_ray(beside), kInf, entry));
  }
}

TEST_CASE("bvh: the padded slab test never misses a box the exact ray touches") {
  // Rays from random origins aimed at points on the edges and corners of random boxes,
  // where entry and exit coincide in exact arithmetic. A double-precision reference
  // (the slab distances of the float inputs, divided, not multiplied by a rounded
  // reciprocal) decides whether the ray touches the box; the padded test must accept
  // every such ray. The unpadded test misses some, which shows the padding is needed
  // and that this test can fail.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  std::size_t touching = 0, padded_missed = 0, unpadded_missed = 0;
  for (int i = 0; i < 200000; ++i) {
    const float scale = std::ldexp(1.0f, static_cast<int>(rng() % 16) - 8);
    BBox box;
    box.extend(scale * glm::vec3(unit(rng), unit(rng), unit(rng)));
    box.extend(scale * glm::vec3(unit(rng), unit(rng), unit(rng)));
    // A point on an edge: two coordinates on bounds, one free (or a corner).
    glm::vec3 target;
    const int free_axis = static_cast<int>(rng() % 4);  // 3: a corner
    for (int a = 0; a < 3; ++a)
      target[a] = a == free_axis ? box.lo[a] + unit(rng) * (box.hi[a] - box.lo[a])
                                 : (rng() % 2 ? box.hi[a] : box.lo[a]);
    const glm::vec3 org = target + 3.0f * scale * glm::vec3(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.5f);
    const Ray ray{org, 0.0f, target - org, kInf};
    double t_enter = 0.0, t_exit = kInf;
    for (int a = 0; a < 3; ++a) {
      const double d = ray.dir[a];
      if (d == 0.0) {
        if (org[a] < box.lo[a] || org[a] > box.hi[a]) t_exit = -1.0;
        continue;
      }
      double t0 = (double(box.lo[a]) - org[a]) / d, t1 = (double(box.hi[a]) - org[a]) / d;
      if (t0 > t1) std::swap(t0, t1);
      t_enter = std::max(t_enter, t0);
      t_exit = std::min(t_exit, t1);
    }
    if (!(t_enter <= t_exit)) continue;
    ++touching;
    const auto r = volley::core::make_box_ray(ray);
    float entry = 0.0f;
    if (!volley::core::intersect_box<true>(box, r, kInf, entry)) ++padded_missed;
    if (!volley::core::intersect_box<false>(box, r, kInf, entry)) ++unpadded_missed;
  }
  MESSAGE("edge/corner rays touching their box: ", touching, ", unpadded test missed ",
          unpadded_missed, ", padded missed ", padded_missed);
  CHECK(touching > 50000);
  CHECK(padded_missed == 0);
  CHECK(unpadded_missed > 0);
}
