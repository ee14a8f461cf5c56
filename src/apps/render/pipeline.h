// Skip what a scene doesn't need: the stages a scene's features call for, as bits that
// select compile-time specialised shading functions and the render loop's stages once
// per render. The general pipeline (all bits) renders every scene; a specialised one
// renders only scenes without the features it leaves out, to the same image.
#pragma once
#include <string>

#include "render/scene.h"

namespace volley::render {

/// Pipeline stages that can be compiled out.
enum Stage : unsigned {
  kShadows = 1u << 0,            ///< point lights: Phong direct light and shadow rays
  kMirrors = 1u << 1,            ///< mirror reflection rays
  kRefraction = 1u << 2,         ///< refraction rays, and shadow rays that pass through
                                 ///< transmissive surfaces (closest-hit, attenuated)
  kSmoothNormals = 1u << 3,      ///< interpolated per-corner normals
  kAllStages = (1u << 4) - 1u,   ///< the general pipeline
};

/// True when a pipeline with these stages shades whole streams in SIMD lanes
/// (render/shade_batch.h): no stage that branches per hit (mirror or refraction rays) or
/// interpolates normals.
constexpr bool batch_shadable(unsigned stages) {
  return (stages & (kMirrors | kRefraction | kSmoothNormals)) == 0;
}

/// The stages `features` need.
unsigned needed_stages(const SceneFeatures& features);

/// One line per stage left out, saying why (for --stats and volley info).
std::string describe_skipped(unsigned stages, const SceneFeatures& features);

/// Whether back-face culling of occlusion rays is admissible for the scene (closed and
/// opaque, SceneFeatures::cull_admissible) and whether it is used, with the reason.
std::string describe_culling(const SceneFeatures& features);

}  // namespace volley::render
