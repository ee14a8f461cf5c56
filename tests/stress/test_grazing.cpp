// Numerical stress suite, items 6 and 13 (docs/accuracy.md, stress catalogue): grazing rays
// (0.1 .. 1e-4 degrees) on skinny triangles (aspect 1e3 .. 1e5) against a double reference,
// every ISA this CPU has plus the scalar oracle, every query mode: hit/miss agree where the
// answer is well conditioned, t bounded, and the SIMD Moller-Trumbore Accels give the
// oracle's hit/miss. The rest of the suite is in test_geometry.cpp.
#include <doctest/doctest.h>

#include <xmmintrin.h>

#include <algorithm>
#include <optional>
#include <random>
#include <sstream>

#include "accuracy/cases.h"
#include "accuracy/error_stats.h"
#include "simd/triangle/watertight_stats.h"
#include "stress_util.h"

using namespace stress;

namespace {

/// One grazing configuration: a skinny triangle (length 1, width 1/aspect, random
/// orientation, float vertices) and rays meeting its plane at `degrees` from distance 0.5,
/// aimed at targets inside it (a third) and outside (barycentrics ±10^[-2, 3]).
struct Grazing {
  double aspect = 0, degrees = 0, sin_g = 0;
  Mesh mesh;
  std::vector<Ray> rays;
};

std::vector<Grazing> grazing_cases() {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double kPi = 3.14159265358979323846;
  const int per = long_mode() ? 20000 : 300;
  std::vector<Grazing> out;
  for (double aspect : {1e3, 1e4, 1e5}) {
    const double th = 2 * kPi * u01(rng), ph = kPi * u01(rng);
    const std::array<double, 3> ax{std::cos(th) * std::sin(ph), std::sin(th) * std::sin(ph), std::cos(ph)};
    std::array<double, 3> by{-ax[1], ax[0], 0.0};
    const double bl = std::hypot(by[0], by[1]);
    for (double& c : by) c /= bl;
    const std::array<double, 3> nz{ax[1] * by[2] - ax[2] * by[1], ax[2] * by[0] - ax[0] * by[2], ax[0] * by[1] - ax[1] * by[0]};
    Mesh mesh;
    const auto at = [&](double a, double b) {
      return mesh.vertex(0.3 + a * ax[0] + b * by[0], -0.2 + a * ax[1] + b * by[1], 0.1 + a * ax[2] + b * by[2]);
    };
    mesh.triangle(at(0, 0), at(1, 0), at(0.5, 1.0 / aspect));
    const auto p0 = mesh.position(0), p1 = mesh.position(1), p2 = mesh.position(2);
    for (double degrees : {1.0, 0.1, 1e-2, 1e-3, 1e-4}) {  // 1 degree: a well-conditioned control
      Grazing g;
      g.aspect = aspect, g.degrees = degrees, g.mesh = mesh;
      g.sin_g = std::sin(degrees * kPi / 180.0);
      const double cos_g = std::cos(degrees * kPi / 180.0);
      for (int k = 0; k < per; ++k) {
        double b1, b2;
        if (k % 3 == 0) {  // inside
          b1 = u01(rng), b2 = u01(rng);
          if (b1 + b2 > 1) b1 = 1 - b1, b2 = 1 - b2;
        } else {  // outside, at distances over five decades
          b1 = (rng() % 2 ? 1 : -1) * std::pow(10.0, -2 + 5 * u01(rng));
          b2 = (rng() % 2 ? 1 : -1) * std::pow(10.0, -2 + 5 * u01(rng));
        }
        const double w = 1.0 - b1 - b2;
        std::array<double, 3> tp{};
        for (int c = 0; c < 3; ++c) tp[c] = w * p0[c] + b1 * p1[c] + b2 * p2[c];
        const double hd = 2 * kPi * u01(rng), side = (k % 2) ? 1.0 : -1.0;
        float d[3], o[3];
        for (int c = 0; c < 3; ++c) {
          const double dc = cos_g * (std::cos(hd) * ax[c] + std::sin(hd) * by[c]) - side * g.sin_g * nz[c];
          d[c] = to_float(dc);
          o[c] = to_float(tp[c] - 0.5 * dc);
        }
        g.rays.push_back(make_ray(o, d));
      }
      out.push_back(std::move(g));
    }
  }
  return out;
}


/// Stress 6 on every configuration of grazing_cases(). With `moller_strict` false, the SIMD
/// Moller-Trumbore kernels' disagreements (with the oracle and with the reference) are only
/// reported: see the skipped case below.
void check_grazing(bool moller_strict) {
  // Condition: rounding inside any of the tests perturbs the inputs by ~eps relative, which
  // moves the ray's crossing with the plane by up to ~eps |o - p| / sin(angle) along the
  // plane, i.e. by up to cond = eps aspect / sin(angle) in barycentrics across the skinny
  // side (|o - p| ~ 1 here), more the farther the crossing lies from the triangle, and t by
  // a similar amount (measured: t errors stay below 0.05 cond). Hit/miss must agree with the
  // double reference where its barycentrics are farther than margin x cond x (1 + |u| + |v|)
  // from an edge and its t is farther than that from 0 (margin 16, and 64 for the plane
  // test, whose rounding is larger: both set with VOLLEY_STRESS_LONG=1, 20000 rays per
  // configuration); a t more than 64 cond from the reference's (or negative, or not finite)
  // is absurd.
  constexpr double kEps = 0x1p-24;
  const auto margin_of = [](TriangleTest test) { return test == TriangleTest::plane ? 64.0 : 16.0; };
  Coverage angle_cov, aspect_cov, bary_cov;
  std::size_t total_in = 0, total_out = 0;
  for (const Grazing& g : grazing_cases()) {
    angle_cov.add(g.degrees), aspect_cov.add(g.aspect);
    const auto p0 = g.mesh.position(0), p1 = g.mesh.position(1), p2 = g.mesh.position(2);
    const double cond = kEps * g.aspect / g.sin_g;
    std::ostringstream what;
    what << "grazing " << g.degrees << " deg, aspect " << g.aspect;
    std::size_t clear_in = 0, clear_out = 0;
    for (const Ray& r : g.rays) {
      const RefHit h = reference(r, p0, p1, p2);
      REQUIRE(h.ok);
      bary_cov.add(h.u);
      const double scale = 1 + std::fabs(h.u) + std::fabs(h.v);
      clear_in += h.inside(16 * cond * scale) && h.t > 16 * cond * scale;
      clear_out += !h.inside(-16 * cond * scale) || h.t < -16 * cond * scale;
    }
    total_in += clear_in, total_out += clear_out;
    const auto check = [&](TriangleTest test, Isa isa, Mode mode, const Answers& a) {
      std::size_t wrong = 0, absurd = 0;
      double worst = 0;
      for (std::size_t i = 0; i < g.rays.size(); ++i) {
        const RefHit r = reference(g.rays[i], p0, p1, p2);
        const double m = margin_of(test) * (1 + std::fabs(r.u) + std::fabs(r.v));
        const bool in = r.inside(m * cond) && r.t > m * cond, out = !r.inside(-m * cond) || r.t < -m * cond;
        wrong += (in && !a.hits[i].hit()) || (out && a.hits[i].hit());
        if (a.hits[i].hit()) {
          const double t = a.hits[i].t, err = std::fabs(t - r.t) / r.t;
          worst = std::max(worst, err / cond);
          absurd += !(t >= 0 && std::isfinite(t) && err <= 64 * cond);
        }
      }
      INFO(what.str(), " ", name(test), " ", name(isa), " ", name(mode));
      if (moller_strict || test != TriangleTest::moller || isa == Isa::scalar) {
        CHECK(wrong == 0);
        CHECK(absurd == 0);
      } else if ((wrong != 0 || absurd != 0) && mode == Mode::single) {
        MESSAGE(what.str(), " moller ", name(isa), ": ", wrong, " well-conditioned rays disagree with the double "
                "reference, ", absurd, " absurd t (see the skipped stress 13 case)");
      }
      if (isa == Isa::scalar && mode == Mode::single)
        MESSAGE(what.str(), " ", name(test), ": ", clear_in, " clearly inside, ", clear_out, " clearly outside of ",
                g.rays.size(), "; ", g.rays.size() - misses(a), " hits, max t error ", worst,
                " x eps aspect / sin(angle)");
    };
    if (moller_strict)
      for_each_config(g.mesh, g.rays, what.str(), check);
    else
      for_each_config(g.mesh, g.rays, what.str(), check, TriangleTest::moller);
  }
  CHECK(total_in > 0);
  CHECK(total_out > 0);
  CHECK(angle_cov.min_decade == -4);
  CHECK(angle_cov.max_decade == 0);
  CHECK(aspect_cov.min_decade == 3);
  CHECK(aspect_cov.max_decade == 5);
  CHECK((bary_cov.negative && bary_cov.positive && bary_cov.min_decade <= -2 && bary_cov.max_decade >= 2));
}

}  // namespace

TEST_CASE("stress 6/13/14: grazing rays on skinny triangles agree with a double reference") {
  check_grazing(false);
}

// Found by this suite: on grazing rays the SIMD Moller-Trumbore Accels (SSE4.2, AVX2 and
// AVX-512 alike) gave a different hit/miss than the scalar one for 5-29 of 300 rays per
// configuration. Not the kernels (they match the oracle bit for bit on these rays): the
// Accels culled differently. The scalar one tests the binary BVH's root box before the
// triangle, while the wide BVH of this one-triangle mesh was a lone leaf tested with no box,
// and Moller's ill-conditioned hits can lie far outside the triangle's box (t = 76 for a
// crossing at t = 0.5 at 1e-3 degrees). A lone leaf now sits in a one-child node whose box
// is tested (src/accel/wide/wide_build.cpp), so both Accels cull alike.
TEST_CASE("stress 13: SIMD Moller-Trumbore gives the oracle's hit/miss on grazing rays") {
  check_grazing(true);
}
