// Lane-by-lane equivalence of the SIMD triangle kernels with the scalar oracle
// (src/core/triangle_*.h), for every test x ISA x form x packet size K the CPU runs, on
// random triangles and rays aimed at them: same hit/miss, same prim, t u v within kMaxUlps
// (0: bit-identical). Partial packets (1, K-1, K), inactive lanes and pre-existing hits are
// part of every packet run.
#include "simd_test_util.h"

namespace {

using namespace simd_test;

/// One ray x blocks, closest and any hit, against the oracle's loop over the same triangles.
template <class Arch, TriangleTest Test>
void single_ray(unsigned seed, int leaves, int rays_per_leaf) {
  constexpr int W = kLanes<Arch>;
  Generator g(seed);
  Agreement closest, any;
  const std::string where = name(Test) + " 1 ray x block";
  for (int leaf = 0; leaf < leaves; ++leaf) {
    // 2W - 3 triangles: one full block and one with 3 padding lanes.
    const Soup s = g.triangles(2 * W - 3);
    const auto blocks = pack<Arch, Test>(s);
    for (int k = 0; k < rays_per_leaf; ++k) {
      const Ray ray = g.aimed(s, static_cast<std::size_t>(g.integer(0, static_cast<int>(s.size()) - 1)));
      Hit hit;
      if (k % 4 == 0) hit = {g.uniform(0.0f, 5.0f), 0.25f, 0.5f, 77};  // an earlier hit to beat
      const auto pr = volley::simd::prepare_ray(ray, Test == TriangleTest::watertight);
      Hit got = hit;
      RayBlockKernels<Arch, Test>::intersect(pr, blocks.data(), static_cast<std::uint32_t>(blocks.size()), got);
      closest.check(got, oracle_closest<Arch>(Test, ray, hit, s, 0, s.size()), ray, where);
      any.check_bool(
          RayBlockKernels<Arch, Test>::occluded(pr, blocks.data(), static_cast<std::uint32_t>(blocks.size())),
          oracle_occluded<Arch>(Test, ray, s, 0, s.size()), ray, where + " (occluded)");
    }
  }
  INFO(closest.first);
  INFO(any.first);
  CHECK(closest.mismatches == 0);
  CHECK(any.mismatches == 0);
  CHECK(closest.worst_ulps <= kMaxUlps);
  // The generator must produce both answers in quantity (docs/accuracy.md, stress item 14).
  CHECK(closest.hits > closest.compared / 5);
  CHECK(closest.hits < closest.compared * 9 / 10);
}

/// K rays x blocks and K rays x one triangle, closest and any hit.
template <class Arch, TriangleTest Test, int K>
void packets(unsigned seed, int leaves, int packets_per_leaf) {
  constexpr int W = kLanes<Arch>;
  Generator g(seed);
  Agreement closest, per_triangle, sparse, any;
  std::size_t uniform_axes = 0, mixed_axes = 0;
  const std::string where = name(Test) + " packet K=" + std::to_string(K);
  for (int leaf = 0; leaf < leaves; ++leaf) {
    const Soup s = g.triangles(2 * W - 3);
    const auto blocks = pack<Arch, Test>(s);
    const auto nblocks = static_cast<std::uint32_t>(blocks.size());
    for (int k = 0; k < packets_per_leaf; ++k) {
      // Partial packets: 1, K - 1 or K rays; coherent (one origin, nearby targets) or not.
      const int count = k % 3 == 0 ? 1 : k % 3 == 1 ? K - 1 : K;
      const bool coherent = k % 2 == 0;
      Ray rays[K];
      const std::size_t target = static_cast<std::size_t>(g.integer(0, static_cast<int>(s.size()) - 1));
      const V3 shared_org = g.point(3.0f);
      for (int i = 0; i < count; ++i) {
        rays[i] = g.aimed(s, coherent ? target : static_cast<std::size_t>(g.integer(0, static_cast<int>(s.size()) - 1)));
        if (coherent) {
          const V3 to(rays[i].org[0] + rays[i].dir[0], rays[i].org[1] + rays[i].dir[1], rays[i].org[2] + rays[i].dir[2]);
          const V3 d = to - shared_org;
          rays[i].org[0] = shared_org.x, rays[i].org[1] = shared_org.y, rays[i].org[2] = shared_org.z;
          rays[i].dir[0] = d.x, rays[i].dir[1] = d.y, rays[i].dir[2] = d.z;
        }
      }
      RayPacket<K> packet;
      volley::simd::load(packet, rays, count);
      // Switch off a random lane now and then: it must stay untouched.
      if (k % 5 == 0) packet.active &= ~(1u << g.integer(0, K - 1));
      {
        int kz0 = -1;
        bool same = true;
        for (int i = 0; i < count; ++i) {
          if (!(packet.active >> i & 1)) continue;
          const auto w = volley::core::make_woop_ray(V3(rays[i].dir[0], rays[i].dir[1], rays[i].dir[2]));
          const int key = w.kz * 2 + (w.kx == (w.kz + 1) % 3 ? 0 : 1);
          same = same && (kz0 < 0 || kz0 == key);
          kz0 = key;
        }
        (same ? uniform_axes : mixed_axes)++;
      }
      HitPacket<K> start;
      volley::simd::reset(start);
      for (int i = 0; i < K; ++i)
        if (g.integer(0, 3) == 0) set_lane(start, i, Hit{g.uniform(0.0f, 5.0f), 0.25f, 0.5f, 77});

      HitPacket<K> got = start, got_tri = start, got_last = start;
      volley::simd::PreparedPacket<K> prepared;
      PacketKernels<Arch, Test, K>::prepare(packet, prepared);
      PacketKernels<Arch, Test, K>::intersect(prepared, blocks.data(), nblocks, got);
      // The last block cut short at `last` triangles (the walks' sparse leaf tails).
      const int last = g.integer(1, W - 3);
      const std::size_t last_end = static_cast<std::size_t>(W) * (nblocks - 1) + static_cast<std::size_t>(last);
      PacketKernels<Arch, Test, K>::intersect(prepared, blocks.data(), nblocks, got_last, last);
      for (std::uint32_t b = 0; b < nblocks; ++b)
        for (int j = 0; j < W; ++j) PacketKernels<Arch, Test, K>::intersect_triangle(prepared, blocks[b], j, got_tri);
      const std::uint32_t ask = packet.active & static_cast<std::uint32_t>(g.integer(0, (1 << K) - 1) | 1);
      const std::uint32_t occ = PacketKernels<Arch, Test, K>::occluded(prepared, blocks.data(), nblocks, ask);
      const std::uint32_t occ_last = PacketKernels<Arch, Test, K>::occluded(prepared, blocks.data(), nblocks, ask, last);
      for (int i = 0; i < K; ++i) {
        const Ray ray = volley::simd::ray_of(packet, i);
        const bool active = packet.active >> i & 1;
        const Hit before = volley::simd::hit_of(start, i);
        const Hit want = active ? oracle_closest<Arch>(Test, ray, before, s, 0, s.size()) : before;
        closest.check(volley::simd::hit_of(got, i), want, ray, where + " x block, lane " + std::to_string(i));
        per_triangle.check(volley::simd::hit_of(got_tri, i), want, ray, where + " x triangle, lane " + std::to_string(i));
        const Hit want_last = active ? oracle_closest<Arch>(Test, ray, before, s, 0, last_end) : before;
        sparse.check(volley::simd::hit_of(got_last, i), want_last, ray,
                     where + " x blocks to triangle " + std::to_string(last_end) + ", lane " + std::to_string(i));
        const bool want_occ = (ask >> i & 1) && oracle_occluded<Arch>(Test, ray, s, 0, s.size());
        any.check_bool(occ >> i & 1, want_occ, ray, where + " occluded, lane " + std::to_string(i));
        const bool want_occ_last = (ask >> i & 1) && oracle_occluded<Arch>(Test, ray, s, 0, last_end);
        any.check_bool(occ_last >> i & 1, want_occ_last, ray,
                       where + " occluded to triangle " + std::to_string(last_end) + ", lane " + std::to_string(i));
      }
    }
  }
  INFO(closest.first);
  INFO(per_triangle.first);
  INFO(sparse.first);
  INFO(any.first);
  CHECK(closest.mismatches == 0);
  CHECK(per_triangle.mismatches == 0);
  CHECK(sparse.mismatches == 0);
  CHECK(any.mismatches == 0);
  CHECK(closest.hits > closest.compared / 10);
  CHECK(uniform_axes > 0);
  CHECK(mixed_axes > 0);
}

template <class Arch, TriangleTest Test>
void all_forms(unsigned seed) {
  constexpr int L = kLanes<Arch>;
  // ~40k rays per (test, ISA) in the single-ray form, ~40k lanes per packet size.
  single_ray<Arch, Test>(seed, 640, 64);
  if constexpr (4 % L == 0) packets<Arch, Test, 4>(seed + 1, 640, 16);
  if constexpr (8 % L == 0) packets<Arch, Test, 8>(seed + 2, 320, 16);
  packets<Arch, Test, 16>(seed + 3, 160, 16);
}

}  // namespace

TEST_CASE_TEMPLATE("kernels agree with the scalar oracle lane by lane: moller", Arch, VOLLEY_TEST_ARCHES) {
  if (skip_isa<Arch>()) return;
  all_forms<Arch, TriangleTest::moller>(11);
}

TEST_CASE_TEMPLATE("kernels agree with the scalar oracle lane by lane: plane", Arch, VOLLEY_TEST_ARCHES) {
  if (skip_isa<Arch>()) return;
  all_forms<Arch, TriangleTest::plane>(22);
}

TEST_CASE_TEMPLATE("kernels agree with the scalar oracle lane by lane: watertight", Arch, VOLLEY_TEST_ARCHES) {
  if (skip_isa<Arch>()) return;
  all_forms<Arch, TriangleTest::watertight>(33);
}

// The rule: the Moller kernels fuse exactly where the ISA has an FMA instruction (AVX2,
// AVX-512; not SSE4.2, where it would be a libm call per lane), and each ISA is compared
// with the oracle variant core::moller_fused_for names for it. The scalar oracle's own
// default is unfused (x86-64-v2 build, no FMA). The bit-identity above is what proves the
// kernels fuse, or do not, as claimed (an xsimd::fma that silently splits into a multiply
// and an add, as 8.1's does on AVX-512, would pass any tolerance test): it can only fail
// if the fused and unfused oracles differ on such rays, which the case below checks.
template <class Arch>
constexpr bool fuses_by_the_rule() {
  using volley::simd::detail::kHasFma;
  using volley::simd::detail::kMollerFused;
  return kMollerFused<Arch> == kHasFma<Arch> &&
         kMollerFused<Arch> == volley::core::moller_fused_for(volley::simd::kIsaOf<Arch>);
}
static_assert(fuses_by_the_rule<volley::simd::Sse42>() && fuses_by_the_rule<volley::simd::Avx2>() &&
                  fuses_by_the_rule<volley::simd::Avx512>() &&
                  fuses_by_the_rule<volley::simd::Avx512Ymm>(),
              "the Moller kernels fuse where the ISA has FMA, and the oracle's variant for each ISA must match");
static_assert(!volley::simd::detail::kHasFma<volley::simd::Sse42> &&
                  volley::simd::detail::kHasFma<volley::simd::Avx2> &&
                  volley::simd::detail::kHasFma<volley::simd::Avx512>,
              "FMA: AVX2 (fma3) and AVX-512 have it, SSE4.2 does not");
static_assert(!volley::core::kMollerFused &&
                  volley::core::kMollerFused == volley::core::moller_fused_for(volley::Isa::scalar),
              "the scalar oracle's default is unfused (no FMA in the x86-64-v2 baseline)");

TEST_CASE("moller oracle: the fused and unfused variants differ, so bit-identity checks the FMA") {
  Generator g(44);
  std::size_t hits = 0, differ = 0;
  for (int leaf = 0; leaf < 64; ++leaf) {
    const Soup s = g.triangles(16);
    for (int k = 0; k < 64; ++k) {
      const std::size_t t = static_cast<std::size_t>(g.integer(0, static_cast<int>(s.size()) - 1));
      const Ray ray = g.aimed(s, t);
      const volley::core::RayT<float> r{V3(ray.org[0], ray.org[1], ray.org[2]), ray.tmin,
                                        V3(ray.dir[0], ray.dir[1], ray.dir[2]), ray.tmax};
      volley::core::TriHit<float> fused{}, unfused{};
      const bool a =
          volley::core::intersect_moller<float, true>(r, s.vertex(t, 0), s.vertex(t, 1), s.vertex(t, 2), fused);
      const bool b =
          volley::core::intersect_moller<float, false>(r, s.vertex(t, 0), s.vertex(t, 1), s.vertex(t, 2), unfused);
      if (!(a && b)) continue;
      ++hits;
      differ += ulps(fused.t, unfused.t) != 0 || ulps(fused.u, unfused.u) != 0 || ulps(fused.v, unfused.v) != 0;
    }
  }
  MESSAGE("moller fused vs unfused: t, u or v differ in " << differ << " of " << hits << " hits");
  CHECK(hits > 1000);
  CHECK(differ > hits / 10);
}
