// The accuracy report's rows for the queries beyond the first hit (docs/crossings.md):
// per ISA, wrong crossing parities on rays from inside closed meshes aimed exactly at
// vertices, edge midpoints and diagonals and in random directions (offsets 0 .. 1e6) and on axis-aligned box rays,
// wrong inside/outside answers against an exact reference, the distance error against a
// double-precision brute force, and the speed of counting and of distances.
#pragma once
#include <cstddef>
#include <vector>

#include "volley/options.h"

namespace volley::accuracy {

struct QueryRow {
  Isa isa = Isa::scalar;
  std::size_t parity_rays = 0, parity_errors = 0;      ///< aimed and random rays from inside, odd count expected
  std::size_t box_rays = 0, box_errors = 0;            ///< axis-aligned rays through a box mesh's grid, count 1 expected
  std::size_t contains_points = 0, contains_errors = 0;  ///< points farther than 1e-6 of the size from the surface
  std::size_t distance_points = 0;
  double distance_error_max = 0;  ///< max |d - d_ref| / (eps (d_ref + size)), eps = 2^-24
  double count_ns = 0;            ///< per aimed ray, count_intersections, one thread
  double distance_ns = 0;         ///< per point, distances batch on one thread
};

/// Runs the checks on every ISA in `isas` (scalar = the oracle).
std::vector<QueryRow> run_query_checks(const std::vector<Isa>& isas);

}  // namespace volley::accuracy
