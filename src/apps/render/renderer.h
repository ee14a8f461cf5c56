// Image rendering: 16x16 tiles spread over oneTBB worker threads, jittered supersampling,
// deterministic for a given seed whatever the thread count.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include <glm/glm.hpp>

#include "render/integrator.h"
#include "render/scene.h"
#include "render/stats.h"

namespace volley::render {

struct RenderOptions {
  int spp = 1;                 ///< samples per pixel; 1 = the pixel centre, more = stratified jitter
  int max_depth = 5;           ///< bounces after the primary hit
  IntegratorKind integrator = IntegratorKind::whitted;
  std::uint64_t seed = 1;
  int threads = 0;             ///< 0 = all hardware threads
  /// Run only the stages the scene needs (render/pipeline.h); false: the general pipeline,
  /// which gives the same image, to measure what specialising saves.
  bool specialize = true;
  /// Called now and then with the fraction of tiles done (from any thread, serialised).
  std::function<void(double)> progress;
};

struct Image {
  int width = 0;
  int height = 0;
  std::vector<glm::vec3> pixels;  ///< linear RGB, row-major from the top-left
};

struct RenderResult {
  Image image;
  RayStats stats;
  double seconds = 0.0;  ///< wall time of the render loop (not scene loading or building)
  unsigned stages = 0;   ///< pipeline stages that ran (bits of render::Stage)
  bool batch_shaded = false;  ///< hits shaded in SIMD lanes (render/shade_batch.h)
};

/// Renders the scene through its camera (image size = the camera's).
RenderResult render(const Scene& scene, const RenderOptions& options);

}  // namespace volley::render
