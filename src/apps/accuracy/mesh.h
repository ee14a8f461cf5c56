// An indexed triangle mesh with float positions, as the accuracy runner and the stress
// suite generate it, and the two float helpers every generator needs.
#pragma once
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "volley/accel.h"

namespace volley::accuracy {

inline constexpr float kInf = std::numeric_limits<float>::infinity();

/// double -> float, rounded to nearest. Through a volatile: GCC 12.2 at -O2 folds
/// `double(float(x + c)) - c` to `double(float(x))` for some lanes of a loop (the rounding
/// of x + c is lost; reproduced with a 10-line program), which put "interior" origins on
/// the surface of meshes moved to 1e7.
inline float to_float(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}

inline Ray make_ray(const float o[3], const float d[3], float tmin = 0.0f, float tmax = kInf) {
  return Ray{{o[0], o[1], o[2]}, tmin, {d[0], d[1], d[2]}, tmax};
}

/// An indexed triangle mesh (float positions, shared vertices).
struct Mesh {
  std::vector<float> xyz;          ///< 3 floats per vertex
  std::vector<std::uint32_t> idx;  ///< 3 vertex indices per triangle
  std::size_t vertices() const { return xyz.size() / 3; }
  std::size_t triangles() const { return idx.size() / 3; }
  /// Appends a vertex (rounded to float); returns its index.
  std::uint32_t vertex(double x, double y, double z) {
    xyz.insert(xyz.end(), {to_float(x), to_float(y), to_float(z)});
    return static_cast<std::uint32_t>(vertices() - 1);
  }
  void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) { idx.insert(idx.end(), {a, b, c}); }
  /// Vertex v widened to double (exact).
  std::array<double, 3> position(std::uint32_t v) const { return {xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]}; }
  /// Corner k (0..2) of triangle t, widened to double.
  std::array<double, 3> corner(std::uint32_t t, int k) const { return position(idx[3 * t + k]); }
  /// A copy moved by `offset` on every axis (positions rounded to float).
  Mesh translated(float offset) const {
    Mesh m = *this;
    for (float& c : m.xyz) c = c + offset;
    return m;
  }
  /// A committed Accel over this mesh.
  Accel accel(const Options& options) const {
    Accel a;
    a.add_triangles(xyz.data(), vertices(), idx.data(), triangles());
    a.commit(options);
    return a;
  }
  Accel accel(TriangleTest test, Isa isa) const {
    Options o;
    o.test = test;
    o.isa = isa;
    return accel(o);
  }
};

}  // namespace volley::accuracy
