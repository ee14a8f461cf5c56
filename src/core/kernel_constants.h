// The constants and small formulas that the scalar oracle and the SIMD kernels share: one
// definition each, not copies kept equal by a test. No GLM and nothing but constexpr values
// and always-inlined templates, so the per-ISA files include it (docs/style.md rule 2).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>

#include "core/rounding.h"

namespace volley::core {

/// Deepest leaf build_bvh produces (root depth 0; every leaf depth < kBvhMaxDepth).
/// A traversal stack of kBvhMaxDepth entries can therefore never overflow.
inline constexpr int kBvhMaxDepth = 64;

/// Factor applied to a box's exit distance so that the slab test is conservative:
/// each slab distance (bound - org) * inv_dir carries three roundings (the difference,
/// the reciprocal, the product), so entry and exit are each within gamma(3) of their
/// exact values and padding the exit by 2 gamma(3) covers both (pbrt-v3
/// Bounds3::IntersectP; Ize, "Robust BVH ray traversal", JCGT 2013). In float this is
/// 1 + 3 ulp, about 1 + 3.6e-7.
inline constexpr float kSlabExitPad = 1.0f + 2.0f * rounding_gamma(3);
static_assert(kSlabExitPad > 1.0f, "the padding must not round away");

/// Relative widening of the lower end of the watertight test's scaled range prefilter
/// (intersect_watertight, core/triangle_watertight.h; simd/triangle/watertight.h).
template <class T>
inline constexpr T kScaledPad = 2 * std::numeric_limits<T>::epsilon();

/// Factors {lo, hi} such that a ray hits a triangle with tmin <= t < upper whenever its
/// det-scaled distance (t det, det's sign folded in) lies strictly between fl(lo |det|) and
/// fl(hi |det|) and the edge and det tests pass: the division-free any-hit decision of the
/// SIMD kernels (simd/triangle/watertight.h, sure_hit; the reasons are given there). Lanes outside
/// (within ~16 ulps of either end, or not hit) are left to the quotient test.
/// Always inlined: the single-ray walk (simd/wide/wide_traverse.h) calls it from the per-ISA
/// files, which must not emit a copy of their own.
template <class T>
[[gnu::always_inline]] constexpr std::pair<T, T> sure_quotient_range(T tmin, T upper) {
  constexpr T kEps = std::numeric_limits<T>::epsilon(), kMin = std::numeric_limits<T>::min();
  constexpr T kInf = std::numeric_limits<T>::infinity();
  const T lo = tmin > 0 ? (tmin < kMin ? kMin : tmin) * (1 + 8 * kEps) : tmin <= 0 ? T(0) : kInf;
  const T hi = upper >= kMin
                   ? (upper < std::numeric_limits<T>::max() ? upper : std::numeric_limits<T>::max()) * (1 - 8 * kEps)
                   : -kInf;
  return {lo, hi};
}

/// The axes of make_woop_ray, tabulated. Entry c | n << 3 is for the comparisons
/// c = (|d0| >= |d1|) | (|d0| >= |d2|) << 1 | (|d1| >= |d2|) << 2 and the signs
/// n = (d0 < 0) | (d1 < 0) << 1 | (d2 < 0) << 2; it packs kx | ky << 2 | kz << 4. kz is
/// where |d| is largest (ties: the lowest axis), kx and ky the next axes cyclically,
/// swapped when looking down -z (which keeps the winding, so det's sign is the facing).
/// A lookup, not branches: for incoherent rays each of those tests is a coin toss to the
/// branch predictor (1.5 mispredictions per ray), and the single-ray walk
/// (simd/wide/wide_traverse.h) forms c and n with two vector compares.
inline constexpr std::array<std::uint8_t, 64> kWoopAxes = [] {
  std::array<std::uint8_t, 64> table{};
  for (int i = 0; i < 64; ++i) {
    const int c1 = i & 1, c2 = (i >> 1) & 1, c3 = (i >> 2) & 1;
    // kz = |d0| >= |d1| ? (|d0| >= |d2| ? 0 : 2) : (|d1| >= |d2| ? 1 : 2)
    const int kz = c1 ? (c2 ? 0 : 2) : (c3 ? 1 : 2);
    int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
    if ((i >> (3 + kz)) & 1) std::swap(kx, ky);
    table[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(kx | ky << 2 | kz << 4);
  }
  return table;
}();

}  // namespace volley::core
