// volley points and volley query: the point queries from the command line. `points`
// writes query points around a scene (.vpts); `query` answers them (contains, distance,
// signed-distance, closest) with the batch API on all cores, best of --reps, in a stable
// key=value line for scripts and a human summary after it:
//
//   query: scene=S points=N op=OP test=T isa=I threads=N reps=N best_s=F median_s=F
//          Mpoints/s=F found=N inside=N                                     (one line)
//
// found counts points with a surface point within --max-distance (distance ops) and inside
// the points inside (contains, signed-distance). Keys are only ever added.
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/common.h"
#include "io/query_files.h"
#include "io/scene_loader.h"
#include "render/scene.h"
#include "volley/accel.h"

namespace volley::cli {
namespace {

struct PointsArgs {
  std::string scene;
  std::string output;
  std::size_t count = 100000;
  double near = 0.5;
  double spread = 0.1;
  long long seed = 1;
  KernelArgs kernel;
};

struct QueryArgs {
  std::string scene;
  std::string points;
  std::string op;
  std::string output;
  float max_distance = INFINITY;
  int threads = 0;
  int reps = 3;
  KernelArgs kernel;
};

/// The scene's triangles and polygon corners, as they were loaded (instances left out).
struct Surface {
  std::vector<glm::vec3> corners;  ///< 3 per triangle
  glm::vec3 lo{INFINITY}, hi{-INFINITY};
};

Surface surface_of(const io::SceneDesc& desc) {
  Surface s;
  for (std::uint32_t i : desc.mesh.indices) s.corners.push_back(desc.mesh.positions[i]);
  for (const io::PolygonDesc& p : desc.polygons)
    for (std::size_t k = 1; k + 1 < p.vertices.size(); ++k)
      s.corners.insert(s.corners.end(), {p.vertices[0], p.vertices[k], p.vertices[k + 1]});
  for (const glm::vec3& c : s.corners) s.lo = glm::min(s.lo, c), s.hi = glm::max(s.hi, c);
  return s;
}

/// The answers of a point query, one vector filled by the operation.
struct PointAnswers {
  std::vector<std::uint8_t> inside;
  std::vector<float> dist;
  std::vector<ClosestPoint> closest;
};

/// Runs the query --reps times; returns the sorted run times.
std::vector<double> time_queries(const QueryArgs& a, const Accel& accel, const std::vector<float>& xyz, int threads,
                                 PointAnswers& answers) {
  const std::size_t n = xyz.size() / 3;
  answers.inside.resize(a.op == "contains" ? n : 0);
  answers.dist.resize(a.op == "distance" || a.op == "signed-distance" ? n : 0);
  answers.closest.resize(a.op == "closest" ? n : 0);
  std::vector<double> seconds;
  for (int rep = 0; rep < a.reps; ++rep) {
    const auto start = std::chrono::steady_clock::now();
    if (a.op == "contains")
      accel.contains(xyz.data(), n, answers.inside.data(), threads);
    else if (a.op == "closest")
      accel.closest_points(xyz.data(), n, answers.closest.data(), a.max_distance, threads);
    else
      accel.distances(xyz.data(), n, answers.dist.data(), a.op == "signed-distance", threads);
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(seconds.begin(), seconds.end());
  return seconds;
}

/// Writes the answers to --output, if given.
void write_answers(const QueryArgs& a, const PointAnswers& answers) {
  if (a.output.empty()) return;
  if (a.op == "contains") {
    io::write_occupancy(a.output, answers.inside);
  } else if (a.op == "closest") {
    std::vector<io::ClosestRecord> records(answers.closest.size());
    for (std::size_t i = 0; i < records.size(); ++i) records[i] = io::closest_record(answers.closest[i]);
    io::write_closest(a.output, records);
  } else {
    io::write_distances(a.output, answers.dist);
  }
  std::printf("answers -> %s\n", a.output.c_str());
}

/// volley query's run.
int run_query(const QueryArgs& a) {
  const std::vector<float> xyz = io::read_points(a.points);
  const std::size_t n = xyz.size() / 3;
  const io::SceneDesc desc = io::load_scene(a.scene, shared_scenes_dir(a.kernel.scenes));
  const render::Scene scene(desc, desc.settings.width, desc.settings.height, kernel_options(a.kernel));
  const Accel& accel = scene.accel();
  const AccelInfo info = accel.info();
  const bool parity = a.op == "contains" || a.op == "signed-distance";
  if (parity) {
    const render::SceneFeatures f = render::with_closure(scene, desc);
    if (!f.closed)
      std::fprintf(stderr,
                   "volley: warning: %s is not a closed, consistently oriented surface (%zu open or unmatched edges): "
                   "inside/outside is the parity of one ray's crossings and depends on its direction\n",
                   a.scene.c_str(), f.open_edges);
  }
  const int threads = a.threads ? a.threads : tbb::this_task_arena::max_concurrency();
  PointAnswers answers;
  const std::vector<double> seconds = time_queries(a, accel, xyz, threads, answers);
  const double best = seconds.front(), median = seconds[seconds.size() / 2];
  std::size_t found = 0, in = 0;
  for (std::uint8_t b : answers.inside) in += b;
  for (float d : answers.dist) found += std::isfinite(d), in += d < 0.0f;
  for (const ClosestPoint& c : answers.closest) found += c.found();
  const double mpoints = best > 0.0 ? double(n) / best * 1e-6 : 0.0;
  const std::string test(to_string(info.test)), isa(to_string(info.isa));
  std::printf(
      "query: scene=%s points=%zu op=%s test=%s isa=%s threads=%d reps=%d best_s=%.6f median_s=%.6f "
      "Mpoints/s=%.3f found=%zu inside=%zu\n",
      a.scene.c_str(), n, a.op.c_str(), test.c_str(), isa.c_str(), threads, a.reps, best, median, mpoints, found, in);
  std::printf("%s: %zu points from %s, %s, %s/%s, %d thread%s: best %.2f ms (median %.2f ms) of %d, %.2f Mpoints/s",
              a.scene.c_str(), n, a.points.c_str(), a.op.c_str(), test.c_str(), isa.c_str(), threads,
              threads == 1 ? "" : "s", best * 1e3, median * 1e3, a.reps, mpoints);
  if (parity) std::printf("; %zu inside (%.1f%%)", in, n ? 100.0 * double(in) / double(n) : 0.0);
  if (a.op != "contains") std::printf("; %zu with a surface point", found);
  std::printf("\n");
  write_answers(a, answers);
  return 0;
}

}  // namespace

Runner register_points(CLI::App& app) {
  auto args = std::make_shared<PointsArgs>();
  CLI::App* cmd =
      app.add_subcommand("points",
                         "Write query points around a scene as a .vpts file for `volley query`: a share of them\n"
                         "just off the surface (random points of random triangles, moved by up to 1% of the scene's\n"
                         "size), the rest uniform in the scene's box widened by --spread");
  cmd->add_option("scene", args->scene, "Scene file (.json) or mesh (.obj, .ply)")->required();
  cmd->add_option("-o,--output", args->output, "Output point file (.vpts)")->required();
  cmd->add_option("-n,--count", args->count, "Points to write")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1} << 32))
      ->capture_default_str();
  cmd->add_option("--near", args->near, "Share of the points near the surface (0 to 1)")
      ->check(CLI::Range(0.0, 1.0))
      ->capture_default_str();
  cmd->add_option("--spread", args->spread, "Widen the box by this share of its size on every side")
      ->check(CLI::Range(0.0, 100.0))
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Random seed")->check(CLI::NonNegativeNumber)->capture_default_str();
  add_kernel_options(*cmd, args->kernel);
  return [args]() {
    const PointsArgs& a = *args;
    const io::SceneDesc desc = io::load_scene(a.scene, shared_scenes_dir(a.kernel.scenes));
    const Surface s = surface_of(desc);
    if (s.corners.empty())
      throw std::runtime_error(a.scene + ": the scene has no triangles or polygons to put points around");
    const glm::vec3 size = s.hi - s.lo;
    const float scale = std::max({size.x, size.y, size.z, 1e-6f});
    std::mt19937_64 rng(std::uint64_t(a.seed));
    std::uniform_real_distribution<float> unit(0.0f, 1.0f), off(-0.01f * scale, 0.01f * scale);
    std::uniform_int_distribution<std::size_t> pick(0, s.corners.size() / 3 - 1);
    std::vector<float> xyz;
    xyz.reserve(3 * a.count);
    for (std::size_t i = 0; i < a.count; ++i) {
      glm::vec3 p;
      if (unit(rng) < a.near) {
        const std::size_t t = pick(rng);
        float u = unit(rng), v = unit(rng);
        if (u + v > 1) u = 1 - u, v = 1 - v;
        const glm::vec3* c = &s.corners[3 * t];
        p = c[0] + u * (c[1] - c[0]) + v * (c[2] - c[0]) + glm::vec3(off(rng), off(rng), off(rng));
      } else {
        const glm::vec3 lo = s.lo - float(a.spread) * size, hi = s.hi + float(a.spread) * size;
        p = lo + glm::vec3(unit(rng), unit(rng), unit(rng)) * (hi - lo);
      }
      xyz.insert(xyz.end(), {p.x, p.y, p.z});
    }
    io::write_points(a.output, xyz);
    std::printf("%s: %zu points (%.0f%% near the surface), seed %lld -> %s\n", a.scene.c_str(), a.count, 100.0 * a.near,
                a.seed, a.output.c_str());
    return 0;
  };
}

Runner register_query(CLI::App& app) {
  auto args = std::make_shared<QueryArgs>();
  CLI::App* cmd =
      app.add_subcommand("query",
                         "Answer point queries against a scene on all cores and print Mpoints/s (best of --reps):\n"
                         "contains (inside a closed surface, by the parity of one ray's crossings), distance,\n"
                         "signed-distance (negative inside), closest (the nearest surface point and its ids).\n"
                         "Prints one line `query: key=value ...` for scripts, then a summary");
  cmd->add_option("scene", args->scene, "Scene file (.json) or mesh (.obj, .ply)")->required();
  cmd->add_option("--points", args->points, "Point file (.vpts) from `volley points`")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--op", args->op, "contains, distance, signed-distance or closest")
      ->required()
      ->check(CLI::IsMember({"contains", "distance", "signed-distance", "closest"}));
  cmd->add_option("-o,--output", args->output,
                  "Write the answers: .vocc (contains), .vdst (distance, signed-distance), .vclp (closest)");
  cmd->add_option("--max-distance", args->max_distance, "closest: search no farther (default: no limit)")
      ->check(CLI::NonNegativeNumber);
  add_threads_option(*cmd, args->threads);
  cmd->add_option("--reps", args->reps, "Timed repetitions; the best is reported")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  add_kernel_options(*cmd, args->kernel);
  return [args]() { return run_query(*args); };
}

}  // namespace volley::cli
