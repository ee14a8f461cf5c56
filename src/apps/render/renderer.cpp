// The wavefront renderer: per 16x16 tile and sample, all camera rays are traced as one
// stream (in 4x4 pixel blocks, so each run of 16 is a coherent packet), the hits shaded,
// shadow rays traced as one occlusion stream, and the surviving secondary rays (dead ones
// dropped) traced as the next bounce's stream.
#include "render/renderer.h"

#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "render/path_state.h"
#include "render/pipeline.h"
#include "render/shade_batch.h"
#include "render/spawn.h"

namespace volley::render {
namespace {

constexpr int kTile = 16;
constexpr int kBlock = 4;

// Stratified sub-pixel offsets in [-0.5, 0.5): an n x n grid (n = ceil(sqrt(spp))), one
// jittered sample per used cell; the pixel centre for 1 spp (the notes' model).
glm::vec2 jitter(int sample, int spp, Rng& rng) {
  if (spp == 1) return {0.0f, 0.0f};
  const int n = int(std::ceil(std::sqrt(float(spp))));
  const int sx = sample % n, sy = sample / n;
  return {(float(sx) + rng.uniform()) / float(n) - 0.5f, (float(sy) + rng.uniform()) / float(n) - 0.5f};
}

// Buffers of one tile, reused across samples and bounces.
// One per arena slot, on its own cache lines: the slots write their stats once per tile.
struct alignas(64) TileWork {
  std::vector<PathState> paths, next;
  std::vector<ShadowQuery> shadows, passing;
  std::vector<Ray> rays;
  std::vector<Hit> hits;
  std::vector<std::uint8_t> blocked;
  std::vector<glm::vec3> sum;
  RayStats stats;
};

void trace_paths(const Accel& accel, TileWork& w) {
  const std::size_t n = w.paths.size();
  w.rays.resize(n);
  w.hits.assign(n, Hit{});
  for (std::size_t i = 0; i < n; ++i) {
    w.rays[i] = w.paths[i].ray;
    w.stats.add(w.paths[i].kind);
  }
  accel.intersect(w.rays.data(), n, w.hits.data(), 1);
}

void trace_shadows(const Accel& accel, TileWork& w) {
  const std::size_t n = w.shadows.size();
  if (n == 0) return;
  w.rays.resize(n);
  w.blocked.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) w.rays[i] = w.shadows[i].ray;
  w.stats.add(RayKind::shadow, n);
  accel.occluded(w.rays.data(), n, w.blocked.data(), 1);
  for (std::size_t i = 0; i < n; ++i)
    if (!w.blocked[i]) w.sum[w.shadows[i].pixel] += w.shadows[i].contribution;
}

// Shadow rays that may pass through transmissive surfaces (the refraction stage): traced
// closest-hit; a transmissive hit attenuates the light by its transmittance and the ray
// goes on from just past it toward the light; any other hit blocks it.
void trace_shadows_through(const Scene& scene, TileWork& w) {
  constexpr int kMaxSurfaces = 16;
  for (int pass = 0; pass < kMaxSurfaces && !w.shadows.empty(); ++pass) {
    const std::size_t n = w.shadows.size();
    w.rays.resize(n);
    w.hits.assign(n, Hit{});
    for (std::size_t i = 0; i < n; ++i) w.rays[i] = w.shadows[i].ray;
    w.stats.add(RayKind::shadow, n);
    scene.accel().intersect(w.rays.data(), n, w.hits.data(), 1);
    w.passing.clear();
    for (std::size_t i = 0; i < n; ++i) {
      ShadowQuery q = w.shadows[i];
      if (!w.hits[i].hit()) {
        w.sum[q.pixel] += q.contribution;
        continue;
      }
      const SurfacePoint s = scene.surface_as<false>(q.ray, w.hits[i]);
      const glm::vec3 t = scene.materials()[s.material].transmittance;
      if (t == glm::vec3(0.0f)) continue;  // opaque: blocked
      const glm::vec3 light(q.ray.org[0] + q.ray.dir[0], q.ray.org[1] + q.ray.dir[1], q.ray.org[2] + q.ray.dir[2]);
      q.ray = spawn_shadow_ray(s.p, s.p_error, s.ng, light);
      q.contribution *= t;
      w.passing.push_back(q);
    }
    std::swap(w.shadows, w.passing);
  }
}

// The pipeline a render runs, chosen once (render/pipeline.h).
struct Pipeline {
  unsigned stages;     ///< bits of Stage
  ShadeFn shade;       ///< shading compiled for those stages, one hit at a time
  bool batch;          ///< shade whole streams in SIMD lanes (shade_batch.h)
  BatchShading lanes;  ///< how, when batch
};

void render_tile(const Scene& scene, const RenderOptions& options, const Pipeline& pipeline, int x0, int y0,
                 TileWork& w, Image& image) {
  const core::Camera& camera = scene.camera();
  const int x1 = std::min(x0 + kTile, camera.width()), y1 = std::min(y0 + kTile, camera.height());
  w.sum.assign(kTile * kTile, glm::vec3(0.0f));
  for (int s = 0; s < options.spp; ++s) {
    // Camera rays in 4x4 pixel blocks.
    w.paths.clear();
    for (int by = y0; by < y1; by += kBlock)
      for (int bx = x0; bx < x1; bx += kBlock)
        for (int y = by; y < std::min(by + kBlock, y1); ++y)
          for (int x = bx; x < std::min(bx + kBlock, x1); ++x) {
            const std::uint64_t pixel = std::uint64_t(y) * camera.width() + x;
            PathState p;
            p.rng = Rng(options.seed, pixel * std::uint64_t(options.spp) + s);
            const glm::vec2 j = jitter(s, options.spp, p.rng);
            const auto r = camera.ray(float(x) + j.x, float(y) + j.y);
            p.ray = Ray{{r.org.x, r.org.y, r.org.z}, r.tmin, {r.dir.x, r.dir.y, r.dir.z}, r.tmax};
            p.pixel = std::uint32_t((y - y0) * kTile + (x - x0));
            w.paths.push_back(p);
          }
    // Bounces until no ray survives.
    while (!w.paths.empty()) {
      trace_paths(scene.accel(), w);
      w.next.clear();
      w.shadows.clear();
      if (pipeline.batch) {
        shade_batch(scene, pipeline.lanes, w.paths.data(), w.hits.data(), w.paths.size(), options.max_depth, w.next,
                    w.shadows, w.sum.data());
      } else {
        for (std::size_t i = 0; i < w.paths.size(); ++i) {
          const PathState& p = w.paths[i];
          w.sum[p.pixel] += pipeline.shade(scene, p, w.hits[i], options.max_depth, w.next, w.shadows);
        }
      }
      if (pipeline.stages & kRefraction)
        trace_shadows_through(scene, w);
      else
        trace_shadows(scene.accel(), w);
      std::swap(w.paths, w.next);
    }
  }
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      glm::vec3 c = w.sum[(y - y0) * kTile + (x - x0)] / float(options.spp);
      // A NaN or inf would poison the image: show it black rather than propagate it.
      if (!(std::isfinite(c.r) && std::isfinite(c.g) && std::isfinite(c.b))) c = glm::vec3(0.0f);
      image.pixels[std::size_t(y) * image.width + x] = c;
    }
}

}  // namespace

RenderResult render(const Scene& scene, const RenderOptions& options) {
  const core::Camera& camera = scene.camera();
  const int width = camera.width(), height = camera.height();
  RenderResult result;
  result.image = {width, height, std::vector<glm::vec3>(std::size_t(width) * height)};
  const int tiles_x = (width + kTile - 1) / kTile, tiles_y = (height + kTile - 1) / kTile;
  const int tile_count = tiles_x * tiles_y;

  const unsigned stages = options.specialize ? needed_stages(scene.features()) : kAllStages;
  const bool whitted = options.integrator == IntegratorKind::whitted;
  const ShadeFn shade = whitted ? whitted_shader(stages) : path_shader(stages);
  // Lanes as wide as the traversal kernels' ISA (the scalar oracle shades in SSE4.2 lanes).
  const BatchShading lanes{stages, shade, whitted ? whitted_continuation(stages) : path_continuation(stages),
                           continuation_reads_surface(options.integrator, stages), scene.accel().info().isa};
  const Pipeline pipeline{stages, shade, batch_shadable(stages), lanes};
  std::mutex merge;
  int done = 0;
  const auto start = std::chrono::steady_clock::now();
  const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(threads);
  // Scratch per arena slot in plain std allocations, not tbb::enumerable_thread_specific, whose
  // allocator ThreadSanitizer cannot see (a reused block reads as a race between two renders).
  std::vector<TileWork> work_per_slot(static_cast<std::size_t>(threads));
  arena.execute([&] {
    tbb::parallel_for(
        0, tile_count,
        [&](int tile) {
          TileWork& work = work_per_slot[std::size_t(tbb::this_task_arena::current_thread_index())];
          work.stats = RayStats{};
          render_tile(scene, options, pipeline, (tile % tiles_x) * kTile, (tile / tiles_x) * kTile, work,
                      result.image);
          std::lock_guard lock(merge);
          result.stats += work.stats;
          ++done;
          if (options.progress) options.progress(double(done) / tile_count);
        },
        tbb::simple_partitioner());
  });
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.stages = pipeline.stages;
  result.batch_shaded = pipeline.batch;
  return result;
}

}  // namespace volley::render
