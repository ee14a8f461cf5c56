// The measurement runner: traces every case with every configuration, against the
// double-precision reference, and returns one row per (case, configuration).
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "accuracy/cases.h"
#include "accuracy/config.h"
#include "accuracy/error_stats.h"

namespace volley::accuracy {

/// The measures of one configuration on one case.
struct Row {
  std::string set, name;  ///< the case (Case::set, Case::name)
  double offset = 0;
  Config config;
  std::size_t rays = 0;
  std::size_t hits = 0;
  bool closed = false;           ///< leaks measured (rays from inside a closed mesh)
  std::size_t leaks = 0;         ///< closed: rays that intersect() or occluded() let through
  std::size_t false_hits = 0;    ///< hits outside the reported triangle beyond the tolerance
  std::size_t false_misses = 0;  ///< clear reference hits missed (or passed by a farther hit)
  std::size_t nan = 0;           ///< hits with a NaN t, u or v
  ErrorStats t_error;            ///< relative t error against the double reference
  double seconds = 0;            ///< closest-hit pass: thread CPU time, best of the repetitions
  double mrays() const { return seconds > 0 ? double(rays) / seconds * 1e-6 : 0.0; }
  double leak_rate() const { return rays ? double(leaks) / double(rays) : 0.0; }
};

/// What to run.
struct Plan {
  std::vector<TriangleTest> tests;
  std::vector<Isa> isas;
  std::vector<Mode> modes;
  std::vector<bool> robust = {true, false};
  int reps = 3;  ///< timed closest-hit passes per row, alternating robust/plain (the best counts)
  Tolerances tolerances;
};

/// Builds the reference of a case: Isa::scalar, watertight, robust, reference_double.
Options reference_options();

/// Runs every (case, test, ISA, robust, mode); `progress` gets the fraction done.
std::vector<Row> run(const std::vector<Case>& cases, const Plan& plan, const std::function<void(double)>& progress);

}  // namespace volley::accuracy
