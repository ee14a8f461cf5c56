// The accuracy report and its writers: perf/accuracy/report.md (tables), accuracy.csv (one
// line per row) and accuracy.png (run time against error, gnuplot); long.md for --long.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "accuracy/image_error.h"
#include "accuracy/long_run.h"
#include "accuracy/query_checks.h"
#include "accuracy/runner.h"
#include "accuracy/spawn_check.h"

namespace volley::accuracy {

struct Report {
  std::vector<Row> rows;
  std::vector<ImageRow> images;
  std::vector<QueryRow> queries;  ///< the queries beyond the first hit, per ISA
  std::vector<std::string> notes;  ///< what was skipped and why, missing ISAs
  std::string command;             ///< the command line that produced it
  double seconds = 0;              ///< wall time of the whole run
  Tolerances tolerances;
};

/// One configuration over all its cases.
struct ConfigSummary {
  Config config;
  std::size_t rays = 0, closed_rays = 0, leaks = 0, false_hits = 0, false_misses = 0, nan = 0;
  double worst_t_median = 0, worst_t_p999 = 0, t_max = 0;  ///< worst over the cases
  double timed_rays = 0, timed_seconds = 0;                ///< the cases its speed is measured on
  double ns_per_ray() const { return timed_rays > 0 ? timed_seconds / timed_rays * 1e9 : 0.0; }
  double leak_rate() const { return closed_rays ? double(leaks) / double(closed_rays) : 0.0; }
  /// The plot's error axis: leak rate + worst p99.9 t error (floored at 1e-12 for log scale).
  double error_measure() const { return std::max(1e-12, leak_rate() + worst_t_p999); }
};

/// Summaries in the order configurations first appear. Speed: over the shared-mesh cases
/// when there are any, else over all cases.
std::vector<ConfigSummary> summarize(const std::vector<Row>& rows);
/// Indices of the summaries on the Pareto front (no other is both faster and more
/// accurate), sorted by ns/ray.
std::vector<std::size_t> pareto_front(const std::vector<ConfigSummary>& s);
/// What speed is measured on (for captions).
std::string speed_basis(const std::vector<Row>& rows);

void write_markdown(const Report& report, const std::filesystem::path& file);
void write_csv(const Report& report, const std::filesystem::path& file);
/// Writes the PNG with gnuplot; false (and `message` says why) when gnuplot is missing or fails.
bool write_plot(const Report& report, const std::filesystem::path& file, std::string& message);

/// long.md: per ISA, mode, mesh and offset, rays, leaks, NaN and time; totals per ISA;
/// then the self-intersection check of spawned rays per scale and ISA.
void write_long_markdown(const std::vector<LongRow>& rows, std::size_t rays_per_isa,
                         const std::vector<SpawnRow>& spawns, const std::string& command, double seconds,
                         const std::filesystem::path& file);

/// "1e+06" -> "1e6", 0 -> "0": offsets as the report prints them.
std::string offset_text(double offset);
/// Current UTC date and time, "2026-11-22 17:30 UTC".
std::string utc_now();
/// The CPU model from /proc/cpuinfo ("unknown CPU" elsewhere).
std::string cpu_model();

}  // namespace volley::accuracy
