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
#include <optional>
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


/// Traces `rays` through `mesh` for every test × ISA × mode; calls check(test, isa, mode,
/// answers) and counts hit/miss disagreements with the single rays of the first ISA of the
/// same agreement group (item 13: the scalar oracle, or for fused moller the first of AVX2,
/// AVX-512). Disagreements between the moller groups are only reported. `excused`: a test
/// whose cross-ISA disagreements are only reported (the strict variant is the stress 13
/// case below), not checked.
template <class Check>
void for_each_config(const Mesh& mesh, const std::vector<Ray>& rays, const std::string& what, Check check,
                     std::optional<TriangleTest> excused = std::nullopt) {
  for (TriangleTest test : kTests) {
    std::vector<Hit> oracle[kAgreementGroups];
    for (Isa isa : isas()) {
      const Accel accel = mesh.accel(test, isa);
      const int group = agreement_group(test, isa);
      for (Mode mode : kModes) {
        const Answers a = trace(accel, rays, mode);
        if (oracle[group].empty()) oracle[group] = a.hits;
        std::size_t disagree = 0, disagree_unfused = 0, nan = 0, occ_mismatch = 0;
        for (std::size_t i = 0; i < rays.size(); ++i) {
          disagree += a.hits[i].hit() != oracle[group][i].hit();
          disagree_unfused += group != 0 && a.hits[i].hit() != oracle[0][i].hit();
          nan += std::isnan(a.hits[i].t) || std::isnan(a.hits[i].u) || std::isnan(a.hits[i].v);
          occ_mismatch += a.hits[i].hit() != bool(a.occluded[i]);
        }
        INFO(what, ": ", name(test), " ", name(isa), " ", name(mode));
        if (disagree_unfused != 0 && mode == Mode::single)
          MESSAGE(what, ": fused ", name(test), " ", name(isa), " hit/miss differs from the unfused scalar oracle in ",
                  disagree_unfused, " of ", rays.size(), " rays (allowed, docs/accuracy.md, stress item 13)");
        if (excused == test) {
          if (disagree != 0 && mode == Mode::single)
            MESSAGE(what, ": ", name(test), " ", name(isa), " hit/miss differs from ", group_name(group), " in ",
                    disagree, " of ", rays.size(), " rays (see the stress 13 case)");
        } else {
          CHECK(disagree == 0);
        }
        CHECK(nan == 0);
        CHECK(occ_mismatch == 0);
        check(test, isa, mode, a);
      }
    }
  }
}

inline std::size_t misses(const Answers& a) {
  std::size_t n = 0;
  for (const Hit& h : a.hits) n += !h.hit();
  return n;
}


}  // namespace stress
