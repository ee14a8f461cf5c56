#include <algorithm>
#include <cmath>
#include <ctime>
#include <fstream>

#include "accuracy/report.h"

namespace volley::accuracy {
std::string speed_basis(const std::vector<Row>& rows) {
  const bool scenes = std::any_of(rows.begin(), rows.end(), [](const Row& r) { return r.set == "scene"; });
  return scenes ? "the shared-mesh cases (primary and random rays)" : "all cases (no shared meshes)";
}

std::vector<ConfigSummary> summarize(const std::vector<Row>& rows) {
  const bool scenes = std::any_of(rows.begin(), rows.end(), [](const Row& r) { return r.set == "scene"; });
  std::vector<ConfigSummary> out;
  for (const Row& r : rows) {
    auto it = std::find_if(out.begin(), out.end(), [&](const ConfigSummary& s) { return s.config == r.config; });
    if (it == out.end()) {
      out.push_back({});
      out.back().config = r.config;
      it = out.end() - 1;
    }
    ConfigSummary& s = *it;
    s.rays += r.rays;
    if (r.closed) s.closed_rays += r.rays, s.leaks += r.leaks;
    s.false_hits += r.false_hits, s.false_misses += r.false_misses, s.nan += r.nan;
    if (r.t_error.samples > 0) {
      s.worst_t_median = std::max(s.worst_t_median, r.t_error.median);
      s.worst_t_p999 = std::max(s.worst_t_p999, r.t_error.p999);
      s.t_max = std::max(s.t_max, r.t_error.max);
    }
    if (!scenes || r.set == "scene") s.timed_rays += double(r.rays), s.timed_seconds += r.seconds;
  }
  return out;
}

std::vector<std::size_t> pareto_front(const std::vector<ConfigSummary>& s) {
  std::vector<std::size_t> front;
  for (std::size_t i = 0; i < s.size(); ++i) {
    bool dominated = false;
    for (std::size_t j = 0; j < s.size() && !dominated; ++j) {
      if (j == i) continue;
      const double xi = s[i].ns_per_ray(), yi = s[i].error_measure(), xj = s[j].ns_per_ray(), yj = s[j].error_measure();
      dominated = xj <= xi && yj <= yi && (xj < xi || yj < yi);
    }
    if (!dominated) front.push_back(i);
  }
  std::sort(front.begin(), front.end(),
            [&](std::size_t a, std::size_t b) { return s[a].ns_per_ray() < s[b].ns_per_ray(); });
  return front;
}

std::string offset_text(double offset) {
  if (offset == 0) return "0";
  const int e = int(std::lround(std::log10(offset)));
  return "1e" + std::to_string(e);
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char buf[64];
  std::strftime(buf, sizeof(buf), "%Y-%m-%d %H:%M UTC", std::gmtime(&t));
  return buf;
}

std::string cpu_model() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) return line.substr(colon + 2);
    }
  return "unknown CPU";
}

}  // namespace volley::accuracy
