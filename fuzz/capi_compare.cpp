#include "capi_compare.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "core/triangle.h"

namespace fuzz_capi {
namespace {

bool within_ulps(float a, float b, int ulps) {
  if (a == b) return true;
  if (!std::isfinite(a) || !std::isfinite(b) || std::signbit(a) != std::signbit(b)) return false;
  std::int32_t ia, ib;
  std::memcpy(&ia, &a, 4);
  std::memcpy(&ib, &b, 4);
  return std::abs(static_cast<std::int64_t>(ia) - ib) <= ulps;
}

/// A coordinate the exact check can take: a multiple of 1/16 of magnitude at most 1024.
bool tame(float x) {
  const float scaled = x * 16.0f;
  return std::fabs(x) <= 1024.0f && scaled == std::floor(scaled);
}

/// Whether `r` hits triangle (a, b, c) well inside, decided exactly (tame input: every
/// product and sum below is exact in double); its t in `t` then.
bool robust_hit(const volley_ray& r, const float* a, const float* b, const float* c, double& t) {
  for (int k = 0; k < 3; ++k)
    if (!tame(a[k]) || !tame(b[k]) || !tame(c[k]) || !tame(r.org[k]) || !tame(r.dir[k])) return false;
  double e1[3], e2[3], s[3], d[3];
  for (int k = 0; k < 3; ++k) e1[k] = b[k] - a[k], e2[k] = c[k] - a[k], s[k] = r.org[k] - a[k], d[k] = r.dir[k];
  auto cross = [](const double* x, const double* y, double* out) {
    out[0] = x[1] * y[2] - x[2] * y[1], out[1] = x[2] * y[0] - x[0] * y[2], out[2] = x[0] * y[1] - x[1] * y[0];
  };
  auto dot = [](const double* x, const double* y) { return x[0] * y[0] + x[1] * y[1] + x[2] * y[2]; };
  // org + t dir = a + u e1 + v e2 (Cramer, Möller-Trumbore's form).
  double p[3], q[3];
  cross(d, e2, p);
  cross(s, e1, q);
  double det = dot(e1, p), u = dot(s, p), v = dot(d, q), tn = dot(e2, q);
  if (det == 0.0) return false;
  if (det < 0) det = -det, u = -u, v = -v, tn = -tn;
  const double w = det - u - v, margin = 0.01 * det;
  if (!(u > margin && v > margin && w > margin)) return false;
  t = tn / det;
  const double room = 0.01 * std::max(1.0, std::fabs(t));
  return t - room > static_cast<double>(r.tmin) && t + room < static_cast<double>(r.tmax);
}

}  // namespace

bool same_bits(const volley_hit& a, const volley_hit& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

bool same_values(const volley_hit& a, const volley_hit& b) {
  const auto same = [](float x, float y) { return x == y || (std::isnan(x) && std::isnan(y)); };
  return a.prim == b.prim && a.geom == b.geom && a.inst == b.inst && same(a.t, b.t) && same(a.u, b.u) && same(a.v, b.v);
}

bool agree(const volley_hit& got, const volley_hit& want, bool exact) {
  const bool got_hit = got.prim != VOLLEY_INVALID_PRIM, want_hit = want.prim != VOLLEY_INVALID_PRIM;
  if (got_hit != want_hit) return false;
  if (!got_hit) return true;
  if (got.prim == want.prim && got.geom == want.geom) return exact ? same_bits(got, want) : got.t == want.t;
  return within_ulps(got.t, want.t, current.test == VOLLEY_TEST_WATERTIGHT ? 2 : 32);
}

bool comparable(const volley_ray& r) {
  for (float d : r.dir)
    if (d != 0.0f && std::fabs(d) < 1.0f / std::numeric_limits<float>::max()) return false;
  return r.tmin >= 0.0f && current.robust;
}

bool plausible(const volley_ray& r, const volley_hit& h) {
  const Geometry* g = current.geometry;
  if (h.prim == VOLLEY_INVALID_PRIM || !g || current.first_triangle == VOLLEY_INVALID_PRIM) return true;
  const std::size_t local = h.prim;
  if (h.geom != current.first_triangle || local >= g->indices.size() / 3) return true;  // a polygon
  // The exact ray over [tmin, tmax] must meet the triangle's box (long double slab
  // distances: a zero difference stays exactly 0, so a ray in a face plane pointing
  // outwards by a subnormal step misses), and the hit point must lie in it.
  long double enter = r.tmin, leave = r.tmax;
  for (int k = 0; k < 3; ++k) {
    double lo = INFINITY, hi = -INFINITY;
    for (int c = 0; c < 3; ++c) {
      const double x = g->xyz[3 * g->indices[3 * local + static_cast<std::size_t>(c)] + static_cast<std::size_t>(k)];
      lo = std::min(lo, x), hi = std::max(hi, x);
    }
    const long double o = r.org[k], d = r.dir[k];
    if (d == 0) {
      if (o < lo || o > hi) return false;
    } else {
      const long double a = (lo - o) / d, b = (hi - o) / d;
      enter = std::max(enter, std::min(a, b) * (1 - 1e-12L * (std::min(a, b) > 0 ? 1 : -1)));
      leave = std::min(leave, std::max(a, b) * (1 + 1e-12L * (std::max(a, b) > 0 ? 1 : -1)));
    }
    const double p = static_cast<double>(r.org[k]) + static_cast<double>(h.t) * static_cast<double>(r.dir[k]);
    // The box is exact; the hit point carries the rounding of org + t dir's terms (a few
    // float ulps of them; a t off by more, as the plane test's far from the origin, places
    // the point outside: a hit the exact ray does not have there).
    const double slack = 0x1p-21 * (std::fabs(r.org[k]) + std::fabs(static_cast<double>(h.t) * r.dir[k])) + 1e-30;
    if (!(p >= lo - slack && p <= hi + slack)) return false;
  }
  return enter <= leave;
}

void check_against_oracle(const std::vector<volley_ray>& rays, const std::vector<volley_hit>& got,
                          const Geometry& g, std::uint32_t first_triangle, bool triangles_added,
                          volley_triangle_test test, volley_isa isa, bool reference_double) {
  using volley::core::RayT;
  using volley::core::TriHit;
  using volley::core::Vec3;
  const std::size_t triangles = triangles_added ? g.indices.size() / 3 : 0;
  const volley::TriangleTest cxx_test = test == VOLLEY_TEST_PLANE    ? volley::TriangleTest::plane
                                        : test == VOLLEY_TEST_MOLLER ? volley::TriangleTest::moller
                                                                     : volley::TriangleTest::watertight;
  const volley::Isa variant = isa == VOLLEY_ISA_AVX512 ? volley::Isa::avx512
                              : isa == VOLLEY_ISA_AVX2 ? volley::Isa::avx2
                              : isa == VOLLEY_ISA_SSE42 ? volley::Isa::sse42
                                                        : volley::Isa::scalar;
  auto vertex = [&](std::size_t t, int k) { return &g.xyz[3 * g.indices[3 * t + static_cast<std::size_t>(k)]]; };
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const volley_ray& r = rays[i];
    const volley_hit& h = got[i];
    const std::size_t local = h.prim;
    if (h.prim != VOLLEY_INVALID_PRIM && h.geom == first_triangle && local < triangles) {
      // Sound: the oracle's own answer for this triangle, bit for bit.
      const float* p[3] = {vertex(local, 0), vertex(local, 1), vertex(local, 2)};
      float t, u, v;
      bool hit;
      if (reference_double) {
        const RayT<double> rd{{r.org[0], r.org[1], r.org[2]}, r.tmin, {r.dir[0], r.dir[1], r.dir[2]}, r.tmax};
        TriHit<double> th;
        hit = volley::core::intersect_triangle<double>(cxx_test, rd, Vec3<double>(p[0][0], p[0][1], p[0][2]),
                                                       Vec3<double>(p[1][0], p[1][1], p[1][2]),
                                                       Vec3<double>(p[2][0], p[2][1], p[2][2]), th);
        t = static_cast<float>(th.t), u = static_cast<float>(th.u), v = static_cast<float>(th.v);
      } else {
        const RayT<float> rf{{r.org[0], r.org[1], r.org[2]}, r.tmin, {r.dir[0], r.dir[1], r.dir[2]}, r.tmax};
        TriHit<float> th;
        hit = volley::core::intersect_triangle<float>(cxx_test, rf, Vec3<float>(p[0][0], p[0][1], p[0][2]),
                                                      Vec3<float>(p[1][0], p[1][1], p[1][2]),
                                                      Vec3<float>(p[2][0], p[2][1], p[2][2]), th, variant);
        t = th.t, u = th.u, v = th.v;
      }
      const volley_hit want{t, u, v, h.prim, first_triangle, VOLLEY_INVALID_ID};
      if (!hit || !same_bits(h, want)) {
        std::fprintf(stderr, "reported prim %u t %a u %a v %a; the oracle on it: %s t %a u %a v %a\n", h.prim, h.t,
                     h.u, h.v, hit ? "hit" : "miss", t, u, v);
        finding("a reported hit is not the oracle's answer for its triangle", i);
      }
    }
    // Complete: no triangle hit well inside is missed (for tmin >= 0: the first gap above).
    if (!(r.tmin >= 0.0f)) continue;
    for (std::size_t tri = 0; tri < triangles; ++tri) {
      double t;
      if (!robust_hit(r, vertex(tri, 0), vertex(tri, 1), vertex(tri, 2), t)) continue;
      if (h.prim == VOLLEY_INVALID_PRIM || static_cast<double>(h.t) > t + 0.01 * std::max(1.0, std::fabs(t))) {
        std::fprintf(stderr, "triangle %zu is hit well inside at t = %.9g; got prim %u t %a\n", tri, t, h.prim, h.t);
        finding("a triangle hit well inside was missed", i);
      }
    }
  }
}

}  // namespace fuzz_capi
