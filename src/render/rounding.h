// Higham's rounding-error bound, shared by the scalar spawn code (spawn.h) and the SIMD
// shading kernels (shade_lanes.h, which must not include GLM).
#pragma once
#include <limits>

namespace volley::render {

/// Higham's gamma(n) = n u / (1 - n u), u = 2^-24: bound on n float roundings.
constexpr float gamma(int n) {
  constexpr float u = std::numeric_limits<float>::epsilon() * 0.5f;
  return (float(n) * u) / (1.0f - float(n) * u);
}

}  // namespace volley::render
