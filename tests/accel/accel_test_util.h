// Shared helpers of the wide-BVH and Accel option tests: triangle soups, ray mixes that
// reach every traversal form, brute force over the scalar oracle, and a check of every
// query form (single, occluded, packets of 4, 8, 16, streams) against expected hits.
#pragma once
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "accel/wide/wide_accel.h"
#include "core/bvh.h"
#include "core/triangle.h"
#include "simd/isa/dispatch.h"
#include "volley/accel.h"
#include "volley/packet.h"

namespace accel_test {

using volley::Accel;
using volley::Hit;
using volley::Isa;
using volley::Ray;
using volley::TriangleTest;

inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
inline const TriangleTest kTests[] = {TriangleTest::plane, TriangleTest::moller, TriangleTest::watertight};

/// The SIMD ISAs this CPU runs (a message names the others).
inline std::vector<Isa> simd_isas() {
  std::vector<Isa> out;
  for (Isa isa : {Isa::sse42, Isa::avx2, Isa::avx512}) {
    if (volley::simd::cpu_has(isa))
      out.push_back(isa);
    else
      MESSAGE("skipped: this CPU lacks " << std::string(volley::to_string(isa)));
  }
  return out;
}

/// The SIMD ISAs this CPU runs, then the scalar oracle.
inline std::vector<Isa> all_isas() {
  std::vector<Isa> out = simd_isas();
  out.push_back(Isa::scalar);
  return out;
}

/// Calls f(isa, test) for every ISA of all_isas() and every triangle test, both named in
/// any failure.
template <class F>
void for_each_isa_and_test(F&& f) {
  for (Isa isa : all_isas())
    for (TriangleTest test : kTests) {
      CAPTURE(std::string(volley::to_string(isa)));
      CAPTURE(std::string(volley::to_string(test)));
      f(isa, test);
    }
}

/// Triangles as packed xyz (9 floats each), with an indexed form for Accel.
struct Soup {
  std::vector<float> xyz;
  void add(glm::vec3 a, glm::vec3 b, glm::vec3 c) {
    xyz.insert(xyz.end(), {a.x, a.y, a.z, b.x, b.y, b.z, c.x, c.y, c.z});
  }
  std::size_t size() const { return xyz.size() / 9; }
  glm::vec3 vertex(std::size_t i, int k) const {
    return {xyz[9 * i + 3 * k], xyz[9 * i + 3 * k + 1], xyz[9 * i + 3 * k + 2]};
  }
  Accel accel(TriangleTest test, Isa isa) const { return accel(volley::Options{test, isa}); }
  Accel accel(const volley::Options& options) const {
    Accel a;
    std::vector<std::uint32_t> idx(3 * size());
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
    a.add_triangles(xyz.data(), 3 * size(), idx.data(), size());
    a.commit(options);
    return a;
  }
  std::vector<volley::core::BBox> boxes() const {
    std::vector<volley::core::BBox> out(size());
    for (std::size_t i = 0; i < size(); ++i) {
      if (volley::core::is_degenerate(vertex(i, 0), vertex(i, 1), vertex(i, 2))) continue;
      for (int k = 0; k < 3; ++k) out[i].extend(vertex(i, k));
    }
    return out;
  }
};

inline Ray make_ray(glm::vec3 o, glm::vec3 d, float tmin = 0.0f, float tmax = kInf) {
  return Ray{{o.x, o.y, o.z}, tmin, {d.x, d.y, d.z}, tmax};
}

inline bool finite_ray(const Ray& r) {
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(r.org[a]) || !std::isfinite(r.dir[a])) return false;
  return !std::isnan(r.tmin) && !std::isnan(r.tmax);
}

/// Closest hit by brute force with the scalar oracle in its variant for `isa`'s kernels
/// (moller fuses on AVX2/AVX-512 only: core::moller_fused_for) (the oracle's loop: a
/// triangle replaces the hit when t < the current bound). Rays the API rejects miss.
inline Hit brute_force(const Soup& soup, TriangleTest test, const Ray& ray, Isa isa = Isa::scalar) {
  Hit best;
  if (!finite_ray(ray)) return best;
  const glm::vec3 o(ray.org[0], ray.org[1], ray.org[2]), d(ray.dir[0], ray.dir[1], ray.dir[2]);
  float upper = ray.tmax;
  for (std::size_t i = 0; i < soup.size(); ++i) {
    volley::core::TriHit<float> h;
    if (volley::core::intersect_triangle(test, volley::core::RayT<float>{o, ray.tmin, d, upper}, soup.vertex(i, 0),
                                         soup.vertex(i, 1), soup.vertex(i, 2), h, isa)) {
      upper = h.t;
      best = {h.t, h.u, h.v, static_cast<std::uint32_t>(i)};
    }
  }
  return best;
}

/// brute_force for every ray of `rays`.
inline std::vector<Hit> brute_force_all(const Soup& soup, TriangleTest test, const std::vector<Ray>& rays,
                                        Isa isa = Isa::scalar) {
  std::vector<Hit> out(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) out[i] = brute_force(soup, test, rays[i], isa);
  return out;
}

/// Calls f(test, isa, want) for every triangle test and SIMD ISA this CPU runs, `want` the
/// brute-force closest hits of `rays` at that ISA; checks that the rays tell walks apart
/// (more than a tenth and fewer than nine tenths hit) and names the test and ISA in failures.
template <class F>
void against_brute_force(const Soup& soup, const std::vector<Ray>& rays, F&& f) {
  for (TriangleTest test : kTests)
    for (Isa isa : simd_isas()) {
      CAPTURE(std::string(volley::to_string(test)));
      CAPTURE(std::string(volley::to_string(isa)));
      const std::vector<Hit> want = brute_force_all(soup, test, rays, isa);
      const auto hits = std::count_if(want.begin(), want.end(), [](const Hit& h) { return h.hit(); });
      CHECK(hits > static_cast<long>(want.size() / 10));
      CHECK(hits < static_cast<long>(want.size() * 9 / 10));
      f(test, isa, want);
    }
}

/// Same answer: the same primitive of the same geometry (and instance), or both hits at
/// the same t (a tie between triangles).
inline bool agree(const Hit& got, const Hit& want) {
  const bool same = got.prim == want.prim && got.geom == want.geom && got.inst == want.inst;
  return same ? (!got.hit() || got.t == want.t) : (got.hit() && want.hit() && got.t == want.t);
}

/// Counts disagreements of every query form of `accel` with `want` (per ray), and checks
/// the packet contract: inactive lanes untouched, occlusion masks within the active lanes.
struct FormCheck {
  std::size_t single = 0, occluded = 0, packet = 0, packet_occluded = 0, stream = 0, stream_occluded = 0;
  std::size_t inactive_written = 0, lanes = 0;
  std::size_t total() const {
    return single + occluded + packet + packet_occluded + stream + stream_occluded + inactive_written;
  }
};

template <int K>
inline void check_packets(const Accel& accel, const std::vector<Ray>& rays, const std::vector<Hit>& want,
                          std::mt19937& rng, FormCheck& f) {
  volley::RayPacket<K> p;
  volley::HitPacket<K> h;
  for (std::size_t first = 0; first < rays.size(); first += K) {
    // Full packets mostly; partial ones (1, K - 1 lanes) and random inactive lanes too.
    int count = static_cast<int>(std::min<std::size_t>(K, rays.size() - first));
    const int shape = static_cast<int>(rng() % 8);
    if (shape == 0) count = 1;
    if (shape == 1 && count > 1) count = K - 1 < count ? K - 1 : count;
    volley::load(p, rays.data() + first, count);
    if (shape == 2) p.active &= static_cast<std::uint32_t>(rng()) | 1u;
    // Inactive lanes hold garbage rays (ignored whatever they hold) and sentinel hits that
    // must survive bit for bit: a signalling NaN in u turns quiet if a kernel so much as
    // divides it by 1 and stores it back (what a whole-chunk store did).
    volley::reset(h);
    for (int i = 0; i < K; ++i) {
      if ((p.active >> i) & 1u) continue;
      p.ox[i] = p.dy[i] = kNaN, p.oy[i] = 1e30f, p.oz[i] = -kInf, p.dx[i] = 0.0f, p.dz[i] = 1.0f;
      p.tmin[i] = -kInf, p.tmax[i] = kInf;
      h.t[i] = 12345.0f, h.prim[i] = 0xdeadbeefu, h.geom[i] = 0xabad1deau, h.inst[i] = 0x0ddba11u;
      const std::uint32_t snan = 0x7f800001u, ones = 0xffffffffu;
      std::memcpy(&h.u[i], &snan, 4);
      std::memcpy(&h.v[i], &ones, 4);
    }
    const volley::HitPacket<K> before = h;
    accel.intersect(p, h);
    const std::uint32_t mask = accel.occluded(p);
    for (int i = 0; i < K; ++i) {
      if (!((p.active >> i) & 1u)) {
        f.inactive_written += std::memcmp(&h.t[i], &before.t[i], 4) != 0 || std::memcmp(&h.u[i], &before.u[i], 4) != 0 ||
                              std::memcmp(&h.v[i], &before.v[i], 4) != 0 || h.prim[i] != before.prim[i] ||
                              h.geom[i] != before.geom[i] || h.inst[i] != before.inst[i] || ((mask >> i) & 1u);
        continue;
      }
      ++f.lanes;
      const Hit& w = want[first + static_cast<std::size_t>(i)];
      f.packet += !agree(volley::hit_of(h, i), w);
      f.packet_occluded += ((mask >> i) & 1u) != (w.hit() ? 1u : 0u);
    }
  }
}

inline FormCheck check_forms(const Accel& accel, const std::vector<Ray>& rays, const std::vector<Hit>& want,
                             std::uint32_t seed) {
  FormCheck f;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    f.single += !agree(accel.intersect(rays[i]), want[i]);
    f.occluded += accel.occluded(rays[i]) != want[i].hit();
  }
  std::mt19937 rng(seed);
  check_packets<4>(accel, rays, want, rng, f);
  check_packets<8>(accel, rays, want, rng, f);
  check_packets<16>(accel, rays, want, rng, f);
  // Streams of odd lengths, at odd offsets.
  std::vector<Hit> hits(rays.size());
  std::vector<std::uint8_t> blocked(rays.size(), 7);
  for (std::size_t first = 0; first < rays.size();) {
    const std::size_t n = std::min<std::size_t>(rays.size() - first, 1 + rng() % 70);
    accel.intersect(rays.data() + first, n, hits.data() + first);
    accel.occluded(rays.data() + first, n, blocked.data() + first);
    first += n;
  }
  for (std::size_t i = 0; i < rays.size(); ++i) {
    f.stream += !agree(hits[i], want[i]);
    f.stream_occluded += blocked[i] != (want[i].hit() ? 1 : 0);
  }
  return f;
}

inline void report(const FormCheck& f, const std::string& what) {
  CAPTURE(what);
  CHECK(f.single == 0);
  CHECK(f.occluded == 0);
  CHECK(f.packet == 0);
  CHECK(f.packet_occluded == 0);
  CHECK(f.stream == 0);
  CHECK(f.stream_occluded == 0);
  CHECK(f.inactive_written == 0);
}

/// Random soup of n small triangles in [-10, 10]^3.
inline Soup random_soup(int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-10.0f, 10.0f), small(-1.0f, 1.0f);
  Soup soup;
  for (int i = 0; i < n; ++i) {
    const glm::vec3 c(pos(rng), pos(rng), pos(rng));
    soup.add(c + glm::vec3(small(rng), small(rng), small(rng)), c + glm::vec3(small(rng), small(rng), small(rng)),
             c + glm::vec3(small(rng), small(rng), small(rng)));
  }
  return soup;
}

/// Lone triangles (400, sizes 2^-6 .. 2^5 at random places in a 40-unit box) and rays from
/// all around aimed exactly at their vertices (12 per vertex): many only touch a leaf box at
/// a corner or an edge, where rounding decides whether the slab test lets them in.
struct VertexAimed {
  Soup soup;
  std::vector<Ray> rays;
};
inline VertexAimed lone_triangles_vertex_aimed() {
  std::mt19937 rng(21);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  VertexAimed out;
  for (int i = 0; i < 400; ++i) {
    const float scale = std::ldexp(1.0f, static_cast<int>(rng() % 12) - 6);
    const glm::vec3 c = 40.0f * glm::vec3(unit(rng), unit(rng), unit(rng));
    out.soup.add(c + scale * glm::vec3(unit(rng), unit(rng), unit(rng)),
                 c + scale * glm::vec3(unit(rng), unit(rng), unit(rng)),
                 c + scale * glm::vec3(unit(rng), unit(rng), unit(rng)));
  }
  for (std::size_t t = 0; t < out.soup.size(); ++t)
    for (int k = 0; k < 3; ++k)
      for (int r = 0; r < 12; ++r) {
        const glm::vec3 target = out.soup.vertex(t, k);
        const glm::vec3 o = target + 3.0f * glm::vec3(unit(rng) - 0.5f, unit(rng) - 0.5f, unit(rng) - 0.5f);
        out.rays.push_back(make_ray(o, target - o));
      }
  return out;
}

/// Rays of every kind the traversals distinguish, in runs of 16: incoherent (mixed
/// octants: the per-lane packet walk), pinhole 4x4 blocks (one octant: the frustum walk),
/// axis-aligned blocks (zero components: the per-lane one-octant walk), converging
/// shadow-like rays with a finite tmax, runs with NaN / Inf lanes among good ones, and
/// camera blocks whose origins differ (the notes' viewport, each ray from its pixel; an
/// orthographic camera, one direction from a grid of origins: closest hits take the
/// frustum walk for those too).
inline std::vector<Ray> mixed_rays(int runs, float extent, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-extent, extent), unit(-1.0f, 1.0f);
  std::vector<Ray> rays;
  for (int r = 0; r < runs; ++r) {
    const int kind = r % 7;
    const glm::vec3 eye(pos(rng) * 2.0f, pos(rng) * 2.0f, pos(rng) * 2.0f);
    const glm::vec3 look = glm::vec3(pos(rng), pos(rng), pos(rng)) * 0.5f - eye;
    const glm::vec3 u = glm::normalize(glm::cross(look, glm::vec3(0.3f, 1.0f, 0.1f))) * 0.02f * extent;
    const glm::vec3 v = glm::normalize(glm::cross(u, look)) * 0.02f * extent;
    for (int i = 0; i < 16; ++i) {
      const float x = float(i % 4) - 1.5f, y = float(i / 4) - 1.5f;
      switch (kind) {
        case 0:
          rays.push_back(make_ray(eye, glm::vec3(pos(rng), pos(rng), pos(rng)) - eye));
          break;
        case 1:
          rays.push_back(make_ray(eye, look + x * u + y * v));
          break;
        case 2: {
          const int axis = r / 7 % 3;
          glm::vec3 d(0.0f);
          d[axis] = (r / 21) % 2 ? 1.0f : -1.0f;
          glm::vec3 o(pos(rng), pos(rng), pos(rng));
          o[axis] = -d[axis] * extent * 2.0f;
          rays.push_back(make_ray(o, d));
          break;
        }
        case 3: {
          // From points near the packet's own "surface" toward one light, interval [0, 1).
          const glm::vec3 o = eye * 0.25f + x * u * 5.0f + y * v * 5.0f;
          rays.push_back(make_ray(o, look * 1.5f + glm::vec3(0, 0.1f * x, 0), 0.0f, 1.0f));
          break;
        }
        case 5: {
          const glm::vec3 d = look + x * u + y * v;
          rays.push_back(make_ray(eye + 0.05f * d, d));
          break;
        }
        case 6:
          rays.push_back(make_ray(eye + 3.0f * (x * u + y * v), look));
          break;
        default: {
          Ray ray = make_ray(eye, look + x * u + y * v);
          if (i == 3) ray.dir[1] = kNaN;
          if (i == 7) ray.org[0] = kInf;
          if (i == 11) ray.tmax = kNaN;
          if (i == 12) ray.dir[2] = -kInf;
          if (i == 13) ray.tmin = 2.0f, ray.tmax = 1.0f;  // empty interval
          rays.push_back(ray);
          break;
        }
      }
    }
  }
  return rays;
}

/// Bounce-like rays: from random points of the soup's box in random directions, each run
/// of 16 spread across every axis plane; every fourth ray a segment (finite tmax), bad rays
/// (NaN, Inf, an empty interval) and zero direction components among them.
inline std::vector<Ray> bounce_rays(std::size_t count, float extent, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-extent, extent), unit(-1.0f, 1.0f);
  std::vector<Ray> rays;
  for (std::size_t i = 0; i < count; ++i) {
    const glm::vec3 o(pos(rng), pos(rng), pos(rng));
    glm::vec3 d(unit(rng), unit(rng), unit(rng));
    if (i % 37 == 5) d.y = (i % 2) ? 0.0f : -0.0f;
    Ray ray = make_ray(o, d, 0.0f, i % 4 == 1 ? 0.5f + 4.0f * (unit(rng) + 1.0f) : kInf);
    if (i % 101 == 7) ray.dir[0] = kNaN;
    if (i % 103 == 9) ray.org[2] = -kInf;
    if (i % 107 == 11) ray.tmin = 3.0f, ray.tmax = 2.0f;
    rays.push_back(ray);
  }
  return rays;
}

/// The wide engine (watertight test) over `soup` with one triangle per leaf, so that every
/// leaf box is a triangle's own.
inline std::unique_ptr<volley::accel::WideAccel> one_triangle_per_leaf(const Soup& soup, Isa isa, bool robust) {
  volley::core::BvhBuildOptions one_per_leaf;
  one_per_leaf.max_leaf_size = 1;
  const volley::core::Bvh bvh = volley::core::build_bvh(soup.boxes(), one_per_leaf);
  std::vector<std::uint32_t> ids(soup.size());
  for (std::size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<std::uint32_t>(i);
  auto wide = volley::accel::WideAccel::create(TriangleTest::watertight, isa, robust);
  wide->build(bvh, soup.xyz.data(), ids.data());
  return wide;
}

}  // namespace accel_test
