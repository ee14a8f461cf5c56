// The type-erased facade (simd/triangle_kernels.h) every test x ISA: create, build with
// groups of every awkward size, and single-ray and packet queries per group against the
// oracle over the same group.
#include "simd/testing/triangle_kernels.h"

#include <cstring>

#include "simd_test_util.h"

namespace {

using namespace simd_test;
using volley::simd::BlockRange;
using volley::simd::TriangleKernels;

template <class Arch>
void facade_agrees(TriangleTest test) {
  constexpr int W = kLanes<Arch>;
  const auto kernels = TriangleKernels::create(test, volley::simd::kIsaOf<Arch>);
  REQUIRE(kernels);
  CHECK(kernels->width() == W);
  CHECK(kernels->test() == test);
  Generator g(41);
  const Soup soup = g.triangles(400);
  // Groups of 0, 1, W-1, W, W+1, 2W+3 triangles and random sizes.
  std::vector<std::uint32_t> groups{0};
  const int sizes[] = {0, 1, W - 1, W, W + 1, 2 * W + 3};
  for (int i = 0; groups.back() < soup.size(); ++i) {
    const int size = i < 6 ? sizes[i] : g.integer(1, 3 * W);
    groups.push_back(std::min<std::uint32_t>(static_cast<std::uint32_t>(soup.size()), groups.back() + size));
  }
  const auto ranges = kernels->build(soup.xyz.data(), soup.ids.data(), soup.size(), groups.data(), groups.size() - 1);
  REQUIRE(ranges.size() == groups.size() - 1);
  std::size_t blocks = 0;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    CHECK(ranges[i].first == blocks);
    CHECK(ranges[i].count == (groups[i + 1] - groups[i] + W - 1) / W);
    blocks += ranges[i].count;
  }
  CHECK(kernels->blocks() == blocks);
  Agreement a;
  const std::string where = name(test) + " facade";
  for (std::size_t gi = 0; gi < ranges.size(); ++gi) {
    const std::size_t first = groups[gi], last = groups[gi + 1];
    for (int p = 0; p < 8; ++p) {
      Ray rays[volley::simd::kPacketSize];
      for (Ray& r : rays) r = last > first ? g.aimed(soup, first + static_cast<std::size_t>(g.integer(0, int(last - first) - 1)))
                                           : g.aimed(soup, 0);
      volley::simd::Packet packet;
      volley::simd::load(packet, rays, volley::simd::kPacketSize - (p % 2));
      volley::simd::PacketHits hits, hits_prepared;
      volley::simd::reset(hits);
      volley::simd::reset(hits_prepared);
      kernels->intersect(packet, ranges[gi], hits);
      const std::uint32_t occ = kernels->occluded(packet, ranges[gi], packet.active);
      // The prepared form, as a traversal uses it: prepare once, query (twice here).
      volley::simd::PreparedPacket16 prepared;
      kernels->prepare(packet, prepared);
      kernels->intersect(prepared, ranges[gi], hits_prepared);
      kernels->intersect(prepared, ranges[gi], hits_prepared);
      CHECK(kernels->occluded(prepared, ranges[gi], packet.active) == occ);
      for (int i = 0; i < volley::simd::kPacketSize; ++i) {
        const Ray r = volley::simd::ray_of(packet, i);
        const bool active = packet.active >> i & 1;
        const Hit want = active ? oracle_closest<Arch>(test, r, Hit{}, soup, first, last) : Hit{};
        a.check(volley::simd::hit_of(hits, i), want, r, where + " packet");
        a.check(volley::simd::hit_of(hits_prepared, i), want, r, where + " prepared packet");
        a.check_bool(occ >> i & 1, active && oracle_occluded<Arch>(test, r, soup, first, last), r,
                     where + " packet occluded");
        if (!active) continue;
        Hit single;
        kernels->intersect(r, ranges[gi], single);
        a.check(single, want, r, where + " single");
        Hit prepared;
        kernels->intersect(kernels->prepare(r), ranges[gi], prepared);
        a.check(prepared, want, r, where + " prepared");
        a.check_bool(kernels->occluded(r, ranges[gi]), oracle_occluded<Arch>(test, r, soup, first, last), r,
                     where + " occluded");
      }
    }
  }
  INFO(a.first);
  CHECK(a.mismatches == 0);
  CHECK(a.hits > a.compared / 10);
}

}  // namespace

// (The facade picks kernels by Isa, so Avx512Ymm, an Isa::avx512 arch, has no facade of its own.)
TEST_CASE_TEMPLATE("TriangleKernels facade agrees with the oracle per group", Arch, volley::simd::Sse42,
                   volley::simd::Avx2, volley::simd::Avx512) {
  if (skip_isa<Arch>()) return;
  for (TriangleTest test : kTests) {
    INFO(name(test));
    facade_agrees<Arch>(test);
  }
}

// The packet walks hand few lanes to the single-ray walk with the packet's own shear
// (WideKernels::trace_lane), which must be the oracle's make_woop_ray lane by lane: the
// same axes and the same quotients, bit for bit, ties of |d| and signs included.
TEST_CASE_TEMPLATE("packet prepare: every lane's watertight shear is the oracle's", Arch, volley::simd::Sse42,
                   volley::simd::Avx2, volley::simd::Avx512) {
  if (skip_isa<Arch>()) return;
  const auto kernels = TriangleKernels::create(TriangleTest::watertight, volley::simd::kIsaOf<Arch>);
  REQUIRE(kernels);
  Generator g(7);
  std::vector<Ray> rays;
  const float sizes[] = {1.0f, 0.5f, 2.0f, 1e-20f, 3e20f};
  for (float x : sizes)
    for (float y : sizes)
      for (float z : sizes)
        for (int signs = 0; signs < 8; ++signs)
          rays.push_back(Ray{{1, 2, 3}, 0.0f, {signs & 1 ? -x : x, signs & 2 ? -y : y, signs & 4 ? -z : z}, 10.0f});
  for (int i = 0; i < 200; ++i) rays.push_back(g.aimed(g.triangles(1), 0));
  rays.push_back(Ray{{0, 0, 0}, 0.0f, {0.0f, -0.0f, 1.0f}, 1.0f});  // zero components
  rays.push_back(Ray{{0, 0, 0}, 0.0f, {-0.0f, 2.0f, 0.0f}, 1.0f});
  std::size_t wrong = 0;
  for (std::size_t first = 0; first < rays.size(); first += volley::simd::kPacketSize) {
    const std::size_t n = std::min<std::size_t>(volley::simd::kPacketSize, rays.size() - first);
    volley::simd::Packet packet;
    volley::simd::load(packet, rays.data() + first, n);
    volley::simd::PreparedPacket16 prepared;
    kernels->prepare(packet, prepared);
    for (std::size_t i = 0; i < n; ++i) {
      const volley::simd::PreparedRay want = volley::simd::prepare_ray(rays[first + i]);
      for (int a = 0; a < 3; ++a)
        wrong += prepared.k[a][i] != want.k[a] || std::memcmp(&prepared.s[a][i], &want.s[a], sizeof(float)) != 0;
    }
  }
  CHECK(wrong == 0);
}

TEST_CASE("TriangleKernels::create rejects unresolved ISAs and bad groups") {
  CHECK_THROWS_AS(TriangleKernels::create(TriangleTest::moller, volley::Isa::automatic), std::invalid_argument);
  CHECK_THROWS_AS(TriangleKernels::create(TriangleTest::moller, volley::Isa::scalar), std::invalid_argument);
  const auto k = TriangleKernels::create(TriangleTest::watertight, volley::simd::best_isa());
  REQUIRE(k);
  Soup soup;
  soup.add(V3(0, 0, 0), V3(1, 0, 0), V3(0, 1, 0));
  const std::uint32_t bad[] = {0, 2};  // past n = 1
  CHECK_THROWS_AS(k->build(soup.xyz.data(), soup.ids.data(), 1, bad, 1), std::invalid_argument);
  const std::uint32_t none[] = {0};
  CHECK(k->build(soup.xyz.data(), soup.ids.data(), 1, none, 0).empty());
  CHECK(k->bytes() == 0);
}
