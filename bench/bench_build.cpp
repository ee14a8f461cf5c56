// Acceleration-structure builds per second: Accel::add_triangles + Accel::commit of a
// scene's merged triangle mesh, per scene x ISA, on one thread (a oneTBB global_control
// limits the parallel parts of the build to the calling thread, so the figure does not
// depend on what else the machine runs); build/<scene>/avx512/2threads allows two, for
// the parallel build's scaling (the tree is the same for any thread count), and
// build/<scene>/avx512/high is the spatial-split build (BuildQuality::high) on one thread.
//
// The ISA decides the structure: scalar builds the oracle's binary SAH BVH, a SIMD ISA
// the wide BVH with triangle blocks of its lane count (test: watertight). Items processed
// = triangles. Names: build/<scene>/<isa>; the label is the ISA. Counters describe the
// result and are deterministic: sah_cost, nodes, leaves, bytes (AccelInfo).
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cstdint>
#include <exception>
#include <string>

#include "bench_common.h"
#include "volley/accel.h"

namespace volley::bench {
namespace {

void build(benchmark::State& state, const std::string& scene, Isa isa, int threads,
           BuildQuality quality = BuildQuality::medium) {
  state.SetLabel(std::string(volley::to_string(isa)));
  const io::SceneDesc* desc = nullptr;
  try {
    desc = &scene_desc(scene);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  const io::MeshDesc& mesh = desc->mesh;
  const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<std::size_t>(threads));
  const std::size_t extra_builds = slowdown_extra(1);  // the synthetic slowdown: whole extra builds
  AccelInfo info;
  for (auto _ : state) {
    for (std::size_t k = 0; k <= extra_builds; ++k) {
      Accel accel;
      accel.add_triangles(&mesh.positions[0].x, mesh.positions.size(), mesh.indices.data(), mesh.triangle_count());
      Options options{TriangleTest::watertight, isa};
      options.quality = quality;
      accel.commit(options);
      benchmark::DoNotOptimize(accel);
      if (k == 0) info = accel.info();
    }
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(mesh.triangle_count()));
  state.counters["sah_cost"] = info.sah_cost;
  state.counters["nodes"] = static_cast<double>(info.nodes);
  state.counters["leaves"] = static_cast<double>(info.leaves);
  state.counters["bytes"] = static_cast<double>(info.bytes);
}

const bool registered = [] {
  for (const char* scene : {"bunny", "conference"}) {
    note_scene(scene);
    for (Isa isa : {Isa::scalar, Isa::sse42, Isa::avx2, Isa::avx512}) {
      if (!bench_isa(isa)) continue;
      const std::string name = std::string("build/") + scene + "/" + std::string(volley::to_string(isa));
      benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& st) {
        build(st, scene, isa, 1);
      })->Unit(benchmark::kMillisecond);
      if (isa == Isa::avx512) {
        benchmark::RegisterBenchmark((name + "/2threads").c_str(),
                                     [=](benchmark::State& st) { build(st, scene, isa, 2); })
            ->Unit(benchmark::kMillisecond)
            ->UseRealTime();
        benchmark::RegisterBenchmark((name + "/high").c_str(),
                                     [=](benchmark::State& st) { build(st, scene, isa, 1, BuildQuality::high); })
            ->Unit(benchmark::kMillisecond);
      }
    }
  }
  return true;
}();

}  // namespace
}  // namespace volley::bench
