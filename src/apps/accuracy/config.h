// One configuration of the accuracy report (triangle test x ISA x query mode x robust
// traversal) and the tolerances its false hits and misses are judged with.
#pragma once
#include <string>

#include "accuracy/query_modes.h"
#include "volley/options.h"

namespace volley::accuracy {

struct Config {
  TriangleTest test = TriangleTest::watertight;
  Isa isa = Isa::scalar;
  Mode mode = Mode::single;
  bool robust = true;  ///< Options::robust: padded, NaN-safe slab test
  bool operator==(const Config&) const = default;
};

/// "watertight avx2 packet16 robust" (or "plain" for robust = false).
inline std::string label(const Config& c) {
  return std::string(to_string(c.test)) + " " + std::string(to_string(c.isa)) + " " + name(c.mode) + " " +
         (c.robust ? "robust" : "plain");
}

/// What counts as a false hit or a false miss against the double-precision reference.
/// Rays that graze an edge within the margin are ambiguous in float and are not counted.
struct Tolerances {
  /// Barycentric margin: a hit whose double-precision barycentrics on the reported triangle
  /// are below -margin is a false hit; a reference hit whose barycentrics are all >= margin
  /// is "clear", and missing it (or reporting a farther hit) is a false miss.
  double margin = 1e-4;
  /// A reported hit farther than the clear reference hit by more than this relative amount
  /// means the nearer surface was missed (a false miss).
  double t_relative = 1e-4;
  /// Hits with |t_reference| below this are left out of the relative t error and of the
  /// false misses (an origin on the triangle or its plane: relative error means nothing
  /// there, and hit-or-not at t = tmin = 0 is stress item 12's documented behaviour).
  double t_floor = 1e-3;
};

}  // namespace volley::accuracy
