// Mirror reflection, Snell refraction and Schlick's Fresnel approximation.
#pragma once
#include <cmath>
#include <optional>

#include <glm/glm.hpp>

namespace volley::render {

/// Reflects incoming direction d about unit normal n.
inline glm::vec3 reflect(const glm::vec3& d, const glm::vec3& n) { return d - 2.0f * glm::dot(d, n) * n; }

/// Refracts unit direction d at unit normal n (facing against d) from index eta_i into
/// eta_t by Snell's law; nothing on total internal reflection.
inline std::optional<glm::vec3> refract(const glm::vec3& d, const glm::vec3& n, float eta_i, float eta_t) {
  const float eta = eta_i / eta_t;
  const float cos_i = -glm::dot(d, n);
  const float sin2_t = eta * eta * std::max(0.0f, 1.0f - cos_i * cos_i);
  if (sin2_t >= 1.0f) return std::nullopt;
  const float cos_t = std::sqrt(1.0f - sin2_t);
  return eta * d + (eta * cos_i - cos_t) * n;
}

/// Schlick's approximation of the Fresnel reflectance for unpolarised light; cos_i is the
/// cosine on the incident side, cos_t the transmitted one (the larger angle is used, so it
/// also holds from the dense side).
inline float schlick(float cos_i, float cos_t, float eta_i, float eta_t) {
  const float r0 = (eta_i - eta_t) / (eta_i + eta_t);
  const float c = 1.0f - std::min(cos_i, cos_t);
  const float c2 = c * c;
  return r0 * r0 + (1.0f - r0 * r0) * c2 * c2 * c;
}

/// Mirror direction of d about the shading normal ns, or about the geometric normal ng
/// when the shading normal would send it below the surface.
inline glm::vec3 reflect_above(const glm::vec3& d, const glm::vec3& ns, const glm::vec3& ng) {
  const glm::vec3 r = reflect(d, ns);
  return glm::dot(r, ng) > 0.0f ? r : reflect(d, ng);
}

/// What happens to unit direction d at a dielectric surface of index `ior` (ns facing
/// against d; `front`: arriving from outside): the refracted direction and Schlick's
/// reflectance; on total internal reflection no direction and reflectance 1.
struct Refraction {
  std::optional<glm::vec3> dir;
  float reflectance;
};

inline Refraction refraction(const glm::vec3& d, const glm::vec3& ns, bool front, float ior) {
  const float eta_i = front ? 1.0f : ior;
  const float eta_t = front ? ior : 1.0f;
  const auto t = refract(d, ns, eta_i, eta_t);
  if (!t) return {std::nullopt, 1.0f};
  return {t, schlick(-glm::dot(d, ns), -glm::dot(*t, ns), eta_i, eta_t)};
}

}  // namespace volley::render
