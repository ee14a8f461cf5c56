// libFuzzer target: the C API driven by the fuzzer's bytes, and a differential check of
// its answers. The bytes build a scene (triangles with arbitrary floats and indices,
// polygons), commit it with any options (bad enum values included), then trace rays
// (arbitrary, or aimed exactly at vertices and edge midpoints) in every form: single,
// packets of 4, 8 and 16 with partial masks, streams, occlusion. A crash, a sanitizer
// report, a status other than the documented ones, or a wrong answer is a finding:
//
// - Every form of the committed scene agrees with its single-ray closest hit, and
//   occlusion with hit/miss; packets leave inactive lanes untouched; every t lies in
//   [tmin, tmax).
// - Where the scalar oracle is the kernels' exact twin (SSE4.2 for every test, the plane
//   test at every ISA: no fused products), the answers equal the oracle's, committed as
//   VOLLEY_ISA_SCALAR with the same test: same hit or miss; the same prim with the same
//   t, u, v, or another prim at a t within 2 ulps (two overlapping coplanar triangles
//   that the walks meet in different orders: accel.h). AVX2 and AVX-512 fuse the
//   Möller and watertight products, which may move a hit by rounding
//   (ACCURACY.md), so there only the first rules apply.
#include <fuzzer/FuzzedDataProvider.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

#include "volley/volley.h"

namespace {

[[noreturn]] void finding(const char* what, std::size_t ray) {
  std::fprintf(stderr, "fuzz_capi: %s (ray %zu)\n", what, ray);
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
  if (kind == 6) return in.ConsumeFloatingPointInRange(-16.0f, 16.0f);
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
volley_status add(volley_scene* scene, const Geometry& g) {
  volley_status first_error = VOLLEY_OK;
  const volley_status s = volley_scene_add_triangles(scene, g.xyz.data(), g.xyz.size() / 3, g.indices.data(),
                                                     g.indices.size() / 3, nullptr);
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

bool same_bits(const volley_hit& a, const volley_hit& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// `got` and `want` answer the same ray alike: both miss, or the same prim at the same t
/// (and u, v when `exact`), or two prims within 2 ulps of t (a coplanar tie).
bool agree(const volley_hit& got, const volley_hit& want, bool exact) {
  const bool got_hit = got.prim != VOLLEY_INVALID_PRIM, want_hit = want.prim != VOLLEY_INVALID_PRIM;
  if (got_hit != want_hit) return false;
  if (!got_hit) return true;
  if (got.prim == want.prim) return exact ? same_bits(got, want) : got.t == want.t;
  return within_ulps(got.t, want.t, 2);
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
      h.t[i] = 12345.0f, h.prim[i] = 0xdeadbeefu;
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
            std::memcmp(&h.v[i], &before.v[i], 4) || h.prim[i] != before.prim[i] || ((blocked >> i) & 1u))
          finding("a packet wrote an inactive lane", r);
        continue;
      }
      // An active lane that finds nothing keeps its sentinel t (12345 bounds its search).
      const volley_hit want = single[r];
      const bool nearer = want.prim != VOLLEY_INVALID_PRIM && want.t < 12345.0f;
      const volley_hit got{h.t[i], h.u[i], h.v[i], h.prim[i]};
      if (nearer ? !agree(got, want, true) : got.prim != 0xdeadbeefu) finding("a packet lane disagrees", r);
      if (((blocked >> i) & 1u) != (want.prim != VOLLEY_INVALID_PRIM ? 1u : 0u))
        finding("packet occlusion disagrees with the closest hit", r);
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
    if (!agree(stream[i], single[i], true)) finding("stream disagrees with intersect1", i);
    if (blocked[i] != (single[i].prim != VOLLEY_INVALID_PRIM ? 1 : 0)) finding("stream occlusion disagrees", i);
  }
  return single;
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
  const Geometry geometry = make_geometry(in);

  volley_scene* scene = nullptr;
  volley_scene* oracle = nullptr;
  if (volley_scene_create(&scene) != VOLLEY_OK || volley_scene_create(&oracle) != VOLLEY_OK)
    finding("scene_create failed", 0);
  const volley_status added = add(scene, geometry);
  if (add(oracle, geometry) != added) finding("the same geometry gave two statuses", 0);
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
    const std::vector<volley_hit> got = trace_all_forms(scene, rays, in);

    // The oracle twin: plane everywhere, and SSE4.2's unfused Möller and watertight.
    const bool twin = !options.reference_double &&
                      (options.test == VOLLEY_TEST_PLANE || info.isa == VOLLEY_ISA_SSE42 || info.isa == VOLLEY_ISA_SCALAR);
    volley_commit_options scalar = options;
    scalar.isa = VOLLEY_ISA_SCALAR;
    if (twin && volley_scene_commit_ex(oracle, &scalar) == VOLLEY_OK) {
      for (std::size_t i = 0; i < rays.size(); ++i) {
        volley_hit want;
        if (volley_intersect1(oracle, &rays[i], &want) != VOLLEY_OK) finding("oracle intersect1 failed", i);
        if (!agree(got[i], want, true)) {
          std::fprintf(stderr, "got prim %u t %a, oracle prim %u t %a\n", got[i].prim, got[i].t, want.prim, want.t);
          finding("SIMD answer differs from the scalar oracle", i);
        }
      }
    }
  }
  volley_scene_destroy(scene);
  volley_scene_destroy(oracle);
  return 0;
}
