// Refit against rebuild (Accel::update_vertices, Options::refit) on a smoothly deformed
// mesh, one thread (as bench_build.cpp):
//   refit/<scene>/<isa>/{refit,rebuild}: commit after the vertices moved, alternating
//     between the mesh and its deformation, so every commit has work to do. Counters:
//     refitted (1 when the commit refitted), sah_growth (AccelInfo).
//   refit_trace/<scene>/<isa>/{refit,rebuild}: single-ray closest hits of 2^16 incoherent
//     rays (random origins in the mesh's box, random directions) on the deformed mesh,
//     its BVH refitted from the original or built for it. Items = rays.
// The deformation: every vertex moved by 1% of the mesh's size in a wave of three periods
// across it (x by cos of z, y by sin of x): smooth, as an animated character's or cloth's.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdint>
#include <exception>
#include <random>
#include <string>
#include <vector>

#include "bench_common.h"
#include "volley/accel.h"

namespace volley::bench {
namespace {

std::vector<float> deformed(const io::MeshDesc& mesh) {
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::vec3& p : mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  const float size = std::max({hi.x - lo.x, hi.y - lo.y, hi.z - lo.z});
  const float amp = 0.01f * size, k = 2.0f * 3.14159265f * 3.0f / size;
  std::vector<float> out;
  out.reserve(3 * mesh.positions.size());
  for (const glm::vec3& p : mesh.positions)
    out.insert(out.end(), {p.x + amp * std::cos(k * p.z), p.y + amp * std::sin(k * p.x), p.z});
  return out;
}

void commit_after_move(benchmark::State& state, const std::string& scene, Isa isa, bool refit) {
  const io::MeshDesc* mesh = mesh_for(state, scene, isa);
  if (!mesh) return;
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
  const std::vector<float> moved = deformed(*mesh);
  const float* original = &mesh->positions[0].x;
  Options options{TriangleTest::watertight, isa};
  options.refit = refit;
  Accel accel;
  accel.add_triangles(original, mesh->positions.size(), mesh->indices.data(), mesh->triangle_count());
  accel.commit(options);
  // One move before timing: the first may build (degenerate triangles that gain area).
  accel.update_vertices(0, moved.data(), mesh->positions.size());
  accel.commit(options);
  bool flip = true;
  for (auto _ : state) {
    state.PauseTiming();
    flip = !flip;
    accel.update_vertices(0, flip ? moved.data() : original, mesh->positions.size());
    state.ResumeTiming();
    accel.commit(options);
  }
  // The counters describe the deformed shape, whichever shape the loop ended on (that
  // follows the iteration count's parity, which the timing decides).
  if (!flip) {
    accel.update_vertices(0, moved.data(), mesh->positions.size());
    accel.commit(options);
  }
  const AccelInfo info = accel.info();
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh->triangle_count()));
  state.counters["refitted"] = info.refitted ? 1.0 : 0.0;
  state.counters["sah_growth"] = info.sah_growth;
}

void trace_after_move(benchmark::State& state, const std::string& scene, Isa isa, bool refit) {
  const io::MeshDesc* mesh = mesh_for(state, scene, isa);
  if (!mesh) return;
  const std::vector<float> moved = deformed(*mesh);
  const std::vector<Ray> rays = incoherent_rays(*mesh);
  Accel accel;
  Options options{TriangleTest::watertight, isa};
  options.refit = refit;
  if (refit) {
    accel.add_triangles(&mesh->positions[0].x, mesh->positions.size(), mesh->indices.data(), mesh->triangle_count());
    // Built for the original shape (after one move, so that it holds the degenerate
    // triangles a move gives area: see Options::refit), then refitted to the deformation.
    accel.commit(options);
    accel.update_vertices(0, moved.data(), mesh->positions.size());
    accel.commit(options);
    accel.update_vertices(0, &mesh->positions[0].x, mesh->positions.size());
    Options build = options;
    build.refit = false;
    accel.commit(build);
    accel.update_vertices(0, moved.data(), mesh->positions.size());
  } else {
    accel.add_triangles(moved.data(), mesh->positions.size(), mesh->indices.data(), mesh->triangle_count());
  }
  accel.commit(options);
  std::size_t hits = 0;
  for (auto _ : state)
    for (const Ray& r : rays) hits += accel.intersect(r).hit();
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(rays.size()));
  state.counters["refitted"] = accel.info().refitted ? 1.0 : 0.0;
  state.counters["sah_growth"] = accel.info().sah_growth;
}

const bool registered = [] {
  for (const char* scene : {"conference", "kitchen"}) {
    note_scene(scene);
    for (Isa isa : {Isa::scalar, Isa::avx2, Isa::avx512}) {
      if (!bench_isa(isa)) continue;
      for (bool refit : {true, false}) {
        const std::string tail =
            std::string("/") + scene + "/" + std::string(volley::to_string(isa)) + (refit ? "/refit" : "/rebuild");
        benchmark::RegisterBenchmark(("refit" + tail).c_str(), [=](benchmark::State& st) {
          commit_after_move(st, scene, isa, refit);
        })->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark(("refit_trace" + tail).c_str(), [=](benchmark::State& st) {
          trace_after_move(st, scene, isa, refit);
        })->Unit(benchmark::kMillisecond);
      }
    }
  }
  return true;
}();

}  // namespace
}  // namespace volley::bench
