// Pins the watertight test's scaled range prefilter (src/core/triangle_watertight.h): the
// upper end t det <= fl(upper |det|) with no widening, the lower end with tmin widened, and
// the kernels' division-free any-hit decision (simd/triangle/watertight.h, sure_hit). Rays whose
// quotient t lands exactly on, one ulp below and one ulp above either end of [tmin, tmax),
// at scales where t det and upper |det| are subnormal, must give exactly the answer of the
// quotient alone, tmin <= t < tmax: in the oracle, and in every kernel form of every ISA.
// The quotient test itself is checked against exact long-double arithmetic.
#include <cmath>

#include "core/triangle_watertight.h"
#include "simd_test_util.h"

namespace {

using namespace simd_test;
using RayF = volley::core::RayT<float>;

float up(float x) { return std::nextafter(x, kInf); }
float down(float x) { return std::nextafter(x, -kInf); }

/// The oracle's scaled distance t det and det for a ray it hits (the same float operations,
/// products rounded, and the double fallback for an edge function of 0).
struct Scaled {
  float ts, det;
};
Scaled scaled(const RayF& ray, const V3& p0, const V3& p1, const V3& p2) {
  const auto w = volley::core::make_woop_ray(ray.dir);
  const V3 a = p0 - ray.org, b = p1 - ray.org, c = p2 - ray.org;
  const float ax = a[w.kx] - w.sx * a[w.kz], ay = a[w.ky] - w.sy * a[w.kz];
  const float bx = b[w.kx] - w.sx * b[w.kz], by = b[w.ky] - w.sy * b[w.kz];
  const float cx = c[w.kx] - w.sx * c[w.kz], cy = c[w.ky] - w.sy * c[w.kz];
  float eu = cx * by - cy * bx, ev = ax * cy - ay * cx, ew = bx * ay - by * ax;
  if (eu == 0 || ev == 0 || ew == 0) {  // the oracle's exact fallback
    eu = float(double(cx) * double(by) - double(cy) * double(bx));
    ev = float(double(ax) * double(cy) - double(ay) * double(cx));
    ew = float(double(bx) * double(ay) - double(by) * double(ax));
  }
  const float az = w.sz * a[w.kz], bz = w.sz * b[w.kz], cz = w.sz * c[w.kz];
  return {eu * az + ev * bz + ew * cz, eu + ev + ew};
}

/// A ray and one triangle it hits at t (by the oracle with [-inf, inf)), at a scale.
struct Case {
  Ray ray;
  V3 p0, p1, p2;
  float t;
};

/// Random triangles hit near their centroid, scaled by `scale` (coordinates) and `dscale`
/// (direction: t scales by 1 / dscale). Scales near 1e-20 make det and upper |det| subnormal.
/// `fused`: t by the oracle's fused variant (core::watertight_fused_for), as the FMA ISAs'
/// kernels compute it.
std::vector<Case> cases(unsigned seed, float scale, float dscale, int n, bool fused = false) {
  Generator g(seed);
  std::vector<Case> out;  // fewer than n when the scale leaves few hits (checked by the callers)
  for (int tries = 0; tries < 50 * n && static_cast<int>(out.size()) < n; ++tries) {
    const V3 c = g.point(1.0f) * scale;
    const V3 p0 = c + g.point(0.5f) * scale, p1 = c + g.point(0.5f) * scale, p2 = c + g.point(0.5f) * scale;
    const V3 target = (p0 + p1 + p2) / 3.0f;
    const V3 org = g.point(3.0f) * scale;
    const V3 dir = (target - org) * dscale;
    const RayF r{org, -kInf, dir, kInf};
    volley::core::TriHit<float> h;
    const bool hit = fused ? volley::core::intersect_watertight<float, true>(r, p0, p1, p2, h)
                           : volley::core::intersect_watertight<float, false>(r, p0, p1, p2, h);
    if (!hit || !(h.t > 0) || !std::isfinite(h.t)) continue;
    out.push_back({Ray{{org.x, org.y, org.z}, 0.0f, {dir.x, dir.y, dir.z}, kInf}, p0, p1, p2, h.t});
  }
  return out;
}

/// The interval ends tried around a hit at t: on it, one ulp either side, and the usual ends.
std::vector<std::pair<float, float>> intervals(float t) {
  std::vector<std::pair<float, float>> out;
  for (float tmax : {t, up(t), down(t), up(up(t)), kInf}) out.push_back({0.0f, tmax});
  for (float tmin : {t, up(t), down(t), -0.0f, -kInf, -t, t * 0.5f}) out.push_back({tmin, kInf});
  out.push_back({down(t), up(t)});
  out.push_back({t, up(t)});
  return out;
}

TEST_CASE("watertight oracle: the prefilter never decides, the quotient agrees with long double") {
  std::size_t compared = 0, subnormal_bound = 0, tight_bound = 0;
  for (float scale : {1.0f, 1e-13f, 1e-19f, 1e-20f, 1e-21f, 1e15f})
    for (float dscale : {1.0f, 1e-6f, 1e6f}) {
      for (const Case& c : cases(17, scale, dscale, 200)) {
        const Scaled s = scaled(RayF{V3(c.ray.org[0], c.ray.org[1], c.ray.org[2]), -kInf,
                                     V3(c.ray.dir[0], c.ray.dir[1], c.ray.dir[2]), kInf},
                                c.p0, c.p1, c.p2);
        INFO("scale ", scale, " dscale ", dscale, " t ", c.t);
        REQUIRE(float(double(s.ts) / double(s.det)) == c.t);  // the test's copy of the oracle's steps
        const float ad = std::abs(s.det), ts_s = s.det < 0 ? -s.ts : s.ts;
        for (const auto& interval : intervals(c.t)) {
          // Named copies, not a structured binding: INFO captures them in a lambda (clang 14).
          const float tmin = interval.first, tmax = interval.second;
          const RayF r{V3(c.ray.org[0], c.ray.org[1], c.ray.org[2]), tmin, V3(c.ray.dir[0], c.ray.dir[1], c.ray.dir[2]),
                       tmax};
          volley::core::TriHit<float> h;
          const bool got = volley::core::intersect_watertight(r, c.p0, c.p1, c.p2, h);
          const bool want = tmin <= c.t && c.t < tmax;
          ++compared;
          INFO("[", tmin, ", ", tmax, ")");
          REQUIRE(got == want);
          if (got) REQUIRE(h.t == c.t);
          if (!want || !std::isfinite(tmax)) continue;
          // t < tmax in float means t det < tmax |det| exactly (long double products of floats
          // are exact), hence t det <= fl(tmax |det|): the unwidened bound holds.
          const long double exact_bound = static_cast<long double>(tmax) * static_cast<long double>(ad);
          REQUIRE(static_cast<long double>(ts_s) < exact_bound);
          const float bound = tmax * ad;
          REQUIRE(ts_s <= bound);
          subnormal_bound += std::fpclassify(bound) == FP_SUBNORMAL;
          tight_bound += ts_s == bound;  // a strict ts < fl(tmax |det|) would have missed it
        }
      }
    }
  MESSAGE(compared << " intervals; " << subnormal_bound << " hits with a subnormal upper |det|, " << tight_bound
                   << " with t det == fl(tmax |det|)");
  CHECK(subnormal_bound > 100);  // the scales reach subnormal products
  CHECK(tight_bound > 100);      // and the bound is met with equality: it cannot be strict
}

/// Every kernel form of Arch on each case and interval: hit/miss and t as the quotient says.
template <class Arch>
void kernels_pin() {
  constexpr int W = kLanes<Arch>;
  constexpr TriangleTest kWt = TriangleTest::watertight;
  constexpr bool kFused = volley::core::watertight_fused_for(volley::simd::kIsaOf<Arch>);
  Agreement single, any, packet, packet_any;
  for (float scale : {1.0f, 1e-19f, 1e-20f, 1e-21f, 1e15f})
    for (float dscale : {1.0f, 1e-6f, 1e6f})
      for (const Case& c : cases(29, scale, dscale, 60, kFused)) {
        // The triangle alone in a block, and at the last lane of a full one whose other
        // triangles are far off the ray.
        Soup alone, last;
        alone.add(c.p0, c.p1, c.p2, 7);
        for (int i = 0; i + 1 < W; ++i) {
          const V3 far(1e30f, 1e30f, 1e30f);
          last.add(far, far + V3(1, 0, 0), far + V3(0, 1, 0));
        }
        last.add(c.p0, c.p1, c.p2, 7);
        for (const Soup* soup : {&alone, &last}) {
          const auto blocks = pack<Arch, kWt>(*soup);
          const auto nblocks = static_cast<std::uint32_t>(blocks.size());
          for (const auto& [tmin, tmax] : intervals(c.t)) {
            Ray ray = c.ray;
            ray.tmin = tmin, ray.tmax = tmax;
            const bool want = tmin <= c.t && c.t < tmax;
            const Hit want_hit = want ? oracle_closest<Arch>(kWt, ray, Hit{}, *soup, 0, soup->size()) : Hit{};
            const auto pr = volley::simd::prepare_ray(ray, true);
            Hit got;
            RayBlockKernels<Arch, kWt>::intersect(pr, blocks.data(), nblocks, got);
            single.check(got, want_hit, ray, "1 ray x block");
            any.check_bool(RayBlockKernels<Arch, kWt>::occluded(pr, blocks.data(), nblocks), want, ray,
                           "1 ray x block (occluded)");
            // A packet of 16 rays: this one in lane 5, the others inactive or with tmax = 0.
            constexpr int K = 16;
            Ray lanes[K];
            for (int i = 0; i < K; ++i) {
              lanes[i] = ray;
              if (i != 5) lanes[i].tmax = 0.0f;
            }
            RayPacket<K> rays;
            volley::simd::load(rays, lanes, K);
            rays.active &= ~(1u << 9);
            volley::simd::PreparedPacket<K> prepared;
            PacketKernels<Arch, kWt, K>::prepare(rays, prepared);
            HitPacket<K> hits;
            volley::simd::reset(hits);
            PacketKernels<Arch, kWt, K>::intersect(prepared, blocks.data(), nblocks, hits);
            packet.check(volley::simd::hit_of(hits, 5), want_hit, ray, "16 rays x block, lane 5");
            const std::uint32_t occ = PacketKernels<Arch, kWt, K>::occluded(prepared, blocks.data(), nblocks, 0xffffu);
            packet_any.check_bool(occ == (want ? 1u << 5 : 0u), true, ray, "16 rays x block occluded (only lane 5)");
          }
        }
      }
  for (const Agreement* a : {&single, &any, &packet, &packet_any}) {
    INFO(a->first);
    CHECK(a->mismatches == 0);
  }
  CHECK(any.hits > any.compared / 4);
  CHECK(any.hits < any.compared * 9 / 10);
}

TEST_CASE_TEMPLATE("watertight kernels: hits at either end of the interval decided as the quotient says", Arch,
                   VOLLEY_TEST_ARCHES) {
  if (skip_isa<Arch>()) return;
  kernels_pin<Arch>();
}

}  // namespace
