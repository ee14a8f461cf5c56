// Sampling helpers shared by the integrators and the ray workloads.
#pragma once
#include <cmath>

#include <glm/glm.hpp>

#include "render/rng.h"

namespace volley::render {

/// Luminance of linear sRGB (Rec. 709 weights).
inline float luminance(const glm::vec3& c) { return 0.2126f * c.r + 0.7152f * c.g + 0.0722f * c.b; }

/// Cosine-weighted direction about unit normal n (Malley's method, the basis from
/// Duff et al. 2017, "Building an orthonormal basis, revisited").
inline glm::vec3 cosine_direction(const glm::vec3& n, Rng& rng) {
  const float r = std::sqrt(rng.uniform());
  const float phi = 6.28318530718f * rng.uniform();
  const float sign = std::copysign(1.0f, n.z);
  const float a = -1.0f / (sign + n.z);
  const float b = n.x * n.y * a;
  const glm::vec3 t(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
  const glm::vec3 bt(b, sign + n.y * n.y * a, -n.y);
  const float z = std::sqrt(std::max(0.0f, 1.0f - r * r));
  return glm::normalize(r * std::cos(phi) * t + r * std::sin(phi) * bt + z * n);
}

}  // namespace volley::render
