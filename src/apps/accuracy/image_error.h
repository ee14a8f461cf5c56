// Image error: a scene rendered with each configuration against a double-precision scalar
// reference render (Isa::scalar, watertight, reference_double).
#pragma once
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "volley/options.h"

namespace volley::accuracy {

struct ImageRow {
  std::string scene;  ///< file name of the scene
  TriangleTest test = TriangleTest::watertight;
  Isa isa = Isa::scalar;
  bool reference = false;  ///< the reference render itself
  int width = 0, height = 0;
  double seconds = 0;  ///< render loop, one thread
  double rmse = 0;     ///< over sRGB-encoded channels in [0, 1] (what the PNG shows)
  double psnr = 0;     ///< 20 log10(1 / rmse) dB; +inf when identical
  std::size_t nan_pixels = 0;
};

/// Renders `scene_file` at size x size, 1 spp, one thread, with the reference and then every
/// (test, ISA) with robust traversal; one row per render, the reference first.
std::vector<ImageRow> image_error(const std::filesystem::path& scene_file, const std::filesystem::path& scenes_dir,
                                  int size, const std::vector<TriangleTest>& tests, const std::vector<Isa>& isas,
                                  const std::function<void()>& step);

}  // namespace volley::accuracy
