// SoA packets and triangle blocks: AoS conversion, inert padding, alignment, and the
// block packing (values the oracle computes, NaN padding, degenerate lanes).
#include "simd/rays/packet_convert.h"
#include "simd_test_util.h"

namespace {

using namespace simd_test;

template <int K>
void packet_round_trip() {
  Ray rays[K];
  for (int i = 0; i < K; ++i) rays[i] = Ray{{float(i), 1.0f, 2.0f}, 0.5f, {0.0f, -1.0f, float(i)}, 9.0f + float(i)};
  for (int count : {0, 1, K - 1, K}) {
    RayPacket<K> p;
    volley::simd::load(p, rays, count);
    CHECK(reinterpret_cast<std::uintptr_t>(&p) % 64 == 0);
    CHECK(p.active == volley::simd::lane_bits(count));
    for (int i = 0; i < K; ++i) {
      const Ray r = volley::simd::ray_of(p, i);
      if (i < count) {
        CHECK(std::memcmp(&r, &rays[i], sizeof r) == 0);
      } else {
        CHECK(r.tmax == -kInf);  // inert: nothing lies in [tmin, -inf)
        CHECK(r.dir[0] == 0.0f);
      }
    }
  }
  HitPacket<K> h;
  volley::simd::reset(h);
  for (int i = 0; i < K; ++i) CHECK(!volley::simd::hit_of(h, i).hit());
  set_lane(h, 1 % K, Hit{2.0f, 0.25f, 0.5f, 42});
  Hit out[K];
  volley::simd::store(h, out, K);
  CHECK(out[1 % K].prim == 42);
  CHECK(out[1 % K].t == 2.0f);
}

/// Rays whose floats are all different bit patterns, NaN payloads, infinities and -0
/// among them, starting 4 bytes past a 64-byte line (the whole-packet loads are unaligned).
struct OddRays {
  alignas(64) unsigned char bytes[sizeof(Ray) * 17 + 4];
  const Ray* rays() const { return reinterpret_cast<const Ray*>(bytes + 4); }
  OddRays() {
    const float specials[] = {std::numeric_limits<float>::quiet_NaN(), kInf, -kInf, -0.0f,
                              std::numeric_limits<float>::denorm_min()};
    for (int i = 0; i < 17 * 8; ++i) {
      std::uint32_t b = std::bit_cast<std::uint32_t>(float(i) * 1.25f - 40.0f);
      if (i % 7 == 3) b = std::bit_cast<std::uint32_t>(specials[(i / 7) % 5]) ^ (i % 2 ? 0x5u : 0u);
      std::memcpy(bytes + 4 + 4 * i, &b, 4);
    }
  }
};

/// Every ISA's whole-packet load against the header's lane-by-lane template, bit for bit,
/// and the library's load (the overload) for every count.
template <int K>
void whole_packet_loads(const OddRays& src) {
  RayPacket<K> expect;
  volley::load<K>(expect, src.rays(), K);
  const auto same = [](const RayPacket<K>& a, const RayPacket<K>& b) {
    return std::memcmp(&a, &b, offsetof(RayPacket<K>, active)) == 0 && a.active == b.active;
  };
  const auto check_isa = [&](auto arch) {
    using Arch = decltype(arch);
    if (!volley::simd::cpu_has(volley::simd::kIsaOf<Arch>)) return;
    RayPacket<K> got;
    std::memset(&got, 0xab, sizeof got);
    volley::simd::PacketConvert<Arch>::whole(got, src.rays());
    CAPTURE(K);
    CAPTURE(volley::simd::kIsaOf<Arch>);
    CHECK(same(got, expect));
  };
  check_isa(volley::simd::Sse42{});
  check_isa(volley::simd::Avx2{});
  check_isa(volley::simd::Avx512{});
  for (int count = 0; count <= K; ++count) {
    RayPacket<K> lanes, got;
    volley::load<K>(lanes, src.rays(), count);
    std::memset(&got, 0xab, sizeof got);
    volley::load(got, src.rays(), count);
    CAPTURE(count);
    CHECK(same(got, lanes));
  }
}

/// A packet of 16 hits whose fields are all different bit patterns (NaN payloads among
/// them): AVX-512's whole-packet store and the library's store for every count against the
/// header's lane-by-lane template, record by record.
void whole_packet_stores() {
  HitPacket<16> hits;
  for (int i = 0; i < 16; ++i) {
    hits.t[i] = i % 5 == 2 ? std::bit_cast<float>(0x7fc00000u + std::uint32_t(i)) : float(i) + 0.5f;
    hits.u[i] = -float(i) * 0.25f;
    hits.v[i] = i % 3 == 0 ? -0.0f : float(i) * 0.125f;
    hits.prim[i] = 1000u + std::uint32_t(i);
    hits.geom[i] = 2000u + std::uint32_t(i);
    hits.inst[i] = i % 4 == 0 ? volley::kInvalidId : 3000u + std::uint32_t(i);
  }
  // Filled with a byte pattern through void*: Hit is trivially copyable but has default
  // member values, which -Wclass-memaccess would flag for a memset through Hit*.
  Hit expect[17], got[17];
  std::memset(static_cast<void*>(expect), 0xcd, sizeof expect);
  volley::store<16>(hits, expect, 16);
  if (volley::simd::cpu_has(volley::Isa::avx512)) {
    std::memset(static_cast<void*>(got), 0xcd, sizeof got);
    volley::simd::PacketConvert<volley::simd::Avx512>::store(hits, got);
    CHECK(std::memcmp(got, expect, sizeof got) == 0);  // record 16 untouched
  }
  for (int count = 0; count <= 16; ++count) {
    std::memset(static_cast<void*>(expect), 0xcd, sizeof expect);
    volley::store<16>(hits, expect, count);
    std::memset(static_cast<void*>(got), 0xcd, sizeof got);
    volley::store(hits, got, count);
    CAPTURE(count);
    CHECK(std::memcmp(got, expect, sizeof got) == 0);
  }
}

}  // namespace

TEST_CASE("a whole packet of hits stores by a transpose as the lane-by-lane store does") {
  whole_packet_stores();
}

TEST_CASE("whole packets load by transposes as the lane-by-lane load does, on every ISA") {
  const OddRays src;
  whole_packet_loads<4>(src);
  whole_packet_loads<8>(src);
  whole_packet_loads<16>(src);
}

TEST_CASE("ray packets load AoS rays, make padding lanes inert, store hits back") {
  packet_round_trip<4>();
  packet_round_trip<8>();
  packet_round_trip<16>();
}

TEST_CASE_TEMPLATE("blocks hold the oracle's values, NaN padding and invalid ids", Arch, VOLLEY_TEST_ARCHES) {
  // Packing is baseline code: no ISA needed, but the width follows Arch.
  constexpr int W = kLanes<Arch>;
  Generator g(1);
  Soup soup = g.triangles(W + 2);
  soup.add(V3(0, 0, 0), V3(1, 0, 0), V3(2, 0, 0), 999);  // zero area
  const auto m = pack<Arch, TriangleTest::moller>(soup);
  const auto p = pack<Arch, TriangleTest::plane>(soup);
  const auto w = pack<Arch, TriangleTest::watertight>(soup);
  REQUIRE(m.size() == 2);
  for (const void* b : {(const void*)m.data(), (const void*)p.data(), (const void*)w.data()})
    CHECK(reinterpret_cast<std::uintptr_t>(b) % 64 == 0);
  for (std::size_t t = 0; t < soup.size(); ++t) {
    const std::size_t b = t / W, i = t % W;
    const V3 p0 = soup.vertex(t, 0), p1 = soup.vertex(t, 1), p2 = soup.vertex(t, 2);
    const V3 e1 = p1 - p0, e2 = p2 - p0, n = glm::cross(e1, e2);
    CHECK(m[b].prim[i] == soup.ids[t]);
    CHECK(m[b].v0[0][i] == p0.x);
    CHECK(m[b].ne2[2][i] == -e2.z);
    CHECK(m[b].n[1][i] == n.y);
    const auto pt = volley::core::PlaneTriangle<float>::from(p0, p1, p2);
    CHECK(p[b].v0[1][i] == pt.p0.y);
    CHECK(p[b].n[2][i] == pt.n.z);
    CHECK(p[b].n1[1][i] == pt.n1.y);
    CHECK(p[b].n2[0][i] == pt.n2.x);
    if (soup.ids[t] == 999) {
      CHECK(std::isnan(w[b].p[1][1][i]));  // zero area: a NaN lane
    } else {
      CHECK(w[b].p[2][1][i] == p2.y);
    }
  }
  for (std::size_t t = soup.size(); t < 2 * W; ++t) {
    const std::size_t i = t % W;
    CHECK(m[1].prim[i] == kInvalidPrim);
    CHECK(std::isnan(m[1].v0[0][i]));
    CHECK(std::isnan(m[1].n[2][i]));
    CHECK(std::isnan(p[1].v0[0][i]));
    CHECK(std::isnan(p[1].n2[2][i]));
    CHECK(std::isnan(w[1].p[0][0][i]));
    CHECK(w[1].prim[i] == kInvalidPrim);
  }
}
