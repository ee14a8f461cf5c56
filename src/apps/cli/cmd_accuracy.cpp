// volley accuracy: the accuracy report (run time against error) of every triangle test x
// ISA x query mode x traversal, written to perf/accuracy/ (docs/accuracy.md, issue 5).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "accuracy/cases.h"
#include "accuracy/image_error.h"
#include "accuracy/long_run.h"
#include "accuracy/report.h"
#include "accuracy/runner.h"
#include "accuracy/spawn_check.h"
#include "cli/commands.h"
#include "cli/common.h"
#include "cli/progress.h"
#include "simd/isa/dispatch.h"

namespace volley::cli {
namespace {

namespace acc = volley::accuracy;
namespace fs = std::filesystem;

struct AccuracyArgs {
  std::string scenes;
  std::string output = "perf/accuracy";
  std::vector<std::string> tests = {"plane", "moller", "watertight"};
  std::vector<std::string> isas;  ///< empty: scalar + every SIMD ISA of the CPU
  std::vector<std::string> modes = {"single", "packet16", "stream"};
  bool long_mode = false;
  double long_rays = 10e6;
  bool quick = false;
  bool no_images = false;
  int reps = 3;
};

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const std::string& n : names) s += (s.empty() ? "" : ",") + n;
  return s;
}

/// The command as the report quotes it: the options that differ from the defaults.
std::string command_line(const AccuracyArgs& a) {
  const AccuracyArgs defaults;
  std::string s = "volley accuracy";
  if (a.long_mode) s += " --long";
  if (a.long_mode && a.long_rays != defaults.long_rays)
    s += " --long-rays " + std::to_string(std::llround(a.long_rays));
  if (a.quick) s += " --quick";
  if (a.tests != defaults.tests) s += " --test " + joined(a.tests);
  if (!a.isas.empty()) s += " --isa " + joined(a.isas);
  if (a.modes != defaults.modes) s += " --modes " + joined(a.modes);
  if (a.reps != defaults.reps) s += " --reps " + std::to_string(a.reps);
  if (a.no_images) s += " --no-images";
  if (!a.scenes.empty()) s += " --scenes " + a.scenes;
  if (a.output != defaults.output) s += " -o " + a.output;
  return s;
}

std::vector<Isa> chosen_isas(const AccuracyArgs& a) {
  if (a.isas.empty()) return acc::available_isas();
  std::vector<std::string> has;
  for (Isa i : acc::available_isas()) has.emplace_back(to_string(i));
  std::vector<Isa> out;
  for (const std::string& n : a.isas) {
    const Isa isa = *parse_isa(n);  // CLI11 checked the name
    if (isa != Isa::scalar && !simd::cpu_has(isa))
      throw std::runtime_error("--isa " + n + ": this CPU cannot run it (it has " + joined(has) + ")");
    out.push_back(isa);
  }
  return out;
}

/// The project folder (for scenes/cornell.json and bench/scenes/bunny.json): the working
/// directory when it holds scenes/, else two levels above the executable (build/<dir>/volley).
fs::path project_root() {
  if (fs::exists(fs::path("scenes") / "cornell.json")) return fs::current_path();
  if (const auto root = project_dir_of_executable(); root && fs::exists(*root / "scenes" / "cornell.json"))
    return *root;
  return fs::current_path();
}

/// The cases: closed meshes and random triangles at every offset, then the shared meshes
/// (skipped with a note when missing).
std::vector<acc::Case> gather_cases(const AccuracyArgs& a, const fs::path& scenes, acc::Report& report) {
  std::vector<acc::Case> cases = acc::closed_cases(1);
  std::vector<acc::Case> random = acc::random_triangle_cases(a.quick ? 2000 : 20000);
  std::vector<acc::Case> shared;
  if (fs::is_directory(scenes)) {
    std::vector<std::string> missing;
    // --quick: the first mesh found only (the dragon alone takes seconds to load).
    shared = acc::scene_cases(scenes, a.quick ? 32 : 256, missing, a.quick ? 1 : std::size(acc::kSceneMeshes));
    for (const std::string& m : missing) report.notes.push_back("Shared mesh " + m + " not found: skipped.");
  } else {
    report.notes.push_back("Shared scenes folder " + scenes.string() + " not found: shared-mesh cases skipped.");
    std::fprintf(stderr, "volley accuracy: %s not found, shared-mesh cases skipped\n", scenes.string().c_str());
  }
  if (a.quick) {  // one closed mesh at 0, the other at 1e6, one random set, one shared mesh
    cases = {std::move(cases.front()), std::move(cases.back())};
    random.resize(1);
  }
  for (auto* set : {&random, &shared})
    for (acc::Case& c : *set) cases.push_back(std::move(c));
  return cases;
}

/// Image error of scenes/cornell.json and, when the shared bunny is there,
/// bench/scenes/bunny.json; `progress` gets the fraction of renders done.
void add_image_rows(const AccuracyArgs& a, const acc::Plan& plan, const fs::path& scenes, acc::Report& report,
                    const std::function<void(double)>& progress) {
  const fs::path root = project_root();
  std::vector<fs::path> files = {root / "scenes" / "cornell.json"};
  if (fs::exists(scenes / "stanford-bunny.obj"))
    files.push_back(root / "bench" / "scenes" / "bunny.json");
  else
    report.notes.push_back("stanford-bunny.obj not found: the shared-mesh image-error scene is skipped.");
  const double renders = double(files.size() * (1 + plan.tests.size() * plan.isas.size()));
  double done = 0;
  for (const fs::path& file : files) {
    if (!fs::exists(file)) {
      report.notes.push_back(file.string() + " not found: its image error is skipped.");
      continue;
    }
    const int size = a.quick ? 32 : 256;
    for (acc::ImageRow& r :
         acc::image_error(file, scenes, size, plan.tests, plan.isas, [&] { progress(++done / renders); }))
      report.images.push_back(std::move(r));
  }
}

int run_long(const AccuracyArgs& a, const std::vector<Isa>& isas, const std::vector<acc::Mode>& modes) {
  const auto start = std::chrono::steady_clock::now();
  ProgressBar bar("accuracy --long");
  const std::size_t per_isa = std::size_t(a.long_rays);
  const std::vector<acc::LongRow> rows = acc::long_run(per_isa, isas, modes, [&bar](double f) { bar.update(0.9 * f); });
  // Self-intersection: 1e6 spawned rays per scale and ISA (a tenth of --long-rays).
  std::vector<acc::SpawnRow> spawns;
  const std::size_t per_scale = std::max<std::size_t>(1000, per_isa / 10);
  for (std::size_t i = 0; i < isas.size(); ++i)
    for (std::size_t k = 0; k < acc::kSpawnScales.size(); ++k) {
      spawns.push_back(acc::spawn_check(acc::kSpawnScales[k], per_scale, isas[i]));
      bar.update(0.9 +
                 0.1 * double(i * acc::kSpawnScales.size() + k + 1) / double(isas.size() * acc::kSpawnScales.size()));
    }
  bar.finish();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const fs::path file = fs::path(a.output) / "long.md";
  acc::write_long_markdown(rows, per_isa, spawns, command_line(a), seconds, file);
  std::size_t rays = 0, leaks = 0, nan = 0, rehits = 0;
  for (const acc::LongRow& r : rows) rays += r.rays, leaks += r.leaks, nan += r.nan;
  for (const acc::SpawnRow& r : spawns) rehits += r.rehits;
  std::printf(
      "accuracy --long: %zu rays traced (%zu ISAs x %zu modes), %zu leaks, %zu NaN; %zu spawned rays per "
      "scale and ISA, %zu re-hits; in %.0f s -> %s\n",
      rays, isas.size(), modes.size(), leaks, nan, per_scale, rehits, seconds, file.string().c_str());
  return 0;
}

/// The configurations to measure, from the options.
acc::Plan make_plan(const AccuracyArgs& a) {
  acc::Plan plan;
  for (const std::string& t : a.tests) plan.tests.push_back(*parse_triangle_test(t));
  plan.isas = chosen_isas(a);
  for (const std::string& m : a.modes) {
    acc::Mode mode{};
    acc::parse_mode(m, mode);  // CLI11 checked the name
    plan.modes.push_back(mode);
  }
  plan.reps = a.reps;

  return plan;
}

/// The report's measurements: every case, the image error and the queries' checks.
acc::Report measure(const AccuracyArgs& a, const acc::Plan& plan, std::size_t& case_count) {
  const auto start = std::chrono::steady_clock::now();
  acc::Report report;
  report.command = command_line(a);
  report.tolerances = plan.tolerances;
  for (Isa isa : acc::missing_isas())
    report.notes.push_back("This CPU lacks " + std::string(to_string(isa)) + ": not measured.");

  const fs::path scenes = shared_scenes_dir(a.scenes);
  const std::vector<acc::Case> cases = gather_cases(a, scenes, report);
  case_count = cases.size();
  ProgressBar bar("accuracy");
  const double image_share = a.no_images ? 0.0 : 0.2;
  report.rows = acc::run(cases, plan, [&](double f) { bar.update(f * (1.0 - image_share)); });

  if (!a.no_images)
    add_image_rows(a, plan, scenes, report, [&](double f) { bar.update(1.0 - image_share + image_share * f); });
  report.queries = acc::run_query_checks(plan.isas);
  bar.finish();
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  return report;
}

/// Writes report.md, accuracy.csv and accuracy.png and prints the summary line.
int write_report(const AccuracyArgs& a, const acc::Report& report, std::size_t case_count) {
  const fs::path out(a.output);
  acc::write_markdown(report, out / "report.md");
  acc::write_csv(report, out / "accuracy.csv");
  std::string plot_message;
  const bool plotted = acc::write_plot(report, out / "accuracy.png", plot_message);
  if (!plotted) std::fprintf(stderr, "volley accuracy: %s\n", plot_message.c_str());

  std::size_t rays = 0, wt_leaks = 0, nan = 0;
  double worst_median = 0;
  const std::vector<acc::ConfigSummary> summaries = acc::summarize(report.rows);
  for (const acc::ConfigSummary& s : summaries) {
    rays += s.rays, nan += s.nan;
    if (s.config.test == TriangleTest::watertight && s.config.robust) wt_leaks += s.leaks;
    worst_median = std::max(worst_median, s.worst_t_median);
  }
  std::size_t parity = 0, contains = 0;
  for (const acc::QueryRow& q : report.queries) parity += q.parity_errors + q.box_errors, contains += q.contains_errors;
  std::printf(
      "accuracy: %zu configurations x %zu cases, %zu rays, watertight+robust leaks %zu, worst t error "
      "median %.3g, NaN %zu, %zu renders, crossing parity errors %zu, contains errors %zu, in %.0f s -> "
      "%s/{report.md,accuracy.csv%s}\n",
      summaries.size(), case_count, rays, wt_leaks, worst_median, nan, report.images.size(), parity, contains,
      report.seconds, out.string().c_str(), plotted ? ",accuracy.png" : "");
  return 0;
}

/// volley accuracy's run.
int run_accuracy(const AccuracyArgs& a) {
  const acc::Plan plan = make_plan(a);
  fs::create_directories(a.output);  // fail before the measurements, not after
  if (a.long_mode) return run_long(a, plan.isas, plan.modes);
  std::size_t case_count = 0;
  const acc::Report report = measure(a, plan, case_count);
  return write_report(a, report, case_count);
}

/// The command's options.
void add_accuracy_options(CLI::App* cmd, AccuracyArgs* args) {
  cmd->add_option("--scenes", args->scenes,
                  "Folder of the benchmark meshes (scenes/fetch gets them): default $VOLLEY_SCENES, else "
                  "../shared/scenes, else scenes/downloads");
  cmd->add_option("-o,--output", args->output, "Output folder")->capture_default_str();
  cmd->add_option("--test", args->tests, "Triangle tests, comma-separated")
      ->delimiter(',')
      ->check(CLI::IsMember({"plane", "moller", "watertight"}))
      ->capture_default_str();
  cmd->add_option("--isa", args->isas, "ISAs, comma-separated (default: scalar and every SIMD ISA of this CPU)")
      ->delimiter(',')
      ->check(CLI::IsMember({"scalar", "sse4.2", "avx2", "avx512"}));
  cmd->add_option("--modes", args->modes, "Query modes, comma-separated (single, packet4, packet8, packet16, stream)")
      ->delimiter(',')
      ->check(CLI::IsMember({"single", "packet4", "packet8", "packet16", "stream"}))
      ->capture_default_str();
  cmd->add_option("--reps", args->reps, "Timed closest-hit passes per row (the best counts)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_flag("--quick", args->quick, "Small cases (a few seconds; for tests): fewer rays, 32x32 images");
  cmd->add_flag("--no-images", args->no_images, "Skip the image-error renders");
  cmd->add_flag("--long", args->long_mode,
                "Only the long leak run: watertight + robust, >= --long-rays aimed rays per ISA and mode at offsets "
                "0..1e6; writes long.md");
  cmd->add_option("--long-rays", args->long_rays, "Distinct rays per ISA for --long")
      ->check(CLI::Range(1e3, 1e9))
      ->capture_default_str();
}

}  // namespace

Runner register_accuracy(CLI::App& app) {
  auto args = std::make_shared<AccuracyArgs>();
  CLI::App* cmd =
      app.add_subcommand("accuracy",
                         "Measure run time against error for every triangle test x ISA x query mode x traversal;\n"
                         "write report.md, accuracy.csv and accuracy.png (gnuplot) to the output folder.\n"
                         "Cases: closed meshes (grid cube, icosphere) with rays from inside aimed exactly at shared\n"
                         "vertices, edge midpoints and diagonals (leaks), 500 random triangles (t error), both moved\n"
                         "to 0, 1e3, 1e5, 1e6; the shared meshes stanford-bunny.obj and dragon_100k.obj (primary and\n"
                         "random rays); image error of scenes/cornell.json and bench/scenes/bunny.json against a\n"
                         "double-precision reference render. About 3-5 minutes on 2 cores.\n"
                         "Examples:\n"
                         "  volley accuracy                                   # perf/accuracy/\n"
                         "  volley accuracy --test watertight --isa avx2 -o out/acc\n"
                         "  volley accuracy --long                            # perf/accuracy/long.md");
  add_accuracy_options(cmd, args.get());
  return [args]() { return run_accuracy(*args); };
}

}  // namespace volley::cli
