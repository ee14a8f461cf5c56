// Float rounding-error bounds, shared by the oracle's slab test (bvh_traverse.h), the
// renderer's spawn code and its SIMD shading kernels. No GLM: per-ISA files include it.
#pragma once

namespace volley::core {

/// pbrt's gamma(n) = n u / (1 - n u) with u = 2^-24, the unit roundoff of float: bounds
/// the relative error of n chained float operations (Pharr, Jakob, Humphreys, PBR 3rd
/// ed., sec. 3.9.1).
constexpr float rounding_gamma(int n) {
  constexpr float u = 0x1p-24f;
  return static_cast<float>(n) * u / (1.0f - static_cast<float>(n) * u);
}

}  // namespace volley::core
