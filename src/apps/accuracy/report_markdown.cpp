// perf/accuracy/report.md: the tables of the accuracy report.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>

#include "accuracy/report.h"

namespace volley::accuracy {
namespace {

std::string num(double x, const char* format = "%.3g") {
  if (std::isnan(x)) return "–";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, x);
  return buf;
}

std::string config_cells(const Config& c) {
  return std::string(to_string(c.test)) + " | " + std::string(to_string(c.isa)) + " | " + name(c.mode) + " | " +
         (c.robust ? "robust" : "plain");
}

/// The distinct cases (set, name, offset) in first-seen order.
struct CaseKey {
  std::string set, name;
  double offset;
  std::string title() const { return name + (set == "scene" ? "" : " @" + offset_text(offset)); }
  bool operator==(const CaseKey& o) const { return set == o.set && name == o.name && offset == o.offset; }
};

std::vector<CaseKey> case_keys(const std::vector<Row>& rows, const std::string& set) {
  std::vector<CaseKey> keys;
  for (const Row& r : rows) {
    const CaseKey k{r.set, r.name, r.offset};
    if (r.set == set && std::find(keys.begin(), keys.end(), k) == keys.end()) keys.push_back(k);
  }
  return keys;
}

const Row* find_row(const std::vector<Row>& rows, const Config& c, const CaseKey& k) {
  for (const Row& r : rows)
    if (r.set == k.set && r.name == k.name && r.offset == k.offset && r.config == c) return &r;
  return nullptr;
}

/// A table with one row per configuration and one column per case of `set`.
void per_case_table(std::ostream& out, const std::vector<Row>& rows, const std::vector<ConfigSummary>& configs,
                    const std::string& set, const std::function<std::string(const Row&)>& cell) {
  const std::vector<CaseKey> keys = case_keys(rows, set);
  out << "| test | ISA | mode | traversal |";
  for (const CaseKey& k : keys) out << " " << k.title() << " |";
  out << "\n|---|---|---|---|";
  for (std::size_t i = 0; i < keys.size(); ++i) out << "---:|";
  out << "\n";
  for (const ConfigSummary& s : configs) {
    out << "| " << config_cells(s.config) << " |";
    for (const CaseKey& k : keys) {
      const Row* r = find_row(rows, s.config, k);
      out << " " << (r ? cell(*r) : "") << " |";
    }
    out << "\n";
  }
  out << "\n";
}

void targets_section(std::ostream& out, const std::vector<ConfigSummary>& configs) {
  std::size_t wt_leaks = 0, wt_rays = 0, nan = 0;
  for (const ConfigSummary& s : configs) {
    if (s.config.test == TriangleTest::watertight && s.config.robust) wt_leaks += s.leaks, wt_rays += s.closed_rays;
    nan += s.nan;
  }
  out << "## Targets (issue 5)\n\n";
  out << "| target | measured | met |\n|---|---|---|\n";
  out << "| watertight + robust: 0 leaks (every ISA, mode, offset) | " << wt_leaks << " leaks in " << wt_rays
      << " rays | " << (wt_leaks == 0 && wt_rays > 0 ? "yes" : "**no**") << " |\n";
  for (TriangleTest test : {TriangleTest::plane, TriangleTest::moller, TriangleTest::watertight}) {
    double worst = -1;
    std::string where;
    for (const ConfigSummary& s : configs)
      if (s.config.test == test && s.worst_t_median > worst) worst = s.worst_t_median, where = label(s.config);
    if (worst < 0) continue;
    out << "| " << to_string(test) << ": t relative error median <= 1e-7 in every case | worst " << num(worst) << " ("
        << where << ") | " << (worst <= 1e-7 ? "yes" : "**no**") << " |\n";
  }
  out << "| no NaN in any output | " << nan << " hits with a NaN t, u or v | " << (nan == 0 ? "yes" : "**no**")
      << " |\n\n";
  out << "The case behind a worst median is in the per-case t error tables below. >= 10 million rays per ISA: "
         "[long.md](long.md) (`volley accuracy --long`).\n\n";
}

void summary_section(std::ostream& out, const std::vector<ConfigSummary>& configs) {
  const std::vector<std::size_t> front = pareto_front(configs);
  out << "## Summary per configuration\n\n"
      << "Leaks: rays from inside a closed mesh aimed exactly at a shared vertex, edge midpoint or quad diagonal "
      << "that `intersect` or `occluded` lets through (all offsets). t error: relative, against the double-precision "
      << "reference on the reported triangle; the worst median, worst p99.9 and max over the cases. "
      << "P = on the Pareto front of the plot (ns/ray against leak rate + worst p99.9).\n\n";
  out << "| test | ISA | mode | traversal | ns/ray | leaks / rays | t err median | t err p99.9 | t err max | false "
         "hits | "
         "false misses | NaN | P |\n|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|:-:|\n";
  for (std::size_t i = 0; i < configs.size(); ++i) {
    const ConfigSummary& s = configs[i];
    const bool on_front = std::find(front.begin(), front.end(), i) != front.end();
    out << "| " << config_cells(s.config) << " | " << num(s.ns_per_ray(), "%.1f") << " | " << s.leaks << " / "
        << s.closed_rays << " | " << num(s.worst_t_median) << " | " << num(s.worst_t_p999) << " | " << num(s.t_max)
        << " | " << s.false_hits << " | " << s.false_misses << " | " << s.nan << " | " << (on_front ? "P" : "")
        << " |\n";
  }
  out << "\n";
}

void robust_section(std::ostream& out, const std::vector<ConfigSummary>& configs) {
  out << "## Robust traversal: its cost and what it buys\n\n"
      << "ns/ray of the plain and the robust slab test, same test, ISA and mode; leaks over all closed cases.\n\n"
      << "| test | ISA | mode | plain ns/ray | robust ns/ray | cost | plain leaks | robust leaks |\n"
      << "|---|---|---|---:|---:|---:|---:|---:|\n";
  for (const ConfigSummary& s : configs) {
    if (!s.config.robust) continue;
    for (const ConfigSummary& p : configs)
      if (!p.config.robust && p.config.test == s.config.test && p.config.isa == s.config.isa &&
          p.config.mode == s.config.mode) {
        const double cost = p.ns_per_ray() > 0 ? (s.ns_per_ray() / p.ns_per_ray() - 1.0) * 100.0 : NAN;
        out << "| " << to_string(s.config.test) << " | " << to_string(s.config.isa) << " | " << name(s.config.mode)
            << " | " << num(p.ns_per_ray(), "%.1f") << " | " << num(s.ns_per_ray(), "%.1f") << " | "
            << num(cost, "%+.1f") << "% | " << p.leaks << " | " << s.leaks << " |\n";
      }
  }
  out << "\n";
}

void images_section(std::ostream& out, const std::vector<ImageRow>& images) {
  if (images.empty()) return;
  out << "## Image error\n\n"
      << "Each scene rendered at 1 spp on one thread with every test × ISA (robust traversal) and compared with the "
      << "reference render (scalar, watertight, double precision). RMSE over the sRGB-encoded channels in [0, 1] "
      << "(what the PNG shows); PSNR = 20 log10(1 / RMSE).\n\n"
      << "| scene | size | test | ISA | render s (wall) | RMSE | PSNR dB | NaN pixels "
         "|\n|---|---|---|---|---:|---:|---:|---:|\n";
  for (const ImageRow& r : images)
    out << "| " << r.scene << " | " << r.width << "×" << r.height << " | "
        << (r.reference ? "reference" : std::string(to_string(r.test))) << " | " << to_string(r.isa) << " | "
        << num(r.seconds, "%.3f") << " | " << num(r.rmse) << " | " << num(r.psnr, "%.1f") << " | " << r.nan_pixels
        << " |\n";
  out << "\n";
}

void queries_section(std::ostream& out, const std::vector<QueryRow>& queries) {
  if (queries.empty()) return;
  out << "## Queries beyond the first hit\n\n"
         "Crossing parity: rays from inside closed meshes (cube, icospheres) aimed exactly at vertices, edge "
         "midpoints and diagonals, and in random directions, at offsets 0, 1e3, 1e5 and 1e6, unbounded: an even "
         "count_intersections is a wrong parity. Box: axis-aligned rays from inside a box mesh through its grid's "
         "vertices and edges "
         "(one crossing each). contains: points farther than 1e-6 of the size from the surface against the box "
         "and a double winding number. Distance error: max |d - d_ref| / (eps (d_ref + size)) against a double "
         "brute force, eps = 2^-24. One thread (docs/crossings.md).\n\n"
         "| ISA | wrong parities / rays | box rays wrong / rays | contains wrong / points | distance error (eps) | "
         "ns per count | ns per distance |\n|---|---|---|---|---|---|---|\n";
  for (const QueryRow& q : queries)
    out << "| " << to_string(q.isa) << " | " << q.parity_errors << " / " << q.parity_rays << " | " << q.box_errors
        << " / " << q.box_rays << " | " << q.contains_errors << " / " << q.contains_points << " | "
        << num(q.distance_error_max, "%.2f") << " | " << num(q.count_ns, "%.0f") << " | " << num(q.distance_ns, "%.0f")
        << " |\n";
  out << "\n";
}

void definitions_section(std::ostream& out, const Tolerances& t) {
  out << "## Definitions and tolerances\n\n"
      << "- Reference: the scalar oracle with `Options::reference_double` (watertight test in double precision, "
         "robust traversal) gives the reference closest hit of every ray; a Möller–Trumbore test in double on the "
         "float vertices gives t and barycentrics of any (ray, triangle).\n"
      << "- t error: |t − t_ref| / |t_ref| with t_ref in double on the triangle the configuration reported; hits with "
         "|t_ref| < "
      << num(t.t_floor) << " left out.\n"
      << "- False hit: the reported triangle's double barycentrics are below −" << num(t.margin)
      << " (the ray passes outside it by more than the margin).\n"
      << "- False miss: the reference hit is clear (all barycentrics >= " << num(t.margin) << ", |t_ref| > "
      << num(t.t_floor)
      << ": an origin on a triangle is stress item 12, not a miss) and the configuration misses it, reports a hit "
         "farther by more than "
      << num(t.t_relative) << " relative, or `occluded` says no.\n"
      << "- Leak: a ray from inside a closed mesh that `intersect` misses or `occluded` lets through.\n"
      << "- NaN: a hit with a NaN t, u or v.\n\n";
}

}  // namespace

void write_markdown(const Report& report, const std::filesystem::path& file) {
  const std::vector<ConfigSummary> configs = summarize(report.rows);
  std::ostringstream out;
  out << "# Accuracy report: run time against error\n\n";
  out << "Written by `" << report.command << "` on " << utc_now() << ", " << cpu_model() << ", in "
      << num(report.seconds, "%.0f") << " s. Each configuration is a triangle test × ISA × query mode × BVH "
      << "traversal (robust = padded, NaN-safe slab test; plain = the unpadded one). Speed: CPU time of one thread, "
      << "closest hit only, best of the timed passes (robust and plain alternating), over " << speed_basis(report.rows)
      << ". Plot: [accuracy.png](accuracy.png); "
      << "every number: [accuracy.csv](accuracy.csv).\n\n";
  for (const std::string& n : report.notes) out << "- " << n << "\n";
  if (!report.notes.empty()) out << "\n";
  targets_section(out, configs);

  summary_section(out, configs);
  robust_section(out, configs);
  out << "## Leaks by closed mesh and offset\n\n"
      << "Leaked rays (intersect or occluded) of the rays in each case (rays: "
      << "cube8 = 12 origins × 1734 targets, icosphere3 = 8 origins × 2562 targets, fewer when an origin rounds onto "
      << "the surface). Targets stay exactly representable up to 1e6.\n\n";
  per_case_table(out, report.rows, configs, "closed", [](const Row& r) { return std::to_string(r.leaks); });

  out << "## t relative error by case: median (p99.9)\n\n"
      << "Closed meshes (t = 1 at the target) and 500 random triangles with random aimed rays, moved by each "
         "offset.\n\n";
  const auto t_cell = [](const Row& r) { return num(r.t_error.median) + " (" + num(r.t_error.p999) + ")"; };
  per_case_table(out, report.rows, configs, "closed", t_cell);
  per_case_table(out, report.rows, configs, "random", t_cell);

  if (!case_keys(report.rows, "scene").empty()) {
    out << "## Shared meshes: Mrays/s, t error median, false hits / false misses\n\n";
    per_case_table(out, report.rows, configs, "scene", [](const Row& r) {
      return num(r.mrays(), "%.2f") + ", " + num(r.t_error.median) + ", " + std::to_string(r.false_hits) + "/" +
             std::to_string(r.false_misses);
    });
  }

  images_section(out, report.images);
  queries_section(out, report.queries);
  definitions_section(out, report.tolerances);
  out << "## Reproduce\n\n```sh\n"
      << "cmake -S . -B build/release -DCMAKE_BUILD_TYPE=Release && cmake --build build/release --target volley_cli\n"
      << "build/release/volley accuracy                 # this report (perf/accuracy/)\n"
      << "build/release/volley accuracy --long          # long.md: >= 10 million aimed rays per ISA\n"
      << "build/release/volley accuracy --help\n```\n";
  std::ofstream f(file);
  if (!(f << out.str())) throw std::runtime_error(file.string() + ": cannot write the report");
}

}  // namespace volley::accuracy
