// Rays per second of whole renders (src/apps/render): tiles, shading, secondary rays and
// shadow rays together, per scene x ISA x integrator, one thread, 128 x 128 pixels,
// 1 sample per pixel, the scene's own max_depth and seed, the integrator its file names.
//
// Scenes: cornell (Whitted: mirror and glass spheres), cornell-original (path tracing),
// polygons (Whitted, planar polygons). Items processed = rays traced, all kinds (RayStats);
// the counter rays_per_pixel is deterministic for a given scene and seed. Names:
// render/<scene>/<isa>/<integrator>; the label is the ISA. The scene is built once per
// (scene, ISA), outside the timed loop.
#include <benchmark/benchmark.h>

#include <cstdint>
#include <exception>
#include <map>
#include <memory>
#include <string>

#include "bench_common.h"
#include "render/renderer.h"
#include "render/scene.h"

namespace volley::bench {
namespace {

constexpr int kImage = 128;

void render_scene(benchmark::State& state, const std::string& scene, Isa isa, render::IntegratorKind integrator) {
  static std::map<std::pair<std::string, Isa>, std::unique_ptr<render::Scene>> cache;
  state.SetLabel(std::string(volley::to_string(isa)));
  const io::SceneDesc* desc = nullptr;
  try {
    desc = &scene_desc(scene);
    auto& slot = cache[{scene, isa}];
    if (!slot) slot = std::make_unique<render::Scene>(*desc, kImage, kImage, Options{TriangleTest::watertight, isa});
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  const render::Scene& s = *cache[{scene, isa}];
  render::RenderOptions options;
  options.spp = 1;
  options.max_depth = desc->settings.max_depth;
  options.integrator = integrator;
  options.seed = desc->settings.seed;
  options.threads = 1;
  const std::size_t extra_renders = slowdown_extra(1);  // the synthetic slowdown: whole extra renders
  std::uint64_t rays = 0;
  for (auto _ : state) {
    for (std::size_t k = 0; k <= extra_renders; ++k) {
      const render::RenderResult result = render::render(s, options);
      if (k == 0) rays += result.stats.total();
      benchmark::DoNotOptimize(result.image.pixels.data());
    }
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(rays));
  const double iterations = static_cast<double>(state.iterations());
  state.counters["rays_per_pixel"] = iterations > 0 ? static_cast<double>(rays) / iterations / (kImage * kImage) : 0.0;
}

const bool registered = [] {
  // The integrator each scene file asks for, fixed here so that registering needs no file.
  const std::pair<const char*, render::IntegratorKind> scenes[] = {
      {"cornell", render::IntegratorKind::whitted},
      {"cornell-original", render::IntegratorKind::path},
      {"polygons", render::IntegratorKind::whitted},
  };
  for (const auto& [scene, integrator] : scenes) {
    note_scene(scene);
    for (Isa isa : {Isa::scalar, Isa::sse42, Isa::avx2, Isa::avx512}) {
      if (!bench_isa(isa)) continue;
      const std::string name = std::string("render/") + scene + "/" + std::string(volley::to_string(isa)) + "/" +
                               (integrator == render::IntegratorKind::path ? "path" : "whitted");
      benchmark::RegisterBenchmark(name.c_str(), [=, scene = std::string(scene), integrator = integrator](benchmark::State& st) {
        render_scene(st, scene, isa, integrator);
      })->Unit(benchmark::kMillisecond);
    }
  }
  return true;
}();

}  // namespace
}  // namespace volley::bench
