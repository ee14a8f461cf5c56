// What skipping the stages a scene doesn't need saves: each scene rendered by the
// pipeline specialised to it and by the general one (every stage), one thread, AVX-512
// or the best ISA, 128 x 128 pixels, 1 sample per pixel. Run with
// --benchmark_repetitions=N --benchmark_enable_random_interleaving=true so that the two
// alternate; the speedup of each scene is general / specialised (perf/reports/specialize.md). Names:
// specialize/<scene>/<specialised|general>; items = rays traced (the general pipeline
// traces the same rays: the two images are identical). The speedup is the ratio of the
// two rates (perf/reports/specialize.md).
#include <benchmark/benchmark.h>

#include <exception>
#include <map>
#include <memory>
#include <string>

#include "bench_common.h"
#include "render/renderer.h"
#include "render/scene.h"
#include "simd/isa/dispatch.h"

namespace volley::bench {
namespace {

constexpr int kImage = 128;

// A benchmark scene, or a variant of one: "<scene>-unlit" is the scene without its point
// lights (diffuse only: no direct light, no shadow rays).
constexpr const char* kUnlit = "-unlit";

void render_pipeline(benchmark::State& state, const std::string& scene, bool specialize) {
  static std::map<std::string, std::unique_ptr<render::Scene>> cache;
  static std::map<std::string, io::SceneDesc> variants;
  const io::SceneDesc* desc = nullptr;
  try {
    const std::size_t unlit = scene.rfind(kUnlit);
    if (unlit != std::string::npos && unlit + std::string(kUnlit).size() == scene.size()) {
      auto [it, fresh] = variants.try_emplace(scene, scene_desc(scene.substr(0, unlit)));
      if (fresh) it->second.lights.clear();
      desc = &it->second;
    } else {
      desc = &scene_desc(scene);
    }
    auto& slot = cache[scene];
    if (!slot) slot = std::make_unique<render::Scene>(*desc, kImage, kImage, Options{});
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  const render::Scene& s = *cache[scene];
  state.SetLabel(std::string(volley::to_string(s.accel().info().isa)));
  render::RenderOptions options;
  options.max_depth = desc->settings.max_depth;
  options.integrator = desc->settings.integrator == "path" ? render::IntegratorKind::path : render::IntegratorKind::whitted;
  options.threads = 1;
  options.specialize = specialize;
  std::uint64_t rays = 0;
  for (auto _ : state) {
    const render::RenderResult result = render::render(s, options);
    rays += result.stats.total();
    benchmark::DoNotOptimize(result.image.pixels.data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(rays));
}

const bool registered = [] {
  // Feature sets: diffuse + shadows (path), mirrors + polygons, glass + mirror + smooth
  // normals, a large diffuse mesh with shadows (Whitted), the same diffuse only (no
  // lights), a bare mesh (automatic camera and light, Whitted).
  for (const char* scene :
       {"cornell-original", "polygons", "cornell", "conference", "conference-unlit", "bunny-bare"}) {
    const std::string base(scene);
    note_scene(base.substr(0, base.rfind(kUnlit)));
    for (bool specialize : {true, false}) {
      const std::string name = std::string("specialize/") + scene + (specialize ? "/specialised" : "/general");
      benchmark::RegisterBenchmark(name.c_str(), [=, scene = std::string(scene)](benchmark::State& st) {
        render_pipeline(st, scene, specialize);
      })->Unit(benchmark::kMillisecond);
    }
  }
  return true;
}();

}  // namespace
}  // namespace volley::bench
