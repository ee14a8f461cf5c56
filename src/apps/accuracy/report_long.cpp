// perf/accuracy/long.md: the long leak run (--long).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "accuracy/report.h"

namespace volley::accuracy {

void write_long_markdown(const std::vector<LongRow>& rows, std::size_t rays_per_isa,
                         const std::vector<SpawnRow>& spawns, const std::string& command, double seconds,
                         const std::filesystem::path& file) {
  std::ostringstream out;
  out << "# Long leak run: watertight test, robust traversal\n\n"
      << "Written by `" << command << "` on " << utc_now() << ", " << cpu_model() << ", in " << std::lround(seconds)
      << " s wall; seconds below are CPU time of the one tracing thread. Rays from inside the closed grid cube (n = 8) "
         "and the integer "
      << "icosphere (3 levels, radius 1000), aimed exactly at shared vertices, edge midpoints and quad diagonals, with "
      << "the mesh moved to 0, 1e3, 1e5 and 1e6 (targets stay exactly representable); requested >= " << rays_per_isa
      << " distinct rays per ISA, each traced in every mode listed (closest hit and occlusion). A leak: `intersect` "
      << "misses or `occluded` lets the ray through. Target: 0 leaks.\n\n";
  struct Total {
    std::size_t rays = 0, leaks = 0, nan = 0;
    double seconds = 0;
  };
  std::map<std::pair<int, int>, Total> totals;  // (isa, mode)
  for (const LongRow& r : rows) {
    Total& t = totals[{int(r.isa), int(r.mode)}];
    t.rays += r.rays, t.leaks += r.leaks, t.nan += r.nan, t.seconds += r.seconds;
  }
  out << "## Totals per ISA and mode\n\n| ISA | mode | rays | leaks | NaN | seconds | Mrays/s (hit + occluded) | 0 "
         "leaks |\n"
      << "|---|---|---:|---:|---:|---:|---:|:-:|\n";
  for (const auto& [key, t] : totals) {
    char rate[32];
    std::snprintf(rate, sizeof(rate), "%.2f", t.seconds > 0 ? double(t.rays) / t.seconds * 1e-6 : 0.0);
    out << "| " << to_string(Isa(key.first)) << " | " << name(Mode(key.second)) << " | " << t.rays << " | " << t.leaks
        << " | " << t.nan << " | " << std::lround(t.seconds * 10) / 10.0 << " | " << rate << " | "
        << (t.leaks == 0 && t.nan == 0 ? "yes" : "**no**") << " |\n";
  }
  out << "\n## Per mesh and offset\n\n| ISA | mode | mesh | offset | rays | leaks | NaN "
         "|\n|---|---|---|---:|---:|---:|---:|\n";
  for (const LongRow& r : rows)
    out << "| " << to_string(r.isa) << " | " << name(r.mode) << " | " << r.mesh << " | " << offset_text(r.offset)
        << " | " << r.rays << " | " << r.leaks << " | " << r.nan << " |\n";
  out << "\n## Self-intersection of spawned rays\n\n"
      << "A ray hits a tilted triangle of size ~scale placed ~scale from the origin; a secondary ray leaves the hit "
         "point in a random direction (either side) from the renderer's offset origin (render/spawn.h: the hit "
         "point's error bound along the normal, rounded away); a re-hit is an occlusion query that finds the same "
         "triangle. Watertight test, robust traversal. Target: 0 re-hits in 1e6 spawns per scale.\n\n"
      << "| scale | ISA | spawned | re-hits | 0 re-hits |\n|---:|---|---:|---:|:-:|\n";
  for (const SpawnRow& r : spawns)
    out << "| " << offset_text(r.scale) << " | " << to_string(r.isa) << " | " << r.spawned << " | " << r.rehits << " | "
        << (r.rehits == 0 ? "yes" : "**no**") << " |\n";
  std::ofstream f(file);
  if (!(f << out.str())) throw std::runtime_error(file.string() + ": cannot write " + file.filename().string());
}

}  // namespace volley::accuracy
