// PNG output of linear RGB images, and PNG input for reference-image tests.
#pragma once
#include <filesystem>
#include <vector>

#include <glm/glm.hpp>

namespace volley::io {

/// sRGB transfer function (IEC 61966-2-1): linear [0, 1] → encoded [0, 1].
float linear_to_srgb(float linear);
/// Its inverse: encoded [0, 1] → linear [0, 1].
float srgb_to_linear(float encoded);

/// Writes `linear_rgb` (width * height pixels, row-major, top row first) as an 8-bit
/// RGB PNG: each channel clamped to [0, 1] (NaN → 0), sRGB-encoded, rounded to the
/// nearest of 0..255. Creates the parent folder when missing. Throws
/// std::invalid_argument when the sizes do not match, std::runtime_error (message
/// `FILE: cannot write PNG (...)`) when the file cannot be written.
void write_png(const std::filesystem::path& file, int width, int height, const std::vector<glm::vec3>& linear_rgb);

/// Reads a PNG (any bit depth / channel count stb_image accepts; alpha dropped, grey
/// expanded) and returns its pixels as linear RGB, row-major, top row first; sets
/// `width` and `height`. Throws LoadError when the file is missing or not an image.
std::vector<glm::vec3> read_png_linear(const std::filesystem::path& file, int& width, int& height);

}  // namespace volley::io
