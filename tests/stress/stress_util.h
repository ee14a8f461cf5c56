// Shared helpers of the numerical stress suite (docs/accuracy.md, stress catalogue): doctest
// wrappers around src/apps/accuracy/ (the mesh type, the ISA list, the query modes of the public
// API, the double-precision ray/triangle reference, shared with `volley accuracy`), the
// Coverage check of generators, and the VOLLEY_STRESS_LONG switch.
#pragma once
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "accuracy/mesh.h"
#include "accuracy/query_modes.h"
#include "accuracy/reference.h"
#include "core/triangle_moller.h"
#include "core/triangle_watertight.h"
#include "volley/accel.h"
#include "volley/packet.h"

namespace stress {

using namespace volley;
using namespace volley::accuracy;

inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
inline constexpr TriangleTest kTests[] = {TriangleTest::plane, TriangleTest::moller, TriangleTest::watertight};

/// True when VOLLEY_STRESS_LONG=1: cases run millions of rays instead of thousands.
inline bool long_mode() {
  const char* v = std::getenv("VOLLEY_STRESS_LONG");
  return v != nullptr && std::string(v) == "1";
}

/// The scalar oracle and every SIMD ISA this CPU runs (a MESSAGE names the missing ones once).
inline const std::vector<Isa>& isas() {
  static const std::vector<Isa> list = [] {
    for (Isa isa : volley::accuracy::missing_isas())
      MESSAGE("stress: this CPU lacks " << std::string(volley::to_string(isa)) << ", not tested");
    return volley::accuracy::available_isas();
  }();
  return list;
}

/// Item 13 compares hit/miss across the ISAs of one formulation group: plane computes the
/// same everywhere (group 0), moller and watertight fuse on AVX2/AVX-512 (group 1) but not
/// in the scalar oracle and SSE4.2 (group 0), and the two formulations may differ on hit/miss
/// for ill-conditioned rays (grazing, rays through shared edges; docs/accuracy.md, stress item 13).
inline int agreement_group(TriangleTest test, Isa isa) {
  if (test == TriangleTest::moller) return volley::core::moller_fused_for(isa) ? 1 : 0;
  if (test == TriangleTest::watertight) return volley::core::watertight_fused_for(isa) ? 1 : 0;
  return 0;
}
inline constexpr int kAgreementGroups = 2;

/// Whose answers the ISAs of `group` are compared with (for messages).
inline std::string group_name(int group) { return group == 0 ? "the scalar oracle" : "the first fused ISA"; }

inline std::string name(Isa isa) { return std::string(volley::to_string(isa)); }
inline std::string name(TriangleTest t) { return std::string(volley::to_string(t)); }
using volley::accuracy::name;

/// Traces `rays` through `accel` in `mode` (closest hit and occlusion); fails the test when
/// an occlusion mask sets an inactive lane.
inline Answers trace(const Accel& accel, const std::vector<Ray>& rays, Mode mode) {
  Answers a = volley::accuracy::trace(accel, rays, mode);
  if (a.inactive_lane_reports != 0) FAIL("occlusion mask sets an inactive lane");
  return a;
}

/// Observed signs and decades of a generated quantity (stress item 14: generators check
/// that they cover what they claim to).
struct Coverage {
  bool negative = false, positive = false, neg_zero = false, pos_zero = false;
  int min_decade = 1000, max_decade = -1000;
  void add(double x) {
    if (x == 0.0) {
      (std::signbit(x) ? neg_zero : pos_zero) = true;
      return;
    }
    (x < 0 ? negative : positive) = true;
    if (std::isfinite(x)) {
      const int d = static_cast<int>(std::floor(std::log10(std::fabs(x))));
      min_decade = std::min(min_decade, d);
      max_decade = std::max(max_decade, d);
    }
  }
};

}  // namespace stress
