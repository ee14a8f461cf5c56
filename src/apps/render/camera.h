// The course notes' pinhole camera: eye e, orthonormal basis u v w (w points into the
// scene), image plane at e + f w, window [wl, wr] x [wt, wb] in camera coordinates.
#pragma once
#include "core/geometry.h"

namespace volley::core {

class Camera {
 public:
  /// The notes' form. `u`, `v`, `w` need not be unit length (they are used as given),
  /// `width`/`height` are nc/nr (>= 2 each, so the pixel spacing is defined).
  Camera(const glm::vec3& eye, const glm::vec3& u, const glm::vec3& v, const glm::vec3& w,
         float f, float wl, float wr, float wt, float wb, int width, int height);

  /// Look-at form on top of the notes' one: w = normalize(target - eye), u = w x up,
  /// v = u x w, window from the vertical field of view and the aspect ratio. The image
  /// plane (where the notes' rays start) sits at f = 1e-3 |target - eye|, so nothing
  /// between the eye and the target is clipped whatever the scene's units.
  static Camera look_at(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& up,
                        float fov_deg, int width, int height);

  /// Ray through the image-plane point of pixel coordinates (i, j): i in [0, nc-1] left to
  /// right, j in [0, nr-1] top to bottom; fractional values give sub-pixel (jittered)
  /// samples. p = (wl + i du, wt + j dv, f) in camera coordinates, r(l) = p + l (p - e),
  /// tmin = 0, tmax = inf. The direction p - e is [u v w] p, rounded once per product and
  /// sum, whatever the eye's distance from the world's origin; the origin is that plus e.
  RayT<float> ray(float i, float j) const;

  /// Image-plane point of pixel (i, j) in world coordinates (the ray origin).
  glm::vec3 pixel_point(float i, float j) const;

  int width() const { return nc_; }
  int height() const { return nr_; }
  const glm::vec3& eye() const { return e_; }

 private:
  /// [u v w] (wl + i du, wt + j dv, f): the image-plane point relative to the eye.
  glm::vec3 offset(float i, float j) const;

  glm::vec3 e_, u_, v_, w_;
  float f_, wl_, wt_, du_, dv_;
  int nc_, nr_;
};

}  // namespace volley::core
