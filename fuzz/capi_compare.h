// fuzz_capi's referees: when two answers agree (ulps, ties, the sign of zeros), which rays
// and answers the walks promise to agree on, and the scalar oracle's check of soundness and
// completeness (fuzz_capi.cpp's top comment says what each promises).
#pragma once
#include <cstdint>
#include <vector>

#include "capi_case.h"
#include "volley/volley.h"

namespace fuzz_capi {

bool same_bits(const volley_hit& a, const volley_hit& b);
/// The same answer but for the sign of zeros: the ids bit for bit, t u v equal as numbers
/// (or both NaN).
bool same_values(const volley_hit& a, const volley_hit& b);
/// `got` and `want` answer the same ray alike: both miss, or the same primitive of the same
/// geometry at the same t (and u, v when `exact`), or two prims within 2 ulps of t (a
/// coplanar tie). The plane and Möller tests: within 32 ulps, for their false hits beside
/// an edge, which a walk keeps or culls by the order it opens leaves (docs/accuracy.md,
/// "Known traps": a ray from ~1e6 away, a sliver with a vertex at 1e30; the watertight
/// test agrees throughout).
bool agree(const volley_hit& got, const volley_hit& want, bool exact);
/// Whether the walks promise to agree on `r`: tmin >= 0, robust box tests, and no direction
/// component so small that its reciprocal overflows (1/d = inf turns a finite slab
/// distance infinite; found by this fuzzer, left for an issue).
bool comparable(const volley_ray& r);
/// Whether `h` (an answer to `r`) is a hit the exact ray can have: a miss, a polygon, or a
/// triangle whose box the exact ray meets within [tmin, tmax] and holds the hit point
/// (within rounding). A float test can report a hit the exact ray does not have (rays from
/// 1e27 away, triangles with a vertex at 1e38, a ray in a box's face plane stepping out by
/// a subnormal direction component); whether a walk meets it then depends on which boxes
/// that walk culls, so forms may differ on such a ray, and are not compared there.
bool plausible(const volley_ray& r, const volley_hit& h);
/// Checks the single-ray answers `got` for soundness and completeness.
void check_against_oracle(const std::vector<volley_ray>& rays, const std::vector<volley_hit>& got,
                          const Geometry& g, std::uint32_t first_triangle, bool triangles_added,
                          volley_triangle_test test, volley_isa isa, bool reference_double);

}  // namespace fuzz_capi
