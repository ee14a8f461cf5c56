// Order statistics of an error sample: median, p99.9, max.
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

namespace volley::accuracy {

struct ErrorStats {
  std::size_t samples = 0;
  double median = NAN, p999 = NAN, max = NAN;  ///< NaN when there are no samples
};

/// Sorts `errors` in place and summarises them (p99.9 = the element at floor(0.999 n)).
inline ErrorStats summarize(std::vector<double>& errors) {
  ErrorStats s;
  s.samples = errors.size();
  if (errors.empty()) return s;
  std::sort(errors.begin(), errors.end());
  s.median = errors[errors.size() / 2];
  s.p999 = errors[std::min(errors.size() - 1, errors.size() * 999 / 1000)];
  s.max = errors.back();
  return s;
}

}  // namespace volley::accuracy
