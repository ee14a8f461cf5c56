// The query protocol's concepts (simd/wide/query_protocol.h): every query the walks are
// given satisfies its concept, and a type that breaks one rule of it does not. (Built with
// SSE4.2 enabled, the least of the kernels' ISAs, so that the kernels' types are complete.)
#include <doctest/doctest.h>

#include <cstdint>

#include "simd/wide/wide_traverse.h"

namespace volley::simd {
namespace {

using Kernels = WideKernels<Sse42, TriangleTest::watertight>;
using Block = Kernels::Block;
using Float = Kernels::Float;
using detail::LanesStep;
using detail::LeafStep;
using detail::PacketQuery;
using detail::RayQuery;
using detail::StreamQuery;

struct NoSink {
  void operator()(std::uint32_t, float, float, float) const {}
  void operator()(int, std::uint32_t, float, float, float) const {}
};

/// A single-ray query that keeps every rule but one: it does not say kSureRange.
struct RayWithoutSureRange {
  static constexpr bool kNearFirst = true;
  float bound(const Ray& ray) const { return ray.tmax; }
  void node() {}
  LeafStep leaf(const PreparedRay&, const Block*, std::uint32_t, float&) { return LeafStep::go_on; }
  bool answer() const { return false; }
};
/// A single-ray query that keeps every rule; the ones below each break one.
struct GoodRay : RayWithoutSureRange {
  static constexpr bool kSureRange = false;
};
struct RayWithoutAnswer : GoodRay {
  void answer() = delete;
};
struct RayLeafReturnsBool : GoodRay {
  bool leaf(const PreparedRay&, const Block*, std::uint32_t, float&) { return false; }
};
/// Its bound changes the query, so the walk (which calls it on a const query) cannot.
struct RayMutableBound : GoodRay {
  float bound(const Ray& ray) { return ray.tmax; }
};

struct PacketWithoutSingle {
  static constexpr bool kNearFirst = false;
  Float bound(int, Float tmax) const { return tmax; }
  LanesStep leaf(PreparedPacket<Kernels::K>&, const Block*, std::uint32_t, std::uint32_t, Float*) { return {0, false}; }
};

struct StreamWithoutDone {
  using Single = detail::AnyHitRay<Kernels>;
  static constexpr bool kNearFirst = false;
  float bound(std::size_t, const Ray& ray) const { return ray.tmax; }
  Single single(std::uint32_t) const { return Single{}; }
};

}  // namespace

TEST_CASE("query protocol: every single-ray query the walks take satisfies RayQuery") {
  CHECK(RayQuery<detail::ClosestHitRay<Kernels>, Block>);
  CHECK(RayQuery<detail::AnyHitRay<Kernels>, Block>);
  CHECK(RayQuery<detail::AllHitsRay<Kernels, NoSink>, Block>);
  CHECK(RayQuery<detail::CountingRay<Kernels, detail::ClosestHitRay<Kernels>>, Block>);
  CHECK(RayQuery<detail::InstancesRay<true, false>, std::uint32_t>);
  CHECK(RayQuery<detail::InstancesRay<false, true>, std::uint32_t>);
  CHECK(RayQuery<GoodRay, Block>);
  // A query over triangle blocks is not one over a top level's instance ids.
  CHECK_FALSE(RayQuery<detail::ClosestHitRay<Kernels>, std::uint32_t>);
}

TEST_CASE("query protocol: a type that breaks one rule is not a RayQuery") {
  CHECK_FALSE(RayQuery<RayWithoutAnswer, Block>);
  CHECK_FALSE(RayQuery<RayLeafReturnsBool, Block>);
  CHECK_FALSE(RayQuery<RayWithoutSureRange, Block>);
  CHECK_FALSE(RayQuery<RayMutableBound, Block>);
}

TEST_CASE("query protocol: packet and stream queries satisfy their concepts, incomplete ones do not") {
  CHECK(PacketQuery<detail::ClosestHitPacket<Kernels>, Kernels, Block>);
  CHECK(PacketQuery<detail::AnyHitPacket<Kernels>, Kernels, Block>);
  CHECK(PacketQuery<detail::AllHitsPacket<Kernels, NoSink>, Kernels, Block>);
  CHECK(PacketQuery<detail::InstancesPacket<Kernels, true>, Kernels, std::uint32_t>);
  CHECK(PacketQuery<detail::InstancesPacket<Kernels, false>, Kernels, std::uint32_t>);
  CHECK_FALSE(PacketQuery<PacketWithoutSingle, Kernels, Block>);
  CHECK_FALSE(PacketQuery<detail::InstancesPacket<Kernels, true>, Kernels, Block>);

  CHECK(StreamQuery<detail::AnyHitStream<Kernels>, Kernels>);
  CHECK(StreamQuery<detail::ClosestHitStream<Kernels>, Kernels>);
  CHECK_FALSE(StreamQuery<StreamWithoutDone, Kernels>);
  // A stream query's rays are answered by single-ray queries: a packet query is not one.
  CHECK_FALSE(StreamQuery<detail::AnyHitPacket<Kernels>, Kernels>);
}

}  // namespace volley::simd
