// The pieces both kernel forms share: the vectorized test of each TriangleTest, and the
// decision on a candidate's quotient.
#pragma once
#include <type_traits>
#include <bit>
#include <cstdint>
#include <limits>

#include "simd/isa/arch.h"
#include "simd/triangle/kernel_common.h"
#include "simd/triangle/moller.h"
#include "simd/triangle/plane.h"
#include "simd/rays/prepared_packet.h"
#include "simd/rays/prepared_ray.h"
#include "simd/rays/ray_packet.h"
#include "simd/triangle/triangle_blocks.h"
#include "simd/triangle/triangle_test.h"
#include "simd/triangle/watertight.h"
#include "volley/options.h"
#include "volley/ray.h"

namespace volley::simd {

namespace detail {
template <class Arch, TriangleTest Test>
struct TestOfT;
template <class Arch>
struct TestOfT<Arch, TriangleTest::moller> {
  using type = MollerTest<Arch>;
};
template <class Arch>
struct TestOfT<Arch, TriangleTest::plane> {
  using type = PlaneTest<Arch>;
};
template <class Arch>
struct TestOfT<Arch, TriangleTest::watertight> {
  using type = WatertightTest<Arch>;
};
/// The vectorized test of `Test` on Arch (a TriangleTestLanes: triangle_test.h).
template <class Arch, TriangleTest Test>
using TestOf = typename TestOfT<Arch, Test>::type;
/// The test of the crossing queries (all hits, counts): the watertight test with the
/// exactly-once rule; Möller and plane as they are (no rule for their ties).
template <class Arch, TriangleTest Test>
using CrossingTestOf = std::conditional_t<Test == TriangleTest::watertight, WatertightTest<Arch, true>, TestOf<Arch, Test>>;

/// The valid lanes of `c` that hit, given their quotient t (cand_t) and the upper end.
template <class T>
[[gnu::always_inline]] inline auto confirmed(const typename T::Rays& r, const typename T::Cand& c,
                                             const decltype(c.t)& t, const decltype(c.t)& upper) {
  if constexpr (T::kDecision != Decision::direct)
    return T::confirm(r, c, t, upper);
  else
    return c.valid;
}

/// t of the candidate lanes (a true division for a det-scaled test).
template <class T>
[[gnu::always_inline]] inline auto cand_t(const typename T::Cand& c) {
  if constexpr (kDetScaled<T>)
    return c.t / c.den;
  else
    return c.t;
}
}  // namespace detail

}  // namespace volley::simd
