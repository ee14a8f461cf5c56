// Loading a saved structure against building it (Accel::save, Accel::load), one thread
// (as bench_build.cpp):
//   load/<scene>/<isa>/commit: Accel::commit of the mesh already added (the build alone).
//   load/<scene>/<isa>/load:   Accel::load of the file save() wrote (map, checksum, checks),
//     the file in the page cache (written just before; the first iteration reads it too).
//   load_trace/<scene>/<isa>/{built,loaded}: single-ray closest hits of 2^16 incoherent rays
//     on the structure as built and as loaded (queried in the mapped file). Items = rays.
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bench_common.h"
#include "volley/accel.h"

namespace volley::bench {
namespace {

Accel built(const io::MeshDesc& mesh, Isa isa) {
  Accel accel;
  accel.add_triangles(&mesh.positions[0].x, mesh.positions.size(), mesh.indices.data(), mesh.triangle_count());
  accel.commit({TriangleTest::watertight, isa});
  return accel;
}

std::string saved_file(const io::MeshDesc& mesh, const std::string& scene, Isa isa) {
  const std::string path = (std::filesystem::temp_directory_path() /
                            ("volley_bench_" + scene + "_" + std::string(volley::to_string(isa)) + ".vacc"))
                               .string();
  built(mesh, isa).save(path);
  return path;
}

void commit_or_load(benchmark::State& state, const std::string& scene, Isa isa, bool load) {
  const io::MeshDesc* mesh = mesh_for(state, scene, isa);
  if (!mesh) return;
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
  const std::string path = saved_file(*mesh, scene, isa);
  Accel accel;
  accel.add_triangles(&mesh->positions[0].x, mesh->positions.size(), mesh->indices.data(), mesh->triangle_count());
  for (auto _ : state) {
    if (load) {
      accel = Accel::load(path);
    } else {
      accel.disable_geometry(0);  // uncommits: the next commit builds
      accel.enable_geometry(0);
      accel.commit({TriangleTest::watertight, isa});
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh->triangle_count()));
  state.counters["file_MB"] = double(std::filesystem::file_size(path)) / 1e6;
  std::remove(path.c_str());
}

void trace(benchmark::State& state, const std::string& scene, Isa isa, bool load) {
  const io::MeshDesc* mesh = mesh_for(state, scene, isa);
  if (!mesh) return;
  const std::vector<Ray> rays = incoherent_rays(*mesh);
  std::string path;
  Accel accel = built(*mesh, isa);
  if (load) {
    path = saved_file(*mesh, scene, isa);
    accel = Accel::load(path);
  }
  std::size_t hits = 0;
  for (auto _ : state)
    for (const Ray& r : rays) hits += accel.intersect(r).hit();
  benchmark::DoNotOptimize(hits);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(rays.size()));
  if (load) std::remove(path.c_str());
}

const bool registered = [] {
  for (const char* scene : {"conference", "kitchen"}) {
    note_scene(scene);
    for (Isa isa : {Isa::avx2, Isa::avx512}) {
      if (!bench_isa(isa)) continue;
      for (bool load : {false, true}) {
        const std::string tail = std::string("/") + scene + "/" + std::string(volley::to_string(isa));
        benchmark::RegisterBenchmark(("load" + tail + (load ? "/load" : "/commit")).c_str(),
                                     [=](benchmark::State& st) { commit_or_load(st, scene, isa, load); })
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark(("load_trace" + tail + (load ? "/loaded" : "/built")).c_str(),
                                     [=](benchmark::State& st) { trace(st, scene, isa, load); })
            ->Unit(benchmark::kMillisecond);
      }
    }
  }
  return true;
}();

}  // namespace
}  // namespace volley::bench
