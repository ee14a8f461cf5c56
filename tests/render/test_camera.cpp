// The notes' camera model: pixel (i, j) -> (wl + i du, wt + j dv, f) -> [u v w] p + e.
#include <doctest/doctest.h>

#include <cmath>
#include <initializer_list>

#include "render/camera.h"

using volley::core::Camera;

TEST_CASE("camera: corner pixels land exactly on the window corners") {
  // Axis-aligned basis and dyadic window values: every step is exact in float.
  const Camera cam({1, 2, 3}, {1, 0, 0}, {0, 1, 0}, {0, 0, -1}, 2.0f, -0.5f, 0.75f, 0.25f, -1.0f, 5, 9);
  const glm::vec3 e(1, 2, 3);
  CHECK(cam.pixel_point(0, 0) == e + glm::vec3(-0.5f, 0.25f, -2.0f));     // (wl, wt)
  CHECK(cam.pixel_point(4, 0) == e + glm::vec3(0.75f, 0.25f, -2.0f));     // (wr, wt)
  CHECK(cam.pixel_point(0, 8) == e + glm::vec3(-0.5f, -1.0f, -2.0f));     // (wl, wb)
  CHECK(cam.pixel_point(4, 8) == e + glm::vec3(0.75f, -1.0f, -2.0f));     // (wr, wb)
  // du = (wr - wl) / (nc - 1), dv = (wb - wt) / (nr - 1)
  CHECK(cam.pixel_point(1, 0).x == doctest::Approx(e.x - 0.5f + 1.25f / 4.0f));
  CHECK(cam.pixel_point(0, 1).y == doctest::Approx(e.y + 0.25f - 1.25f / 8.0f));
}

TEST_CASE("camera: the ray starts on the image plane and points away from the eye") {
  const Camera cam({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, 1.0f, -1, 1, 1, -1, 3, 3);
  const auto r = cam.ray(1, 1);  // centre pixel
  CHECK(r.org == glm::vec3(0, 0, 1));
  CHECK(r.dir == glm::vec3(0, 0, 1));  // d = p - e
  CHECK(r.tmin == 0.0f);
  CHECK(std::isinf(r.tmax));
  // r(lambda) = p + lambda (p - e)
  const auto c = cam.ray(0, 0);
  CHECK(c.org == glm::vec3(-1, 1, 1));
  CHECK(c.dir == c.org);
}

TEST_CASE("camera: the basis maps camera coordinates to world coordinates") {
  // A rotated basis: u = z, v = y, w = -x.
  const Camera cam({10, 0, 0}, {0, 0, 1}, {0, 1, 0}, {-1, 0, 0}, 1.0f, -1, 1, 1, -1, 3, 3);
  CHECK(cam.pixel_point(2, 0) == glm::vec3(9, 1, 1));  // u*wr + v*wt + w*f + e
}

TEST_CASE("camera: look_at builds an orthonormal basis and a window from the field of view") {
  const Camera cam = Camera::look_at({0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 90.0f, 201, 101);
  const glm::vec3 centre = glm::normalize(cam.ray(100, 50).dir);
  CHECK(centre.x == doctest::Approx(0.0f).epsilon(1e-6));
  CHECK(centre.y == doctest::Approx(0.0f).epsilon(1e-6));
  CHECK(centre.z == doctest::Approx(-1.0f));
  // fov 90: the top edge is 45 degrees up; the image is twice as wide as tall.
  const auto top = cam.ray(100, 0);
  CHECK(top.dir.y == doctest::Approx(-top.dir.z));
  const auto right = cam.ray(200, 50);
  CHECK(right.dir.x == doctest::Approx(-2.0f * right.dir.z * 100.0f / 101.0f).epsilon(0.02));
  CHECK(right.dir.x > 0.0f);  // u points right
}

TEST_CASE("camera: look_at puts the image plane close to the eye at any scale") {
  // The notes' rays start on the image plane: a small scene close to the eye must not be
  // clipped (a bunny of size 0.15 seen from 0.4 away).
  for (float scale : {1e-3f, 1.0f, 1e4f}) {
    const Camera cam = Camera::look_at(glm::vec3(0, 0, 0.4f) * scale, {0, 0, 0}, {0, 1, 0}, 40.0f, 64, 64);
    const auto r = cam.ray(31.5f, 31.5f);
    CHECK(glm::length(r.org - cam.eye()) == doctest::Approx(0.4e-3f * scale).epsilon(1e-3));
  }
}

TEST_CASE("camera: neighbouring pixels get their own directions with the eye far from the origin") {
  // The conference room's camera: eye at x = 1610, image plane 1e-3 from it. Directions
  // taken as p - e from the world-space point p rounded to one for whole blocks of pixels.
  const glm::vec3 eye(1610, 356, -322);
  const Camera cam = Camera::look_at(eye, {1609, 356, -322}, {0, 1, 0}, 60.0f, 512, 512);
  const float half = 1e-3f * std::tan(glm::radians(30.0f));
  const double step = 2.0 * half / 511.0;
  for (int i : {0, 1, 255, 256, 510}) {
    const auto a = cam.ray(float(i), 100.0f), b = cam.ray(float(i + 1), 100.0f);
    CHECK(a.dir != b.dir);
    // u = w x up = (-1, 0, 0) x (0, 1, 0) = (0, 0, -1): one pixel right is -step along z,
    // to within a few ulps of the coordinates (about 1e-3), not of the eye's (1610).
    CHECK(double(b.dir.z) - double(a.dir.z) == doctest::Approx(-step).epsilon(1e-3));
    CHECK(a.dir.x == doctest::Approx(-1e-3f).epsilon(1e-6));
    // The origin is the image-plane point, as pixel_point.
    CHECK(a.org == cam.pixel_point(float(i), 100.0f));
  }
}

TEST_CASE("camera: bad parameters are rejected with a message") {
  CHECK_THROWS_WITH(Camera::look_at({0, 0, 0}, {0, 0, 0}, {0, 1, 0}, 45, 8, 8), doctest::Contains("coincide"));
  CHECK_THROWS_WITH(Camera::look_at({0, 0, 0}, {0, 1, 0}, {0, 1, 0}, 45, 8, 8), doctest::Contains("parallel"));
  CHECK_THROWS_WITH(Camera::look_at({0, 0, 0}, {0, 0, 1}, {0, 1, 0}, 180, 8, 8), doctest::Contains("fov"));
  CHECK_THROWS(Camera({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, 1, -1, 1, 1, -1, 1, 8));
}
