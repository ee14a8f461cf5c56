#include "accuracy/runner.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "accuracy/cpu_clock.h"
#include "accuracy/reference.h"

namespace volley::accuracy {
namespace {

/// The double-precision test of ray i against triangle `prim` of the case's mesh.
RefHit reference_on(const Case& c, std::size_t i, std::uint32_t prim) {
  return reference(c.rays[i], c.mesh.corner(prim, 0), c.mesh.corner(prim, 1), c.mesh.corner(prim, 2));
}

/// t of each ray's clear reference hit (inside the triangle by the margin, not at the
/// origin: t_ref ~ 0 is stress item 12), NaN where there is none. The same for every
/// configuration, so computed once per case.
std::vector<double> clear_reference_t(const Case& c, const std::vector<Hit>& reference_hits, const Tolerances& tol) {
  std::vector<double> clear(c.rays.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < c.rays.size(); ++i) {
    if (!reference_hits[i].hit()) continue;
    const RefHit r = reference_on(c, i, reference_hits[i].prim);
    if (r.inside(tol.margin) && std::fabs(r.t) > tol.t_floor) clear[i] = r.t;
  }
  return clear;
}

/// Compares one configuration's answers with the reference answers of the case.
void judge(const Case& c, const std::vector<double>& clear_t, const Answers& a, const Tolerances& tol, Row& row) {
  std::vector<double> errors;
  errors.reserve(c.rays.size());
  for (std::size_t i = 0; i < c.rays.size(); ++i) {
    const Hit& h = a.hits[i];
    row.nan += std::isnan(h.t) || std::isnan(h.u) || std::isnan(h.v);
    if (c.closed) row.leaks += !h.hit() || !a.occluded[i];
    if (h.hit()) {
      ++row.hits;
      const RefHit r = reference_on(c, i, h.prim);
      if (!r.ok || r.margin() < -tol.margin) {
        ++row.false_hits;
      } else if (std::fabs(r.t) > tol.t_floor) {
        errors.push_back(std::fabs(double(h.t) - r.t) / std::fabs(r.t));
      }
    }
    if (!std::isnan(clear_t[i])) {
      const bool passed = !h.hit() || double(h.t) > clear_t[i] * (1.0 + tol.t_relative) + tol.t_floor * tol.t_relative;
      row.false_misses += passed || !a.occluded[i];
    }
  }
  row.t_error = summarize(errors);
}

}  // namespace

Options reference_options() {
  Options o;
  o.test = TriangleTest::watertight;
  o.isa = Isa::scalar;
  o.robust = true;
  o.reference_double = true;
  return o;
}

std::vector<Row> run(const std::vector<Case>& cases, const Plan& plan, const std::function<void(double)>& progress) {
  std::vector<Row> rows;
  const double units = double(cases.size() * plan.tests.size() * plan.isas.size());
  double done = 0;
  for (const Case& c : cases) {
    std::vector<Hit> reference_hits;
    intersect(c.mesh.accel(reference_options()), c.rays, Mode::single, reference_hits);
    const std::vector<double> clear_t = clear_reference_t(c, reference_hits, plan.tolerances);
    for (TriangleTest test : plan.tests)
      for (Isa isa : plan.isas) {
        // One Accel per traversal variant; their timed passes alternate (A B A B ...), so
        // that machine load shifts both alike.
        std::vector<Accel> accels;
        for (bool robust : plan.robust) {
          Options options;
          options.test = test, options.isa = isa, options.robust = robust;
          accels.push_back(c.mesh.accel(options));
        }
        for (Mode mode : plan.modes) {
          const std::size_t first = rows.size();
          for (std::size_t v = 0; v < accels.size(); ++v) {
            Row row;
            row.set = c.set, row.name = c.name, row.offset = c.offset, row.closed = c.closed;
            row.config = {test, isa, mode, plan.robust[v]};
            row.rays = c.rays.size();
            row.seconds = INFINITY;
            judge(c, clear_t, trace(accels[v], c.rays, mode), plan.tolerances, row);
            rows.push_back(std::move(row));
          }
          std::vector<Hit> timed;
          for (int r = 0; r < plan.reps; ++r)
            for (std::size_t v = 0; v < accels.size(); ++v) {
              const double start = thread_cpu_seconds();
              intersect(accels[v], c.rays, mode, timed);
              rows[first + v].seconds = std::min(rows[first + v].seconds, thread_cpu_seconds() - start);
            }
        }
        done += 1;
        if (progress) progress(done / units);
      }
  }
  return rows;
}

}  // namespace volley::accuracy
