// libFuzzer target: the C API driven by the fuzzer's bytes, and a differential check of
// its answers. The bytes build a scene (triangles with arbitrary floats and indices,
// polygons), commit it with any options (bad enum values included), then trace rays
// (arbitrary, or aimed exactly at vertices and edge midpoints) in every form: single,
// packets of 4, 8 and 16 with partial masks, streams, occlusion. A crash, a sanitizer
// report, a status other than the documented ones, or a wrong answer is a finding:
//
// - Forms: every form agrees with the single-ray closest hit (the same prim, or a tie
//   within 2 ulps of t: two overlapping coplanar triangles met in different orders,
//   accel.h); occlusion equals hit or miss; inactive packet lanes stay untouched. They are
//   compared where the walks promise to agree (comparable(), plausible()): tmin >= 0 (the
//   exit pad is a factor, which tightens a negative exit distance), robust box tests (the
//   unpadded ones may cull a box the ray grazes), no direction component below 1 / FLT_MAX
//   (its reciprocal overflows to inf and a finite slab distance becomes infinite), and
//   answers that are hits the exact ray can have (a float test can report a hit outside
//   its triangle's box). The first and third are gaps this fuzzer found, left for an issue
//   (docs/accuracy.md, rules 4 and 5).
// - Sound: every reported triangle hit is the scalar oracle's answer for that triangle,
//   bit for bit (t, u, v), in the oracle's variant for the ISA in use (core::
//   intersect_triangle: Möller and watertight fuse on AVX2 / AVX-512), with tmin <= t < tmax.
// - Complete: a triangle that the exact ray hits well inside (barycentrics and t at least
//   1% from every edge of their range, decided in exact arithmetic) is never missed: the
//   closest hit is at most that far. Exact arithmetic needs tame input (multiples of 1/16
//   up to 1024 in magnitude: every product and sum of the test is exact in double); other
//   triangles and rays are checked for soundness only. The scalar oracle's own traversal
//   is no referee here: its binary BVH and the wide BVH cull different boxes, and where the
//   float test reports a hit the exact ray does not have (rays from 1e27 away, subnormal
//   directions), one of them may visit that leaf and the other not.
// - Instances: the scene placed under the identity in a scene of its own answers in every
//   form alike, and as the scene itself where the ray reaches it unchanged (check_instance).
#include <fuzzer/FuzzedDataProvider.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "core/triangle.h"
#include "volley/volley.h"

namespace {

struct Geometry;
struct Case {
  const Geometry* geometry = nullptr;
  const std::vector<volley_ray>* rays = nullptr;
  int test = 0, isa = 0, robust = 0, reference_double = 0;
  std::uint32_t first_triangle = VOLLEY_INVALID_PRIM;  ///< the triangles' geometry id, if added
};
/// What the current input built, printed with a finding (the input itself is saved too).
Case current;

void print_case(std::size_t ray);

[[noreturn]] void finding(const char* what, std::size_t ray) {
  std::fprintf(stderr, "fuzz_capi: %s (ray %zu)\n", what, ray);
  print_case(ray);
  std::abort();
}

/// A coordinate: mostly small exact values (so that vertices coincide, edges are shared
/// and rays hit vertices exactly), sometimes an extreme or arbitrary float.
float coordinate(FuzzedDataProvider& in) {
  static const float kSpecial[] = {0.0f,    -0.0f,   1e-40f, -1e-40f, 1e-30f, 1e30f,
                                   -1e30f,  3e38f,   1e6f,   -1e6f,   0.1f,   std::numeric_limits<float>::infinity(),
                                   -std::numeric_limits<float>::infinity(), std::numeric_limits<float>::quiet_NaN()};
  const int kind = in.ConsumeIntegralInRange(0, 7);
  if (kind < 5) return 0.5f * static_cast<float>(in.ConsumeIntegralInRange(-8, 8));
  if (kind == 5) return kSpecial[in.ConsumeIntegralInRange<std::size_t>(0, std::size(kSpecial) - 1)];
  if (kind == 6) return static_cast<float>(in.ConsumeIntegralInRange(-256, 256)) / 16.0f;
  float f;
  const std::uint32_t bits = in.ConsumeIntegral<std::uint32_t>();
  std::memcpy(&f, &bits, 4);
  return f;
}

struct Geometry {
  std::vector<float> xyz;
  std::vector<std::uint32_t> indices;
  std::vector<std::vector<float>> polygons;
};

void print_case(std::size_t ray) {
  std::fprintf(stderr, "commit: test %d isa %d robust %d reference_double %d\n", current.test, current.isa,
               current.robust, current.reference_double);
  if (current.geometry) {
    const Geometry& g = *current.geometry;
    for (std::size_t i = 0; i + 2 < g.xyz.size(); i += 3)
      std::fprintf(stderr, "v %zu: %a %a %a\n", i / 3, g.xyz[i], g.xyz[i + 1], g.xyz[i + 2]);
    for (std::size_t i = 0; i + 2 < g.indices.size(); i += 3)
      std::fprintf(stderr, "triangle %zu: %u %u %u\n", i / 3, g.indices[i], g.indices[i + 1], g.indices[i + 2]);
    for (const auto& poly : g.polygons) {
      std::fprintf(stderr, "polygon:");
      for (float f : poly) std::fprintf(stderr, " %a", f);
      std::fprintf(stderr, "\n");
    }
  }
  if (current.rays && ray < current.rays->size()) {
    const volley_ray& r = (*current.rays)[ray];
    std::fprintf(stderr, "ray: org %a %a %a dir %a %a %a tmin %a tmax %a\n", r.org[0], r.org[1], r.org[2], r.dir[0],
                 r.dir[1], r.dir[2], r.tmin, r.tmax);
  }
}

Geometry make_geometry(FuzzedDataProvider& in) {
  Geometry g;
  const std::size_t vertices = in.ConsumeIntegralInRange<std::size_t>(0, 48);
  for (std::size_t i = 0; i < 3 * vertices; ++i) g.xyz.push_back(coordinate(in));
  const std::size_t triangles = in.ConsumeIntegralInRange<std::size_t>(0, 64);
  for (std::size_t i = 0; i < 3 * triangles; ++i)
    // Now and then an index out of range (rejected as a whole).
    g.indices.push_back(in.ConsumeIntegralInRange<std::uint32_t>(0, static_cast<std::uint32_t>(vertices) + (i % 97 == 96)));
  const int polygons = in.ConsumeIntegralInRange(0, 2);
  for (int p = 0; p < polygons; ++p) {
    // Planar by construction most of the time: z = a x + b y + c on small values.
    const int n = in.ConsumeIntegralInRange(0, 7);
    const float a = coordinate(in), b = coordinate(in), c = coordinate(in);
    std::vector<float> poly;
    for (int k = 0; k < n; ++k) {
      const float x = coordinate(in), y = coordinate(in);
      poly.insert(poly.end(), {x, y, in.ConsumeBool() ? a * x + b * y + c : coordinate(in)});
    }
    g.polygons.push_back(poly);
  }
  return g;
}

/// Adds `g` to `scene`; returns the status of the first call that failed, else VOLLEY_OK.
/// The triangles' geometry id goes to *first_triangle when they were added.
volley_status add(volley_scene* scene, const Geometry& g, std::uint32_t* first_triangle = nullptr) {
  volley_status first_error = VOLLEY_OK;
  const volley_status s = volley_scene_add_triangles(scene, g.xyz.data(), g.xyz.size() / 3, g.indices.data(),
                                                     g.indices.size() / 3, first_triangle);
  if (s != VOLLEY_OK) first_error = s;
  for (const auto& poly : g.polygons) {
    const volley_status p = volley_scene_add_polygon(scene, poly.data(), poly.size() / 3, nullptr);
    if (p != VOLLEY_OK && first_error == VOLLEY_OK) first_error = p;
  }
  return first_error;
}

volley_ray make_ray(FuzzedDataProvider& in, const Geometry& g) {
  volley_ray r;
  for (float& o : r.org) o = coordinate(in);
  const std::size_t vertices = g.xyz.size() / 3;
  if (vertices > 0 && in.ConsumeBool()) {
    // Aimed exactly at a vertex, or at the midpoint of two.
    const std::size_t a = in.ConsumeIntegralInRange<std::size_t>(0, vertices - 1);
    const std::size_t b = in.ConsumeBool() ? a : in.ConsumeIntegralInRange<std::size_t>(0, vertices - 1);
    for (int k = 0; k < 3; ++k) r.dir[k] = 0.5f * (g.xyz[3 * a + k] + g.xyz[3 * b + k]) - r.org[k];
  } else {
    for (float& d : r.dir) d = coordinate(in);
  }
  r.tmin = in.ConsumeBool() ? 0.0f : coordinate(in);
  r.tmax = in.ConsumeBool() ? std::numeric_limits<float>::infinity() : coordinate(in);
  return r;
}

bool within_ulps(float a, float b, int ulps) {
  if (a == b) return true;
  if (!std::isfinite(a) || !std::isfinite(b) || std::signbit(a) != std::signbit(b)) return false;
  std::int32_t ia, ib;
  std::memcpy(&ia, &a, 4);
  std::memcpy(&ib, &b, 4);
  return std::abs(static_cast<std::int64_t>(ia) - ib) <= ulps;
}

/// Whether `h` (an answer to `r`) is a hit the exact ray can have: a miss, a polygon, or a
/// triangle whose box the exact ray meets within [tmin, tmax] and holds the hit point
/// (within rounding). A float test can report a hit the exact ray does not have (rays from
/// 1e27 away, triangles with a vertex at 1e38, a ray in a box's face plane stepping out by
/// a subnormal direction component); whether a walk meets it then depends on which boxes
/// that walk culls, so forms may differ on such a ray, and are not compared there.
bool plausible(const volley_ray& r, const volley_hit& h);
bool comparable(const volley_ray& r);

bool same_bits(const volley_hit& a, const volley_hit& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// The same answer but for the sign of zeros: the ids bit for bit, t u v equal as numbers
/// (or both NaN).
bool same_values(const volley_hit& a, const volley_hit& b) {
  const auto same = [](float x, float y) { return x == y || (std::isnan(x) && std::isnan(y)); };
  return a.prim == b.prim && a.geom == b.geom && a.inst == b.inst && same(a.t, b.t) && same(a.u, b.u) && same(a.v, b.v);
}

/// `got` and `want` answer the same ray alike: both miss, or the same primitive of the same
/// geometry at the same t
/// (and u, v when `exact`), or two prims within 2 ulps of t (a coplanar tie). The plane and
/// Möller tests: within 32 ulps, for their false hits beside an edge, which a walk keeps or
/// culls by the order it opens leaves (docs/accuracy.md, "Known traps": a ray from ~1e6
/// away, a sliver with a vertex at 1e30; the watertight test agrees throughout).
bool agree(const volley_hit& got, const volley_hit& want, bool exact) {
  const bool got_hit = got.prim != VOLLEY_INVALID_PRIM, want_hit = want.prim != VOLLEY_INVALID_PRIM;
  if (got_hit != want_hit) return false;
  if (!got_hit) return true;
  if (got.prim == want.prim && got.geom == want.geom) return exact ? same_bits(got, want) : got.t == want.t;
  return within_ulps(got.t, want.t, current.test == VOLLEY_TEST_WATERTIGHT ? 2 : 32);
}

/// The packet forms of width K agree with the single-ray answers `single` of `rays`.
template <int K, class RayPacket, class HitPacket, class Intersect, class Occluded>
void check_packets(const volley_scene* scene, const std::vector<volley_ray>& rays,
                   const std::vector<volley_hit>& single, FuzzedDataProvider& in, Intersect intersect,
                   Occluded occluded) {
  for (std::size_t first = 0; first < rays.size(); first += K) {
    RayPacket p;
    HitPacket h;
    std::memset(&p, 0, sizeof p);
    p.active = in.ConsumeIntegral<std::uint32_t>() | (in.ConsumeBool() ? ~0u : 0u);
    for (int i = 0; i < K; ++i) {
      const std::size_t r = first + static_cast<std::size_t>(i);
      if (r >= rays.size()) {
        p.active &= ~(1u << i);
        p.ox[i] = std::numeric_limits<float>::quiet_NaN();  // garbage: must be ignored
        continue;
      }
      const volley_ray& ray = rays[r];
      p.ox[i] = ray.org[0], p.oy[i] = ray.org[1], p.oz[i] = ray.org[2];
      p.dx[i] = ray.dir[0], p.dy[i] = ray.dir[1], p.dz[i] = ray.dir[2];
      p.tmin[i] = ray.tmin, p.tmax[i] = ray.tmax;
    }
    for (int i = 0; i < K; ++i) {
      h.t[i] = 12345.0f, h.prim[i] = 0xdeadbeefu, h.geom[i] = 0xabad1deau, h.inst[i] = 0x0ddba11u;
      const std::uint32_t snan = 0x7f800001u;
      std::memcpy(&h.u[i], &snan, 4);
      h.v[i] = -0.0f;
    }
    const HitPacket before = h;
    std::uint32_t blocked = 0;
    if (intersect(scene, &p, &h) != VOLLEY_OK) finding("packet intersect failed on a committed scene", first);
    if (occluded(scene, &p, &blocked) != VOLLEY_OK) finding("packet occluded failed on a committed scene", first);
    for (int i = 0; i < K; ++i) {
      const std::size_t r = first + static_cast<std::size_t>(i);
      if (!((p.active >> i) & 1u)) {
        if (std::memcmp(&h.t[i], &before.t[i], 4) || std::memcmp(&h.u[i], &before.u[i], 4) ||
            std::memcmp(&h.v[i], &before.v[i], 4) || h.prim[i] != before.prim[i] || h.geom[i] != before.geom[i] ||
            h.inst[i] != before.inst[i] || ((blocked >> i) & 1u))
          finding("a packet wrote an inactive lane", r);
        continue;
      }
      // Forms agree only where the walks are conservative (tmin >= 0) and the answers
      // are hits the exact ray can have (see the top).
      if (!comparable(rays[r])) continue;
      // An active lane that finds nothing keeps its sentinel t (12345 bounds its search).
      const volley_hit want = single[r];
      const bool nearer = want.prim != VOLLEY_INVALID_PRIM && want.t < 12345.0f;
      const volley_hit got{h.t[i], h.u[i], h.v[i], h.prim[i], h.geom[i], h.inst[i]};
      if (!plausible(rays[r], want) || (got.prim != 0xdeadbeefu && !plausible(rays[r], got))) continue;
      if (nearer ? !agree(got, want, true) : got.prim != 0xdeadbeefu) {
        std::fprintf(stderr, "lane %d of %d (active %#x): prim %u t %a u %a v %a; single: prim %u t %a u %a v %a\n", i, K,
                     p.active, got.prim, got.t, got.u, got.v, want.prim, want.t, want.u, want.v);
        finding("a packet lane disagrees", r);
      }
      if (((blocked >> i) & 1u) != (want.prim != VOLLEY_INVALID_PRIM ? 1u : 0u))
        finding("packet occlusion disagrees with the closest hit", r);
    }
  }
}

/// Whether the walks promise to agree on `r` (see the top): tmin >= 0, robust box tests, and
/// no direction component so small that its reciprocal overflows (1/d = inf turns a finite
/// slab distance infinite; found by this fuzzer, left for an issue).
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

/// Checks the single-ray answers `got` for soundness and completeness (see the top).
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

/// Traces `rays` in every form against `scene`; returns the single-ray answers.
std::vector<volley_hit> trace_all_forms(const volley_scene* scene, const std::vector<volley_ray>& rays,
                                        FuzzedDataProvider& in) {
  std::vector<volley_hit> single(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    int occ = -1;
    if (volley_intersect1(scene, &rays[i], &single[i]) != VOLLEY_OK) finding("intersect1 failed", i);
    if (volley_occluded1(scene, &rays[i], &occ) != VOLLEY_OK) finding("occluded1 failed", i);
    const bool hit = single[i].prim != VOLLEY_INVALID_PRIM;
    if (occ != (hit ? 1 : 0)) finding("occluded1 disagrees with intersect1", i);
    if (hit && !(rays[i].tmin <= single[i].t && single[i].t < rays[i].tmax)) finding("t outside [tmin, tmax)", i);
  }
  check_packets<4, volley_ray_packet4, volley_hit_packet4>(scene, rays, single, in, volley_intersect4, volley_occluded4);
  check_packets<8, volley_ray_packet8, volley_hit_packet8>(scene, rays, single, in, volley_intersect8, volley_occluded8);
  check_packets<16, volley_ray_packet16, volley_hit_packet16>(scene, rays, single, in, volley_intersect16,
                                                              volley_occluded16);
  std::vector<volley_hit> stream(rays.size());
  std::vector<std::uint8_t> blocked(rays.size(), 7);
  if (volley_intersect_stream(scene, rays.data(), rays.size(), stream.data()) != VOLLEY_OK ||
      volley_occluded_stream(scene, rays.data(), rays.size(), blocked.data()) != VOLLEY_OK)
    finding("stream query failed", 0);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (!comparable(rays[i]) || !plausible(rays[i], single[i]) || !plausible(rays[i], stream[i])) continue;
    if (!agree(stream[i], single[i], true)) {
      std::fprintf(stderr, "stream: prim %u t %a u %a v %a; single: prim %u t %a u %a v %a\n", stream[i].prim,
                   stream[i].t, stream[i].u, stream[i].v, single[i].prim, single[i].t, single[i].u, single[i].v);
      finding("stream disagrees with intersect1", i);
    }
    if (blocked[i] != (single[i].prim != VOLLEY_INVALID_PRIM ? 1 : 0)) finding("stream occlusion disagrees", i);
  }
  // The batch forms on 2 threads: the stream's answers bit for bit (the same runs of 16).
  std::vector<volley_hit> batch(rays.size());
  std::vector<std::uint8_t> batch_blocked(rays.size(), 7);
  if (volley_intersect_batch(scene, rays.data(), nullptr, rays.size(), batch.data(), 2) != VOLLEY_OK ||
      volley_occluded_batch(scene, rays.data(), nullptr, rays.size(), batch_blocked.data(), 2) != VOLLEY_OK)
    finding("batch query failed", 0);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    if (!same_bits(batch[i], stream[i])) finding("batch disagrees with stream", i);
    if (batch_blocked[i] != blocked[i]) finding("batch occlusion disagrees with stream", i);
    // A hit's geometric normal: unit length or NaN (a degenerate or non-finite triangle);
    // a miss's: NaN.
    float n[3];
    if (volley_geometric_normal(scene, &single[i], n) != VOLLEY_OK) finding("geometric_normal failed", i);
    const double len = std::sqrt(double(n[0]) * n[0] + double(n[1]) * n[1] + double(n[2]) * n[2]);
    if (single[i].prim == VOLLEY_INVALID_PRIM ? !std::isnan(n[0]) : !(std::isnan(n[0]) || std::fabs(len - 1.0) < 1e-5))
      finding("geometric_normal is neither unit nor NaN", i);
  }
  // The batch of normals: each the single call's, bit for bit.
  std::vector<float> normals(3 * rays.size());
  if (volley_geometric_normals(scene, single.data(), single.size(), normals.data()) != VOLLEY_OK)
    finding("geometric_normals failed", 0);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    float n[3];
    volley_geometric_normal(scene, &single[i], n);
    if (std::memcmp(n, &normals[3 * i], sizeof n) != 0) finding("geometric_normals disagrees with geometric_normal", i);
  }
  return single;
}

/// The scene placed once, under the identity, in a scene of its own: the instance's top
/// level and the ray's way into it (single rays, packets of any lanes, streams) answer in
/// every form alike (trace_all_forms), and a finite ray without a zero component in its
/// direction gets the prototype's own answer `got`, through the instance, but for the sign
/// of zeros. The transform's sums turn -0 into +0: in a direction that flips an infinite
/// reciprocal, so such rays only have to agree across the instance's own forms; in an
/// origin it can flip the sign of a zero barycentric (found: a ray from a triangle's
/// vertex, origin z -0, gave v = +0 through the instance and -0 without; t and u the same).
void check_instance(const volley_scene* prototype, const volley_commit_options& options,
                    const std::vector<volley_ray>& rays, const std::vector<volley_hit>& got, FuzzedDataProvider& in) {
  volley_scene* world = nullptr;
  if (volley_scene_create(&world) != VOLLEY_OK) finding("scene_create failed", 0);
  const float identity[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  std::uint32_t id = VOLLEY_INVALID_ID;
  if (volley_scene_add_instance(world, prototype, identity, &id) != VOLLEY_OK ||
      volley_scene_commit_ex(world, &options) != VOLLEY_OK)
    finding("an identity instance of a committed scene failed", 0);
  const std::vector<volley_hit> single = trace_all_forms(world, rays, in);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const volley_ray& r = rays[i];
    bool plain = comparable(r);
    for (int k = 0; k < 3; ++k)
      plain = plain && std::isfinite(r.org[k]) && r.dir[k] != 0.0f && std::isfinite(r.dir[k]);
    if (!plain) continue;
    volley_hit want = got[i];
    if (want.prim != VOLLEY_INVALID_PRIM) want.inst = id;
    if (!same_values(single[i], want)) finding("an identity instance answers otherwise than its prototype", i);
  }
  volley_scene_destroy(world);
}

/// Every geometry given one fuzzed mask and the scene committed again: a ray with a mask
/// that shares a bit with it gets the unmasked answer `got`, one that shares none a miss,
/// in the single, stream and packet forms.
void check_masks(volley_scene* scene, const volley_commit_options& options, std::size_t geometries,
                 const std::vector<volley_ray>& rays, const std::vector<volley_hit>& got, FuzzedDataProvider& in) {
  const std::uint32_t geometry_mask = in.ConsumeIntegral<std::uint32_t>();
  const std::uint32_t ray_mask = in.ConsumeBool() ? geometry_mask & in.ConsumeIntegral<std::uint32_t>()
                                                  : in.ConsumeIntegral<std::uint32_t>();
  for (std::uint32_t g = 0; g < geometries; ++g)
    if (volley_scene_set_geometry_mask(scene, g, geometry_mask) != VOLLEY_OK) finding("set_geometry_mask failed", g);
  if (volley_scene_commit_ex(scene, &options) != VOLLEY_OK) finding("commit after masking failed", 0);
  const bool sees = (geometry_mask & ray_mask) != 0;
  std::vector<std::uint32_t> masks(rays.size(), ray_mask);
  std::vector<volley_hit> stream(rays.size());
  if (volley_intersect_stream_masked(scene, rays.data(), masks.data(), rays.size(), stream.data()) != VOLLEY_OK)
    finding("masked stream failed", 0);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    volley_hit h;
    if (volley_intersect1_masked(scene, &rays[i], ray_mask, &h) != VOLLEY_OK) finding("intersect1_masked failed", i);
    if (!sees) {
      if (h.prim != VOLLEY_INVALID_PRIM || stream[i].prim != VOLLEY_INVALID_PRIM) finding("a masked-out geometry was hit", i);
      continue;
    }
    // The same single-ray walk of the same tree: the same answer, bit for bit.
    if (std::memcmp(&h, &got[i], sizeof h) != 0) finding("a masked ray disagrees with the unmasked one", i);
    // The stream as trace_all_forms compares it (where the walks promise to agree).
    if (!comparable(rays[i]) || !plausible(rays[i], h) || !plausible(rays[i], stream[i])) continue;
    if (!agree(stream[i], h, true)) finding("the masked stream disagrees with intersect1_masked", i);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider in(data, size);
  volley_commit_options options;
  volley_commit_options_default(&options);
  // Enum values one past the last are invalid on purpose.
  options.test = static_cast<volley_triangle_test>(in.ConsumeIntegralInRange(0, 3));
  options.isa = static_cast<volley_isa>(in.ConsumeIntegralInRange(0, 5));
  options.robust = in.ConsumeIntegralInRange(0, 7) != 0;
  options.reference_double = in.ConsumeIntegralInRange(0, 7) == 0;
  options.quality = static_cast<volley_build_quality>(in.ConsumeIntegralInRange(0, 3));  // 1 and 2 are valid
  const Geometry geometry = make_geometry(in);
  current = Case{&geometry, nullptr, int(options.test), int(options.isa), options.robust, options.reference_double};

  volley_scene* scene = nullptr;
  if (volley_scene_create(&scene) != VOLLEY_OK) finding("scene_create failed", 0);
  std::uint32_t first_triangle = VOLLEY_INVALID_PRIM;
  const volley_status added = add(scene, geometry, &first_triangle);
  current.first_triangle = first_triangle;
  if (added != VOLLEY_OK && added != VOLLEY_ERROR_INVALID_GEOMETRY && added != VOLLEY_ERROR_INVALID_ARGUMENT)
    finding("add: undocumented status", 0);

  // A query before commit is an error, not a crash.
  volley_hit hit;
  const volley_ray probe{{0, 0, 0}, 0, {0, 0, 1}, 1};
  if (volley_intersect1(scene, &probe, &hit) != VOLLEY_ERROR_NOT_COMMITTED) finding("query before commit", 0);

  const volley_status committed = volley_scene_commit_ex(scene, &options);
  if (committed != VOLLEY_OK) {
    if (committed != VOLLEY_ERROR_INVALID_ARGUMENT && committed != VOLLEY_ERROR_UNSUPPORTED_ISA)
      finding("commit: undocumented status", 0);
    if (volley_last_error()[0] == '\0') finding("commit failed without a message", 0);
  } else {
    volley_scene_info info;
    if (volley_scene_get_info(scene, &info) != VOLLEY_OK) finding("get_info failed", 0);
    std::vector<volley_ray> rays;
    const std::size_t count = in.ConsumeIntegralInRange<std::size_t>(0, 40);
    for (std::size_t i = 0; i < count && in.remaining_bytes() > 0; ++i) rays.push_back(make_ray(in, geometry));
    current.rays = &rays;
    const std::vector<volley_hit> got = trace_all_forms(scene, rays, in);

    check_against_oracle(rays, got, geometry, first_triangle, first_triangle != VOLLEY_INVALID_PRIM, options.test,
                         info.isa, options.reference_double != 0);
    check_instance(scene, options, rays, got, in);
    check_masks(scene, options, info.geometries, rays, got, in);
  }
  volley_scene_destroy(scene);
  current = Case{};
  return 0;
}
