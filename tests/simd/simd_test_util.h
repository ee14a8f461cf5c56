// Shared helpers of the SIMD kernel tests: ISA list, block packing, the scalar oracle
// driven the way the kernels promise to behave (closest hit in triangle order), ray and
// triangle generators, and lane-by-lane comparison.
#pragma once
#include <doctest/doctest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <type_traits>
#include <algorithm>
#include <vector>

#include "core/triangle.h"
#include "simd/testing/prepare_ray.h"
#include "simd/aligned.h"
#include "simd/isa/arch.h"
#include "simd/triangle/block_build.h"
#include "simd/triangle/block_kernels.h"
#include "simd/isa/dispatch.h"
#include "simd/rays/prepared_ray.h"
#include "simd/rays/ray_packet.h"

/// The kernel arches every kernel test runs on (a test skips those this CPU lacks: skip_isa).
#define VOLLEY_TEST_ARCHES volley::simd::Sse42, volley::simd::Avx2, volley::simd::Avx512, volley::simd::Avx512Ymm

TYPE_TO_STRING(volley::simd::Sse42);
TYPE_TO_STRING(volley::simd::Avx2);
TYPE_TO_STRING(volley::simd::Avx512);
TYPE_TO_STRING(volley::simd::Avx512Ymm);

namespace simd_test {

using volley::Hit;
using volley::kInvalidPrim;
using volley::Ray;
using volley::TriangleTest;
using volley::simd::HitPacket;
using volley::simd::kLanes;
using volley::simd::PacketKernels;
using volley::simd::RayBlockKernels;
using volley::simd::RayPacket;
using V3 = volley::core::Vec3<float>;

inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
inline constexpr TriangleTest kTests[] = {TriangleTest::plane, TriangleTest::moller, TriangleTest::watertight};

/// t, u, v of the kernels may differ from the oracle's by at most this many ulps. The
/// kernels perform the float operations of the oracle's variant for their ISA in the same
/// order (fused exactly where it fuses, true divisions), so the bound is 0: bit-identical.
inline constexpr std::uint32_t kMaxUlps = 0;

/// True (and a MESSAGE) when this CPU cannot run Arch's kernels: the test case returns.
template <class Arch>
bool skip_isa() {
  if (volley::simd::cpu_has(volley::simd::kIsaOf<Arch>)) return false;
  MESSAGE("skipped: this CPU lacks " << volley::to_string(volley::simd::kIsaOf<Arch>));
  return true;
}

inline std::string name(TriangleTest t) { return std::string(volley::to_string(t)); }

/// Distance in ulps between two floats of the same sign class (0 when bit-identical; +0
/// against -0 is 1; NaN against anything but the same NaN bits is "far").
inline std::uint32_t ulps(float a, float b) {
  const auto key = [](float x) {
    const std::int64_t i = std::bit_cast<std::int32_t>(x);
    return i < 0 ? std::int64_t(INT32_MIN) - i : i;
  };
  if (std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b)) return 0;
  if (std::isnan(a) || std::isnan(b)) return 0xffffffffu;
  if (a == b) return 1;  // +0 against -0: a reported zero's sign is part of the answer
  const std::int64_t d = key(a) - key(b);
  return static_cast<std::uint32_t>(std::min<std::int64_t>(d < 0 ? -d : d, 0xffffffffLL));
}

/// Triangles as the facade takes them: 9 floats each, plus ids.
struct Soup {
  std::vector<float> xyz;
  std::vector<std::uint32_t> ids;
  std::size_t size() const { return ids.size(); }
  void add(const V3& a, const V3& b, const V3& c, std::uint32_t id) {
    for (const V3& p : {a, b, c}) xyz.insert(xyz.end(), {p.x, p.y, p.z});
    ids.push_back(id);
  }
  void add(const V3& a, const V3& b, const V3& c) { add(a, b, c, static_cast<std::uint32_t>(1000 + ids.size())); }
  V3 vertex(std::size_t t, int k) const {
    const float* p = xyz.data() + 9 * t + 3 * k;
    return V3(p[0], p[1], p[2]);
  }
};

/// The blocks of `Test` for Arch's width holding all of `soup`.
template <class Arch, TriangleTest Test>
volley::simd::AlignedVector<volley::simd::BlockFor<Test, kLanes<Arch>>> pack(const Soup& soup) {
  constexpr int W = kLanes<Arch>;
  volley::simd::AlignedVector<volley::simd::BlockFor<Test, W>> blocks(volley::simd::blocks_for<W>(soup.size()));
  volley::simd::pack_blocks<Test, W>(soup.xyz.data(), soup.ids.data(), soup.size(), blocks.data());
  return blocks;
}

/// The scalar oracle, in its variant for Arch's kernels (core::moller_fused_for), on
/// triangle t of `soup` with the search interval [ray.tmin, upper).
template <class Arch>
bool oracle(TriangleTest test, const Ray& ray, float upper, const Soup& soup, std::size_t t,
            volley::core::TriHit<float>& h) {
  const volley::core::RayT<float> r{V3(ray.org[0], ray.org[1], ray.org[2]), ray.tmin,
                                    V3(ray.dir[0], ray.dir[1], ray.dir[2]), upper};
  return volley::core::intersect_triangle(test, r, soup.vertex(t, 0), soup.vertex(t, 1), soup.vertex(t, 2), h,
                                          volley::simd::kIsaOf<Arch>);
}

/// Closest hit by Arch's oracle over triangles first .. last in order, as the kernels define
/// it: upper = min(hit.t, tmax) (NaN tmax: nothing), shrinking with each accepted hit.
template <class Arch>
Hit oracle_closest(TriangleTest test, const Ray& ray, Hit hit, const Soup& soup, std::size_t first, std::size_t last) {
  float upper = hit.t < ray.tmax ? hit.t : ray.tmax;
  for (std::size_t t = first; t < last; ++t) {
    volley::core::TriHit<float> h;
    if (oracle<Arch>(test, ray, upper, soup, t, h)) {
      hit = {h.t, h.u, h.v, soup.ids[t]};
      upper = h.t;
    }
  }
  return hit;
}

/// Any hit by Arch's oracle over triangles first .. last within [tmin, tmax).
template <class Arch>
bool oracle_occluded(TriangleTest test, const Ray& ray, const Soup& soup, std::size_t first, std::size_t last) {
  for (std::size_t t = first; t < last; ++t) {
    volley::core::TriHit<float> h;
    if (oracle<Arch>(test, ray, ray.tmax, soup, t, h)) return true;
  }
  return false;
}

/// Counts of agreement between kernel and oracle hits, with the first disagreement kept
/// for the failure message.
struct Agreement {
  std::size_t compared = 0, hits = 0, mismatches = 0;
  std::uint32_t worst_ulps = 0;
  std::string first;
  void check(const Hit& got, const Hit& want, const Ray& ray, const std::string& where) {
    ++compared;
    hits += want.prim != kInvalidPrim;
    const std::uint32_t d = std::max({ulps(got.t, want.t), ulps(got.u, want.u), ulps(got.v, want.v)});
    const bool ok = got.prim == want.prim && d <= kMaxUlps;
    if (got.prim == want.prim && want.prim != kInvalidPrim) worst_ulps = std::max(worst_ulps, d);
    if (!ok && mismatches++ == 0) first = describe(got, want, ray, where);
  }
  void check_bool(bool got, bool want, const Ray& ray, const std::string& where) {
    ++compared;
    hits += want;
    if (got != want && mismatches++ == 0)
      first = where + ": occluded " + std::to_string(got) + ", oracle " + std::to_string(want) + " for ray " + str(ray);
  }
  static std::string str(const Ray& r) {
    char buf[256];
    std::snprintf(buf, sizeof buf, "org (%a %a %a) dir (%a %a %a) t [%a %a)", r.org[0], r.org[1], r.org[2], r.dir[0],
                  r.dir[1], r.dir[2], r.tmin, r.tmax);
    return buf;
  }
  static std::string describe(const Hit& got, const Hit& want, const Ray& ray, const std::string& where) {
    char buf[512];
    std::snprintf(buf, sizeof buf, "%s: kernel prim %u t %a u %a v %a, oracle prim %u t %a u %a v %a, ray %s",
                  where.c_str(), got.prim, got.t, got.u, got.v, want.prim, want.t, want.u, want.v, str(ray).c_str());
    return buf;
  }
};

/// Random triangles in [-1, 1]^3 (a mix of sizes and shapes) and rays aimed at them.
struct Generator {
  std::mt19937 rng;
  explicit Generator(unsigned seed) : rng(seed) {}
  float uniform(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
  V3 point(float r) { return V3(uniform(-r, r), uniform(-r, r), uniform(-r, r)); }

  /// n triangles: most of moderate size around random centres, some skinny, some tiny.
  Soup triangles(std::size_t n) {
    Soup s;
    for (std::size_t i = 0; i < n; ++i) {
      const V3 c = point(1.0f);
      const float size = integer(0, 9) == 0 ? 1e-3f : uniform(0.1f, 0.8f);
      V3 a = c + point(size), b = c + point(size), d = c + point(size);
      if (integer(0, 9) == 0) d = a + (b - a) * uniform(0.0f, 1.0f) + point(size * 1e-3f);  // skinny
      s.add(a, b, d);
    }
    return s;
  }

  /// A ray from a random origin toward a point near triangle t of `s` (barycentrics in
  /// [-0.1, 1.1], so about a third miss, many of them near an edge). tmin, tmax vary.
  Ray aimed(const Soup& s, std::size_t t) {
    const float bu = uniform(-0.1f, 1.1f), bv = uniform(-0.1f, 1.1f - bu);
    const V3 p0 = s.vertex(t, 0), p1 = s.vertex(t, 1), p2 = s.vertex(t, 2);
    const V3 target = p0 + bu * (p1 - p0) + bv * (p2 - p0);
    const V3 org = point(3.0f);
    V3 dir = (target - org) * uniform(0.25f, 4.0f);
    Ray r{{org.x, org.y, org.z}, 0.0f, {dir.x, dir.y, dir.z}, kInf};
    switch (integer(0, 5)) {
      case 0: r.tmax = uniform(0.0f, 2.0f); break;     // may end before the triangles
      case 1: r.tmin = uniform(0.0f, 1.0f); break;     // may start past them
      case 2: r.tmin = -kInf; break;                   // hits behind the origin count
      default: break;
    }
    return r;
  }
};

/// Writes `hit` into lane i of a hit packet.
template <int K>
void set_lane(volley::simd::HitPacket<K>& hp, int i, const Hit& h) {
  hp.t[i] = h.t, hp.u[i] = h.u, hp.v[i] = h.v, hp.prim[i] = h.prim;
}

}  // namespace simd_test

namespace simd_test {

/// Runs every kernel form of Test on Arch over all of `soup` for every ray of `rays` and
/// compares each answer with the oracle. Packets are the rays in order, K at a time (the
/// last one partial), for every K the ISA supports; per-lane hits start empty.
/// Returns the disagreements; also checks that no reported hit has a non-finite t, u, v.
template <class Arch, TriangleTest Test>
Agreement compare_all_forms(const Soup& soup, const std::vector<Ray>& rays, const std::string& label) {
  constexpr int W = kLanes<Arch>;
  const auto blocks = pack<Arch, Test>(soup);
  const auto nblocks = static_cast<std::uint32_t>(blocks.size());
  Agreement a;
  std::size_t non_finite = 0;
  const auto note = [&](const Hit& h) {
    if (h.prim != kInvalidPrim && !(std::isfinite(h.t) && std::isfinite(h.u) && std::isfinite(h.v))) ++non_finite;
  };
  std::vector<Hit> want(rays.size());
  std::vector<bool> want_occ(rays.size());
  for (std::size_t r = 0; r < rays.size(); ++r) {
    want[r] = oracle_closest<Arch>(Test, rays[r], Hit{}, soup, 0, soup.size());
    want_occ[r] = oracle_occluded<Arch>(Test, rays[r], soup, 0, soup.size());
    const auto pr = volley::simd::prepare_ray(rays[r], Test == TriangleTest::watertight);
    Hit got;
    volley::simd::RayBlockKernels<Arch, Test>::intersect(pr, blocks.data(), nblocks, got);
    note(got);
    a.check(got, want[r], rays[r], label + " 1 ray x block");
    a.check_bool(volley::simd::RayBlockKernels<Arch, Test>::occluded(pr, blocks.data(), nblocks), want_occ[r], rays[r],
                 label + " 1 ray x block occluded");
  }
  const auto run_packets = [&](auto k_tag) {
    constexpr int K = decltype(k_tag)::value;
    for (std::size_t first = 0; first < rays.size(); first += K) {
      const int count = static_cast<int>(std::min<std::size_t>(K, rays.size() - first));
      volley::simd::RayPacket<K> packet;
      volley::simd::load(packet, rays.data() + first, count);
      volley::simd::HitPacket<K> got, got_tri;
      volley::simd::reset(got);
      volley::simd::reset(got_tri);
      volley::simd::PreparedPacket<K> prepared;
      volley::simd::PacketKernels<Arch, Test, K>::prepare(packet, prepared);
      volley::simd::PacketKernels<Arch, Test, K>::intersect(prepared, blocks.data(), nblocks, got);
      for (std::uint32_t b = 0; b < nblocks; ++b)
        for (int j = 0; j < W; ++j) volley::simd::PacketKernels<Arch, Test, K>::intersect_triangle(prepared, blocks[b], j, got_tri);
      const std::uint32_t occ = volley::simd::PacketKernels<Arch, Test, K>::occluded(prepared, blocks.data(), nblocks, ~0u);
      for (int i = 0; i < K; ++i) {
        if (i >= count) {
          a.check(volley::simd::hit_of(got, i), Hit{}, volley::simd::ray_of(packet, i), label + " padding lane");
          CHECK(((occ >> i) & 1u) == 0u);
          continue;
        }
        const std::size_t r = first + static_cast<std::size_t>(i);
        const std::string lane = " K=" + std::to_string(K) + " lane " + std::to_string(i);
        note(volley::simd::hit_of(got, i));
        a.check(volley::simd::hit_of(got, i), want[r], rays[r], label + " packet x block" + lane);
        a.check(volley::simd::hit_of(got_tri, i), want[r], rays[r], label + " packet x triangle" + lane);
        a.check_bool(occ >> i & 1, want_occ[r], rays[r], label + " packet occluded" + lane);
      }
    }
  };
  if constexpr (4 % W == 0) run_packets(std::integral_constant<int, 4>{});
  if constexpr (8 % W == 0) run_packets(std::integral_constant<int, 8>{});
  run_packets(std::integral_constant<int, 16>{});
  CHECK(non_finite == 0);
  return a;
}

/// A closed, axis-aligned box surface with integer vertices: each face an n x n grid of
/// unit squares split into two triangles (alternating diagonals), offset by `offset`.
inline Soup grid_box(int n, float offset) {
  Soup s;
  const auto face = [&](int axis, float level, bool flip) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        V3 q[4];
        const int du[4] = {0, 1, 1, 0}, dv[4] = {0, 0, 1, 1};
        for (int c = 0; c < 4; ++c) {
          float p[3];
          p[axis] = level + offset;
          p[u] = static_cast<float>(i + du[c]) + offset;
          p[v] = static_cast<float>(j + dv[c]) + offset;
          q[c] = V3(p[0], p[1], p[2]);
        }
        const bool alt = (i + j) % 2 == 0;
        const int t0[3] = {0, 1, alt ? 2 : 3}, t1[3] = {alt ? 0 : 1, 2, 3};
        for (const int* t : {t0, t1}) {
          if (flip) s.add(q[t[0]], q[t[2]], q[t[1]]);
          else s.add(q[t[0]], q[t[1]], q[t[2]]);
        }
      }
  };
  for (int axis = 0; axis < 3; ++axis) {
    face(axis, 0.0f, true);
    face(axis, static_cast<float>(n), false);
  }
  return s;
}

}  // namespace simd_test
