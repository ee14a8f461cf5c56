#include "render/pipeline.h"

namespace volley::render {

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

}  // namespace volley::render
