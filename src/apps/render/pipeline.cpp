#include "render/pipeline.h"

#include <string>

namespace volley::render {
namespace {

// Why the renderer does not cull back faces for occlusion rays even where it may: culling
// measured faster (perf/reports/specialize.md), but the SIMD occlusion kernels have no culling
// variant to choose.
constexpr const char* kCullingNotUsed =
    "the SIMD occlusion kernels have no culling variant yet (an experimental one measured 12-15% less occlusion "
    "time, 3-4% of the render, same image, on dragon_100k: perf/reports/specialize.md)";

}  // namespace

unsigned needed_stages(const SceneFeatures& f) {
  unsigned stages = 0;
  if (f.lights) stages |= kShadows;
  if (f.mirrors) stages |= kMirrors;
  if (f.refraction) stages |= kRefraction;
  if (f.smooth_normals) stages |= kSmoothNormals;
  return stages;
}

std::string describe_skipped(unsigned stages, const SceneFeatures& f) {
  std::string out;
  auto add = [&](const char* what) { out += out.empty() ? what : std::string(", ") + what; };
  if (!(stages & kShadows)) add("shadow rays and direct light (no point lights)");
  if (!(stages & kMirrors)) add("reflection rays (no mirror materials)");
  if (!(stages & kRefraction))
    add("refraction rays; shadow rays use any-hit occlusion (no transmissive materials)");
  if (!(stages & kSmoothNormals)) add("normal interpolation (no per-corner normals)");
  if (!f.polygons) add("polygon tests (no polygons)");
  if (batch_shadable(stages))
    add("one-at-a-time shading (no per-hit branches: surface points and direct light are computed for "
        "several hits at once in SIMD lanes)");
  return out.empty() ? "nothing (the scene uses every stage)" : out;
}

std::string describe_culling(const SceneFeatures& f) {
  if (f.cull_admissible())
    return "back-face culling admissible (all geometry closed, all materials opaque), not used: " +
           std::string(kCullingNotUsed);
  std::string why;
  if (!f.closed) why = "open geometry (" + std::to_string(f.open_edges) + " edges without one opposite partner)";
  if (f.refraction) why += std::string(why.empty() ? "" : ", ") + "transmissive materials";
  return "back-face culling not admissible: " + why;
}

}  // namespace volley::render
