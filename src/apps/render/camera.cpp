#include "render/camera.h"

#include <cmath>
#include <stdexcept>

namespace volley::core {

Camera::Camera(const glm::vec3& eye, const glm::vec3& u, const glm::vec3& v, const glm::vec3& w,
               float f, float wl, float wr, float wt, float wb, int width, int height)
    : e_(eye), u_(u), v_(v), w_(w), f_(f), wl_(wl), wt_(wt), nc_(width), nr_(height) {
  if (width < 2 || height < 2) throw std::invalid_argument("camera: image must be at least 2x2 pixels");
  // The notes' pixel spacing: corners land exactly on the window corners.
  du_ = (wr - wl) / float(width - 1);
  dv_ = (wb - wt) / float(height - 1);
}

Camera Camera::look_at(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& up,
                       float fov_deg, int width, int height) {
  glm::vec3 w = target - eye;
  if (!(glm::length(w) > 0.0f)) throw std::invalid_argument("camera: eye and look_at coincide");
  const float f = 1e-3f * glm::length(w);
  w = glm::normalize(w);
  glm::vec3 u = glm::cross(w, up);
  if (!(glm::length(u) > 0.0f)) throw std::invalid_argument("camera: up is parallel to the view direction");
  u = glm::normalize(u);
  const glm::vec3 v = glm::cross(u, w);
  if (!(fov_deg > 0.0f && fov_deg < 180.0f)) throw std::invalid_argument("camera: fov must be in (0, 180) degrees");
  const float half_h = f * std::tan(glm::radians(fov_deg) * 0.5f);
  const float half_w = half_h * float(width) / float(height);
  return Camera(eye, u, v, w, f, -half_w, half_w, half_h, -half_h, width, height);
}

glm::vec3 Camera::offset(float i, float j) const {
  // Camera coordinates (wl + i du, wt + j dv, f), then [u v w] p.
  const float pu = wl_ + i * du_;
  const float pv = wt_ + j * dv_;
  return u_ * pu + v_ * pv + w_ * f_;
}

glm::vec3 Camera::pixel_point(float i, float j) const { return offset(i, j) + e_; }

RayT<float> Camera::ray(float i, float j) const {
  // The direction is p - e formed before the eye is added, not subtracted back out of the
  // world-space point: that difference keeps only the digits of p below the eye's, and
  // with the eye far from the origin and the image plane close to it (look_at: 1e-3 of the
  // target distance), neighbouring pixels rounded to one direction (the conference room's
  // camera at x = 1610 gave 1,521 distinct directions for 512 x 512 pixels).
  const glm::vec3 d = offset(i, j);
  return {d + e_, 0.0f, d, INFINITY};
}

}  // namespace volley::core
