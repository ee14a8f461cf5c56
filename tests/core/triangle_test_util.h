// Shared by the scalar triangle oracle's tests (test_triangle.cpp, test_triangle_watertight.cpp):
// the three tests, one triangle, a test run in float or double, random float inputs.
#pragma once
#include <limits>
#include <random>
#include <string>

#include "core/triangle.h"

namespace triangle_test {

using namespace volley;
using namespace volley::core;
using Vec3f = Vec3<float>;
using Vec3d = Vec3<double>;

constexpr TriangleTest kTests[] = {TriangleTest::plane, TriangleTest::moller,
                                   TriangleTest::watertight};
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

inline std::string name(TriangleTest test) { return std::string(volley::to_string(test)); }

struct Tri {
  Vec3f p0, p1, p2;
};

template <class T>
bool run(TriangleTest test, const RayT<float>& ray, const Tri& tri, TriHit<T>& hit) {
  return intersect_triangle(test, volley::core::ray_cast<T>(ray), Vec3<T>(tri.p0), Vec3<T>(tri.p1),
                            Vec3<T>(tri.p2), hit);
}

inline float uniform(std::mt19937& rng, float lo, float hi) {
  return std::uniform_real_distribution<float>(lo, hi)(rng);
}
inline Vec3f uniform3(std::mt19937& rng, float lo, float hi) {
  return {uniform(rng, lo, hi), uniform(rng, lo, hi), uniform(rng, lo, hi)};
}

}  // namespace triangle_test
