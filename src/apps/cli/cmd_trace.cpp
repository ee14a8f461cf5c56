// volley trace: traces a ray file against a scene in one of the query modes (single
// rays, SoA packets, streams), closest hit or occlusion, and prints the rate: best of
// --reps repetitions of the intersection loop alone (loading and the BVH build are not
// timed), in a stable key=value line for scripts and a human summary after it:
//
//   trace: scene=S rays=N mode=single|packet|stream packet=K test=T isa=I threads=N
//          occluded=0|1 reps=N best_s=F median_s=F Mrays/s=F hits=N robust=0|1
//          reference=0|1 mask=M|none query=closest|occluded|count|all normals=0|1
//          exclude=FILE|none  (one line)
//
// packet is the packet width K in packet mode, 0 otherwise; Mrays/s = rays / best_s;
// hits counts closest hits, blocked rays with --occluded, or every hit (crossings) with
// --count and --all; robust=0 with --fast-slabs,
// reference=1 with --reference, mask the --mask the rays were traced with, normals=1 when
// --normals computed each hit's normal inside the timing, exclude the --exclude hit file whose
// primitives the rays passed over. Keys are only ever added.
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "cli/commands.h"
#include "cli/common.h"
#include "cli/trace_tracers.h"
#include "io/query_files.h"
#include "io/ray_file.h"
#include "io/scene_loader.h"
#include "render/scene.h"
#include "volley/accel.h"

namespace volley::cli {
namespace {

struct TraceArgs {
  std::string scene;
  std::string rays;
  std::string output;
  std::string save;                   ///< write the built structure here
  std::string load;                   ///< map the structure from here instead of building it
  std::optional<std::uint32_t> mask;  ///< the rays' mask (the masked query forms)
  std::string exclude;                ///< --exclude: a hit file, one per ray, whose primitives the rays pass over
  bool occluded = false;
  bool count = false;    ///< --count: crossings per ray (.vcnt)
  bool all = false;      ///< --all: every hit per ray (.vall)
  bool stats = false;    ///< --stats: the single-ray walk's visits per ray
  bool normals = false;  ///< --normals: each closest hit's geometric normal too, timed
  std::string mode = "single";
  int packet = 16;
  int threads = 0;
  int reps = 5;
  KernelArgs kernel;
};

/// The command line's options into `args`.
void add_trace_options(CLI::App* cmd, TraceArgs* args) {
  cmd->add_option("scene", args->scene, "Scene file (.json) or mesh (.obj, .ply)")->required();
  cmd->add_option("--rays", args->rays, "Ray file (.vray) from `volley rays`")->required();
  cmd->add_option("-o,--output", args->output,
                  "Write the answers: a hit file (.vhit), or .vcnt / .vall with --count / --all");
  auto* occluded = cmd->add_flag("--occluded", args->occluded,
                                 "Occlusion (any hit) instead of the closest hit; .vhit t = 0 when blocked");
  auto* count =
      cmd->add_flag("--count", args->count,
                    "Count every hit along each ray (crossings, each shared edge or vertex once: docs/crossings.md);\n"
                    "-o writes a count file (.vcnt). Single rays, or the stream API with --mode stream or batch");
  auto* all =
      cmd->add_flag("--all", args->all,
                    "Every hit along each ray, nearest first; -o writes a hit-list file (.vall). Single rays only")
          ->excludes(occluded)
          ->excludes(count);
  cmd->add_flag("--normals", args->normals,
                "Also the geometric normal of every closest hit (Accel::geometric_normals, what Python's\n"
                "cast_rays returns beside the hits), inside the timing: the C++ twin of cast_rays")
      ->excludes(occluded)
      ->excludes(count)
      ->excludes(all);
  count->excludes(occluded);
  cmd->add_option("--mode", args->mode,
                  "single (one ray at a time), packet (SoA packets of consecutive rays), stream (the stream API,\n"
                  "1024 rays a call, the calls spread over --threads), batch (the stream API on the whole file in\n"
                  "one call with its thread count: the library spreads the rays)")
      ->check(CLI::IsMember({"single", "packet", "stream", "batch"}))
      ->capture_default_str();
  cmd->add_option("--packet", args->packet, "Rays per packet in packet mode")
      ->check(CLI::IsMember({4, 8, 16}))
      ->capture_default_str();
  add_threads_option(*cmd, args->threads);
  cmd->add_flag("--stats", args->stats,
                "Also count what the single-ray walk visits per ray (interior nodes, leaves, triangles; an\n"
                "untimed pass; triangles in one layer on a SIMD ISA)");
  cmd->add_option("--reps", args->reps, "Timed repetitions; the best is reported")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  cmd->add_option("--mask", args->mask,
                  "Trace every ray with this 32-bit mask (the masked query forms): it hits only objects whose\n"
                  "\"mask\" shares a bit with it")
      ->check(CLI::Range(std::uint64_t{0}, std::uint64_t{0xffffffffu}));
  cmd->add_option("--exclude", args->exclude,
                  "A hit file (.vhit) with one hit per ray, such as `trace -o` wrote for the rays these start\n"
                  "from: each ray passes over the primitive of its hit (the excluding queries; a miss leaves\n"
                  "nothing out), so rays spawned at hit points need no origin offset. Single, stream or batch mode")
      ->check(CLI::ExistingFile);
  cmd->add_option("--save", args->save,
                  "Write the built structure to this file (Accel::save), to --load it later instead of building");
  cmd->add_option("--load", args->load,
                  "Map the structure from a file --save wrote for this scene instead of building it (its test and\n"
                  "ISA are the file's: --test and --isa are ignored)")
      ->check(CLI::ExistingFile);
  add_kernel_options(*cmd, args->kernel);
}

/// The pairs of options that have no form together: UsageError naming them.
void check_option_pairs(const TraceArgs& a) {
  const bool crossings = a.count || a.all;
  if (a.all && a.mode != "single") throw UsageError("--all traces single rays: leave --mode at single");
  if (a.count && a.mode == "packet") throw UsageError("--count has no packet form: --mode single, stream or batch");
  if (a.count && a.mask && a.mode != "single")
    throw UsageError("--count with --mask traces single rays: leave --mode at single");
  if (a.stats && crossings)
    throw UsageError("--stats counts the closest-hit or occlusion walk: not with --count or --all");
  if (!a.exclude.empty() && (crossings || a.mode == "packet" || a.stats))
    throw UsageError(
        "--exclude has closest-hit and occlusion forms for single rays and arrays: not with --count,\n"
        "--all, --stats or --mode packet");
}

/// What the answers found: closest hits, blocked rays, or every hit (crossings).
std::size_t count_found(const TraceArgs& a, const Answers& answers) {
  std::size_t hit_count = 0;
  if (a.occluded) {
    for (std::uint8_t b : answers.blocked) hit_count += b;
  } else if (a.count || a.all) {
    for (std::uint32_t c : answers.counts) hit_count += c;
    for (const std::vector<Hit>& l : answers.lists) hit_count += l.size();
  } else {
    for (const Hit& h : answers.hits) hit_count += h.hit() ? 1 : 0;
  }
  return hit_count;
}

/// The `trace:` line for scripts and the summary for people.
void print_result(const TraceArgs& a, const AccelInfo& info, std::size_t ray_count, int threads, double best,
                  double median, std::size_t hit_count) {
  const bool crossings = a.count || a.all;
  const char* query = a.occluded ? "occluded" : a.count ? "count" : a.all ? "all" : "closest";
  const double mrays = best > 0.0 ? double(ray_count) / best * 1e-6 : 0.0;
  const int packet = a.mode == "packet" ? a.packet : 0;
  const std::string mode = packet ? "packet" + std::to_string(packet) : a.mode;  // for the summary
  const std::string test(to_string(info.test)), isa(to_string(info.isa));

  std::printf(
      "trace: scene=%s rays=%zu mode=%s packet=%d test=%s isa=%s threads=%d occluded=%d reps=%d "
      "best_s=%.6f median_s=%.6f Mrays/s=%.3f hits=%zu robust=%d reference=%d mask=%s query=%s normals=%d "
      "exclude=%s\n",
      a.scene.c_str(), ray_count, a.mode.c_str(), packet, test.c_str(), isa.c_str(), threads, a.occluded ? 1 : 0,
      a.reps, best, median, mrays, hit_count, info.robust ? 1 : 0, info.reference_double ? 1 : 0,
      a.mask ? std::to_string(*a.mask).c_str() : "none", query, a.normals ? 1 : 0,
      a.exclude.empty() ? "none" : a.exclude.c_str());
  char found[96];
  const double share = ray_count == 0 ? 0.0 : double(hit_count) / double(ray_count);
  if (crossings)
    std::snprintf(found, sizeof found, "%zu hits in all (%.2f per ray)", hit_count, share);
  else
    std::snprintf(found, sizeof found, "%zu %s (%.1f%%)", hit_count, a.occluded ? "blocked" : "hit", 100.0 * share);
  std::printf(
      "%s: %zu rays from %s, %s %s, %s/%s, %d thread%s: best %.2f ms (median %.2f ms) of %d, "
      "%.2f Mrays/s; %s; %s %.3f s\n",
      a.scene.c_str(), ray_count, a.rays.c_str(),
      a.occluded ? "occlusion"
      : a.count  ? "crossing count"
      : a.all    ? "all hits"
                 : "closest hit",
      mode.c_str(), test.c_str(), isa.c_str(), threads, threads == 1 ? "" : "s", best * 1e3, median * 1e3, a.reps,
      mrays, found, info.loaded ? "BVH loaded in" : "BVH built in",
      info.loaded ? info.load_seconds : info.build_seconds);
}

/// An untimed pass of the single-ray walk, counting what it visits (--stats).
void print_walk_counts(const Accel& accel, const std::vector<Ray>& rays, bool occluded) {
  WalkCounts sum;
  for (const Ray& r : rays) {
    const WalkCounts c = accel.walk_counts(r, occluded);
    sum.nodes += c.nodes, sum.leaves += c.leaves, sum.triangles += c.triangles;
  }
  const double n = rays.empty() ? 1.0 : double(rays.size());
  std::printf("walk: nodes/ray=%.3f leaves/ray=%.3f triangles/ray=%.3f (the single-ray walk, %s)\n",
              double(sum.nodes) / n, double(sum.leaves) / n, double(sum.triangles) / n,
              occluded ? "any hit" : "closest hit");
}

/// The answers in the file format of the query (-o).
void write_answers(const TraceArgs& a, const Answers& answers, std::size_t ray_count) {
  if (a.output.empty()) return;
  if (a.count) {
    io::write_counts(a.output, answers.counts);
  } else if (a.all) {
    HitLists lists;
    lists.offsets.push_back(0);
    for (const std::vector<Hit>& l : answers.lists) {
      lists.hits.insert(lists.hits.end(), l.begin(), l.end());
      lists.offsets.push_back(lists.hits.size());
    }
    io::write_hit_lists(a.output, lists);
  } else if (a.occluded) {
    std::vector<Hit> records(ray_count);
    for (std::size_t i = 0; i < ray_count; ++i) records[i] = io::occlusion_record(answers.blocked[i] != 0);
    io::write_hits(a.output, records);
  } else {
    io::write_hits(a.output, answers.hits);
  }
  std::printf("answers -> %s\n", a.output.c_str());
}

}  // namespace

Runner register_trace(CLI::App& app) {
  auto args = std::make_shared<TraceArgs>();
  CLI::App* cmd =
      app.add_subcommand("trace",
                         "Trace a ray file (.vray) against a scene and print Mrays/s (best of --reps, intersection\n"
                         "time only). Prints one line `trace: key=value ...` for scripts, then a summary");
  add_trace_options(cmd, args.get());

  return [args]() {
    const TraceArgs& a = *args;
    const bool crossings = a.count || a.all;
    check_option_pairs(a);
    const std::vector<Ray> rays = io::read_rays(a.rays);
    const std::vector<Hit> excluded = a.exclude.empty() ? std::vector<Hit>{} : io::read_hits(a.exclude);
    if (!a.exclude.empty() && excluded.size() != rays.size())
      throw UsageError("--exclude " + a.exclude + ": " + std::to_string(excluded.size()) + " hits for " +
                       std::to_string(rays.size()) + " rays in " + a.rays + " (one hit per ray expected)");
    const io::SceneDesc desc = io::load_scene(a.scene, shared_scenes_dir(a.kernel.scenes));
    const render::Scene scene(desc, desc.settings.width, desc.settings.height, kernel_options(a.kernel), a.load);
    const Accel& accel = scene.accel();
    const AccelInfo info = accel.info();
    if (a.stats) accel.walk_counts(Ray{}, a.occluded);  // says now, not after the timing, when it cannot count
    if (!a.save.empty()) accel.save(a.save);

    const int threads = a.threads ? a.threads : tbb::this_task_arena::max_concurrency();
    tbb::task_arena arena(threads);
    const std::vector<std::uint32_t> masks(a.mask ? rays.size() : 0, a.mask.value_or(kMaskAll));
    ChunkTracer trace =
        make_tracer(accel, rays, a.mask ? masks.data() : nullptr, a.exclude.empty() ? nullptr : excluded.data(), a.mode,
                    a.packet, a.occluded, crossings, threads);
    if (a.normals) trace = with_normals(accel, std::move(trace), a.mode == "batch" ? threads : 1);
    Answers answers;
    if (a.occluded)
      answers.blocked.assign(rays.size(), 0);
    else if (a.count)
      answers.counts.assign(rays.size(), 0);
    else if (a.all)
      answers.lists.resize(rays.size());
    else
      answers.hits.assign(rays.size(), Hit{});
    if (a.normals) answers.normals.assign(3 * rays.size(), 0.0f);

    std::vector<double> seconds;
    for (int rep = 0; rep < a.reps; ++rep)
      seconds.push_back(timed_pass(trace, rays.size(), threads, arena, answers, a.mode == "batch"));
    std::sort(seconds.begin(), seconds.end());
    const double best = seconds.front();
    const double median = seconds[seconds.size() / 2];

    const std::size_t hit_count = count_found(a, answers);
    print_result(a, info, rays.size(), threads, best, median, hit_count);
    if (!a.save.empty()) std::printf("saved the structure to %s\n", a.save.c_str());
    if (a.stats) print_walk_counts(accel, rays, a.occluded);
    write_answers(a, answers, rays.size());
    return 0;
  };
}

}  // namespace volley::cli
