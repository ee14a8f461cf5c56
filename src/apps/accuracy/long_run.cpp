#include "accuracy/long_run.h"

#include <cmath>

#include "accuracy/cases.h"
#include "accuracy/cpu_clock.h"

namespace volley::accuracy {

std::vector<LongRow> long_run(std::size_t rays_per_isa, const std::vector<Isa>& isas, const std::vector<Mode>& modes,
                              const std::function<void(double)>& progress) {
  // Rays of one origin set over all closed cases; repeat the origins until the total is
  // reached (5% spare: origins that round onto the surface far from 0 are dropped).
  std::size_t base = 0;
  for (const Case& c : closed_cases(1)) base += c.rays.size();
  const std::size_t repeat =
      std::max<std::size_t>(1, std::size_t(std::ceil(1.05 * double(rays_per_isa) / double(base))));
  std::vector<LongRow> rows;
  const std::size_t cases = closed_case_count();
  std::size_t done = 0;
  // One case at a time (a million rays or more each), so memory stays bounded.
  for (std::size_t k = 0; k < cases; ++k) {
    const Case c = closed_case(k, repeat);
    for (Isa isa : isas) {
      Options o;
      o.test = TriangleTest::watertight, o.isa = isa, o.robust = true;
      const Accel accel = c.mesh.accel(o);
      for (Mode mode : modes) {
        LongRow row{isa, mode, c.name, c.offset, c.rays.size()};
        const double start = thread_cpu_seconds();
        const Answers a = trace(accel, c.rays, mode);
        row.seconds = thread_cpu_seconds() - start;
        for (std::size_t i = 0; i < c.rays.size(); ++i) {
          const Hit& h = a.hits[i];
          row.leaks += !h.hit() || !a.occluded[i];
          row.nan += std::isnan(h.t) || std::isnan(h.u) || std::isnan(h.v);
        }
        rows.push_back(row);
      }
      ++done;
      if (progress) progress(double(done) / double(cases * isas.size()));
    }
  }
  return rows;
}

}  // namespace volley::accuracy
