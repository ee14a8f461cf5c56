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

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <vector>

#include "capi_case.h"
#include "capi_compare.h"
#include "volley/volley.h"

using namespace fuzz_capi;

namespace {

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
