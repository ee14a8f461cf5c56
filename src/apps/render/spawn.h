// Spawning secondary rays without re-hitting the surface they leave: the origin is moved
// off the surface by the hit point's rounding-error bound along the normal, then rounded
// away from it (pbrt-v4's OffsetRayOrigin; Pharr, Jakob, Humphreys 2023, 6.8.6).
// A fixed epsilon fails at large and small scales (docs/accuracy.md).
#pragma once
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include <glm/glm.hpp>

#include "core/rounding.h"
#include "volley/ray.h"

namespace volley::render {

/// The point of a triangle hit from its barycentrics, and in `error` the bound of its
/// rounding per axis (pbrt, Pharr et al., 4th ed., 6.8) plus what a ray leaving it costs the
/// triangle test: that test's own rounding grows with the farthest vertex (a wall 500
/// units long was re-hit at t = -0 from 7e-5 off its plane without this term).
inline glm::vec3 hit_point(const glm::vec3& p0, const glm::vec3& p1, const glm::vec3& p2, float u, float v,
                           glm::vec3& error) {
  const float b0 = 1.0f - u - v;
  const glm::vec3 p = b0 * p0 + u * p1 + v * p2;
  error = core::rounding_gamma(7) * (glm::abs(b0 * p0) + glm::abs(u * p1) + glm::abs(v * p2));
  const glm::vec3 reach = glm::max(glm::abs(p0 - p), glm::max(glm::abs(p1 - p), glm::abs(p2 - p)));
  error += glm::vec3(core::rounding_gamma(8) * std::max(reach.x, std::max(reach.y, reach.z)));
  return p;
}

/// std::nextafter(x, +inf) (Up) or (x, -inf), on the bit pattern: the same result, without
/// a libm call per coordinate of every spawned ray.
template <bool Up>
inline float next_float(float x) {
  if (!std::isfinite(x))
    return std::nextafter(x, Up ? std::numeric_limits<float>::infinity() : -std::numeric_limits<float>::infinity());
  if (x == 0.0f) return Up ? std::numeric_limits<float>::denorm_min() : -std::numeric_limits<float>::denorm_min();
  const std::uint32_t bits = std::bit_cast<std::uint32_t>(x);
  // Away from zero adds one to the magnitude, toward zero subtracts one.
  return std::bit_cast<float>((x > 0.0f) == Up ? bits + 1u : bits - 1u);
}

/// Origin for a ray leaving point p (error bound p_error, geometric normal n) toward w.
inline glm::vec3 offset_origin(const glm::vec3& p, const glm::vec3& p_error, const glm::vec3& n, const glm::vec3& w) {
  // A floor of two roundings of the largest coordinate: a point on an axis-aligned plane
  // through 0 (a floor at y = 0) has an exactly zero bound along its normal, yet the ray
  // test still rounds in terms of the other coordinates and would find t = 0 on it.
  const glm::vec3 a = glm::abs(p);
  const glm::vec3 err = p_error + glm::vec3(core::rounding_gamma(2) * std::max(a.x, std::max(a.y, a.z)));
  const float side = glm::dot(w, n) < 0.0f ? -1.0f : 1.0f;
  const glm::vec3 offset = side * glm::dot(glm::abs(n), err) * n;
  glm::vec3 po = p + offset;
  // Round away from p so the rounding of the addition cannot pull the origin back.
  for (int i = 0; i < 3; ++i) {
    if (offset[i] > 0.0f)
      po[i] = next_float<true>(po[i]);
    else if (offset[i] < 0.0f)
      po[i] = next_float<false>(po[i]);
  }
  return po;
}

/// A ray from a surface point in direction w, searched over [0, tmax).
inline Ray spawn_ray(const glm::vec3& p, const glm::vec3& p_error, const glm::vec3& n, const glm::vec3& w,
                     float tmax = std::numeric_limits<float>::infinity()) {
  const glm::vec3 o = offset_origin(p, p_error, n, w);
  return Ray{{o.x, o.y, o.z}, 0.0f, {w.x, w.y, w.z}, tmax};
}

/// A shadow ray from a surface point to a light position: direction = light - origin,
/// so the light sits at t = 1 and the half-open interval [0, 1) stops short of it.
inline Ray spawn_shadow_ray(const glm::vec3& p, const glm::vec3& p_error, const glm::vec3& n, const glm::vec3& light) {
  const glm::vec3 o = offset_origin(p, p_error, n, light - p);
  const glm::vec3 d = light - o;
  return Ray{{o.x, o.y, o.z}, 0.0f, {d.x, d.y, d.z}, 1.0f};
}

}  // namespace volley::render
