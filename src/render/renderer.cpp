#include "render/renderer.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>

#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace volley::render {
namespace {

constexpr int kTile = 16;

// Stratified sub-pixel offsets in [-0.5, 0.5): an n x n grid (n = ceil(sqrt(spp))), one
// jittered sample per used cell.
glm::vec2 jitter(int sample, int spp, Rng& rng) {
  if (spp == 1) return {0.0f, 0.0f};
  const int n = int(std::ceil(std::sqrt(float(spp))));
  const int sx = sample % n, sy = sample / n;
  return {(float(sx) + rng.uniform()) / float(n) - 0.5f, (float(sy) + rng.uniform()) / float(n) - 0.5f};
}

}  // namespace

RenderResult render(const Scene& scene, const RenderOptions& options) {
  const core::Camera& camera = scene.camera();
  const int width = camera.width(), height = camera.height();
  RenderResult result;
  result.image = {width, height, std::vector<glm::vec3>(std::size_t(width) * height)};
  const int tiles_x = (width + kTile - 1) / kTile, tiles_y = (height + kTile - 1) / kTile;
  const int tile_count = tiles_x * tiles_y;

  std::mutex merge;
  std::atomic<int> done{0};
  const auto start = std::chrono::steady_clock::now();
  auto render_tile = [&](int tile) {
    RayStats stats;
    const int x0 = (tile % tiles_x) * kTile, y0 = (tile / tiles_x) * kTile;
    for (int y = y0; y < std::min(y0 + kTile, height); ++y) {
      for (int x = x0; x < std::min(x0 + kTile, width); ++x) {
        const std::uint64_t pixel = std::uint64_t(y) * width + x;
        glm::vec3 sum(0.0f);
        for (int s = 0; s < options.spp; ++s) {
          Rng rng(options.seed, pixel * std::uint64_t(options.spp) + s);
          const glm::vec2 j = jitter(s, options.spp, rng);
          const auto r = camera.ray(float(x) + j.x, float(y) + j.y);
          const Ray ray{{r.org.x, r.org.y, r.org.z}, r.tmin, {r.dir.x, r.dir.y, r.dir.z}, r.tmax};
          stats.add(RayKind::primary);
          const glm::vec3 c = options.integrator == IntegratorKind::path
                                  ? trace_path(scene, ray, options.max_depth, rng, stats)
                                  : trace_whitted(scene, ray, options.max_depth, stats);
          // A NaN or inf sample would poison the pixel: drop it (counted as black).
          if (std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b)) sum += c;
        }
        result.image.pixels[pixel] = sum / float(options.spp);
      }
    }
    std::lock_guard lock(merge);
    result.stats += stats;
    const int n = ++done;
    if (options.progress) options.progress(double(n) / tile_count);
  };

  const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(threads);
  arena.execute([&] {
    tbb::parallel_for(0, tile_count, [&](int tile) { render_tile(tile); }, tbb::simple_partitioner());
  });
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace volley::render
