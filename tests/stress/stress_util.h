// Shared helpers of the numerical stress suite (ACCURACY.md, stress catalogue): the ISA
// list (scalar oracle + every SIMD ISA this CPU has), the query modes of the public API
// (single ray, packets of K = 4, 8, 16, streams), a double-precision ray/triangle reference,
// a tiny indexed-mesh type, and the VOLLEY_STRESS_LONG switch.
#pragma once
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include "simd/dispatch.h"
#include "volley/accel.h"
#include "volley/packet.h"

namespace stress {

using volley::Accel;
using volley::Hit;
using volley::Isa;
using volley::Ray;
using volley::TriangleTest;

inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
inline constexpr TriangleTest kTests[] = {TriangleTest::plane, TriangleTest::moller, TriangleTest::watertight};

/// True when VOLLEY_STRESS_LONG=1: cases run millions of rays instead of thousands.
inline bool long_mode() {
  const char* v = std::getenv("VOLLEY_STRESS_LONG");
  return v != nullptr && std::string(v) == "1";
}

/// The scalar oracle and every SIMD ISA this CPU runs (a MESSAGE names the missing ones once).
inline const std::vector<Isa>& isas() {
  static const std::vector<Isa> list = [] {
    std::vector<Isa> out{Isa::scalar};
    for (Isa isa : {Isa::sse42, Isa::avx2, Isa::avx512}) {
      if (volley::simd::cpu_has(isa))
        out.push_back(isa);
      else
        MESSAGE("stress: this CPU lacks " << std::string(volley::to_string(isa)) << ", not tested");
    }
    return out;
  }();
  return list;
}

inline std::string name(Isa isa) { return std::string(volley::to_string(isa)); }
inline std::string name(TriangleTest t) { return std::string(volley::to_string(t)); }

/// How rays are handed to the Accel.
enum class Mode { single, packet4, packet8, packet16, stream };
inline constexpr Mode kModes[] = {Mode::single, Mode::packet4, Mode::packet8, Mode::packet16, Mode::stream};
inline std::string name(Mode m) {
  switch (m) {
    case Mode::single: return "single";
    case Mode::packet4: return "packet4";
    case Mode::packet8: return "packet8";
    case Mode::packet16: return "packet16";
    case Mode::stream: return "stream";
  }
  return "?";
}

/// Closest hits and occlusion flags of `rays`, in one mode.
struct Answers {
  std::vector<Hit> hits;
  std::vector<std::uint8_t> occluded;
};

template <int K>
void trace_packets(const Accel& accel, const std::vector<Ray>& rays, Answers& out) {
  volley::RayPacket<K> p;
  volley::HitPacket<K> h;
  for (std::size_t first = 0; first < rays.size(); first += K) {
    const int count = static_cast<int>(std::min<std::size_t>(K, rays.size() - first));
    volley::load(p, rays.data() + first, count);
    volley::reset(h);
    accel.intersect(p, h);
    const std::uint32_t mask = accel.occluded(p);
    volley::store(h, out.hits.data() + first, count);
    for (int i = 0; i < count; ++i) out.occluded[first + i] = (mask >> i) & 1u;
    // Inactive lanes are never reported occluded.
    if ((mask & ~volley::lane_bits(count)) != 0u) FAIL("occlusion mask sets an inactive lane");
  }
}

/// Traces `rays` through `accel` in `mode` (closest hit and occlusion).
inline Answers trace(const Accel& accel, const std::vector<Ray>& rays, Mode mode) {
  Answers a;
  a.hits.resize(rays.size());
  a.occluded.assign(rays.size(), 0);
  switch (mode) {
    case Mode::single:
      for (std::size_t i = 0; i < rays.size(); ++i) {
        a.hits[i] = accel.intersect(rays[i]);
        a.occluded[i] = accel.occluded(rays[i]) ? 1 : 0;
      }
      break;
    case Mode::packet4: trace_packets<4>(accel, rays, a); break;
    case Mode::packet8: trace_packets<8>(accel, rays, a); break;
    case Mode::packet16: trace_packets<16>(accel, rays, a); break;
    case Mode::stream:
      accel.intersect(rays.data(), rays.size(), a.hits.data());
      accel.occluded(rays.data(), rays.size(), a.occluded.data());
      break;
  }
  return a;
}

/// double -> float, rounded to nearest. Through a volatile: GCC 12.2 at -O2 folds
/// `double(float(x + c)) - c` to `double(float(x))` for some lanes of a loop (the rounding
/// of x + c is lost; reproduced with a 10-line program), which put "interior" origins on
/// the surface of meshes moved to 1e7.
inline float to_float(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}

/// An indexed triangle mesh (float positions, shared vertices).
struct Mesh {
  std::vector<float> xyz;
  std::vector<std::uint32_t> idx;
  std::size_t vertices() const { return xyz.size() / 3; }
  std::size_t triangles() const { return idx.size() / 3; }
  std::uint32_t vertex(double x, double y, double z) {
    xyz.insert(xyz.end(), {to_float(x), to_float(y), to_float(z)});
    return static_cast<std::uint32_t>(vertices() - 1);
  }
  void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c) { idx.insert(idx.end(), {a, b, c}); }
  std::array<double, 3> position(std::uint32_t v) const { return {xyz[3 * v], xyz[3 * v + 1], xyz[3 * v + 2]}; }
  /// A copy moved by `offset` on every axis (positions rounded to float).
  Mesh translated(float offset) const {
    Mesh m = *this;
    for (float& c : m.xyz) c = c + offset;
    return m;
  }
  Accel accel(TriangleTest test, Isa isa) const {
    Accel a;
    a.add_triangles(xyz.data(), vertices(), idx.data(), triangles());
    a.commit({test, isa});
    return a;
  }
};

inline Ray make_ray(const float o[3], const float d[3], float tmin = 0.0f, float tmax = kInf) {
  return Ray{{o[0], o[1], o[2]}, tmin, {d[0], d[1], d[2]}, tmax};
}

/// Double-precision ray/triangle reference (Moller-Trumbore in double, t unclamped): the
/// ray parameter t and the barycentrics of the intersection of the ray's line with the
/// triangle's plane. `ok` is false when the ray is parallel to the plane (det == 0).
struct RefHit {
  bool ok = false;
  double t = 0, u = 0, v = 0;
  bool inside(double margin = 0.0) const { return ok && u >= margin && v >= margin && 1.0 - u - v >= margin; }
};
inline RefHit reference(const Ray& r, const std::array<double, 3>& p0, const std::array<double, 3>& p1,
                        const std::array<double, 3>& p2) {
  using V = std::array<double, 3>;
  const auto sub = [](const V& a, const V& b) { return V{a[0] - b[0], a[1] - b[1], a[2] - b[2]}; };
  const auto cross = [](const V& a, const V& b) {
    return V{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  };
  const auto dot = [](const V& a, const V& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; };
  const V o{r.org[0], r.org[1], r.org[2]}, d{r.dir[0], r.dir[1], r.dir[2]};
  const V e1 = sub(p1, p0), e2 = sub(p2, p0);
  const V p = cross(d, e2);
  const double det = dot(e1, p);
  RefHit h;
  if (det == 0.0) return h;
  const V s = sub(o, p0);
  const V q = cross(s, e1);
  h.ok = true;
  h.u = dot(s, p) / det;
  h.v = dot(d, q) / det;
  h.t = dot(e2, q) / det;
  return h;
}

/// Observed signs and decades of a generated quantity (stress item 14: generators check
/// that they cover what they claim to).
struct Coverage {
  bool negative = false, positive = false, neg_zero = false, pos_zero = false;
  int min_decade = 1000, max_decade = -1000;
  void add(double x) {
    if (x == 0.0) {
      (std::signbit(x) ? neg_zero : pos_zero) = true;
      return;
    }
    (x < 0 ? negative : positive) = true;
    if (std::isfinite(x)) {
      const int d = static_cast<int>(std::floor(std::log10(std::fabs(x))));
      min_decade = std::min(min_decade, d);
      max_decade = std::max(max_decade, d);
    }
  }
};

}  // namespace stress
