// Accel's stream queries: runs of 16 coherent rays traced as one packet, the rest by the
// stream walk where the scene and ISA allow it, else one by one (see volley/accel.h); a
// batch call whose rays share their nodes sends its incoherent closest-hit runs as packets
// too (stream_plan.h).
#include <immintrin.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstring>
#include <vector>

#include "accel/accel_impl.h"
#include "accel/stream_plan.h"

namespace volley {
namespace {

/// The axes across whose plane the directions of rays[0 .. n) spread (sign bits; -0
/// negative): 0 for one octant. Shadow rays toward one light spread across one plane at
/// most, but near an axis; bounce and ambient-occlusion rays across two or three.
int mixed_axes(const Ray* rays, std::size_t n) {
  // The sign bits of every direction ANDed and ORed, three lanes at once (the fourth, tmax, ignored).
  __m128 all = _mm_castsi128_ps(_mm_set1_epi32(-1)), any = _mm_setzero_ps();
  for (std::size_t i = 0; i < n; ++i) {
    const __m128 d = _mm_loadu_ps(rays[i].dir);
    all = _mm_and_ps(all, d);
    any = _mm_or_ps(any, d);
  }
  return std::popcount(static_cast<unsigned>(_mm_movemask_ps(_mm_xor_ps(all, any)) & 7));
}

/// The 16 bits of `mask` as 16 bytes of 0 or 1 at out (byte i = bit i): each half
/// replicated to eight bytes, bit k kept in byte k, and a kept bit carried to the byte's
/// top bit and moved down (one store per half instead of sixteen).
void store_lane_bytes(std::uint32_t mask, std::uint8_t* out) {
  for (int half = 0; half < 2; ++half) {
    const std::uint64_t kept = (std::uint64_t{(mask >> (8 * half)) & 0xffu} * 0x0101010101010101ull) &
                               0x8040201008040201ull;
    const std::uint64_t bytes = ((kept + 0x7f7f7f7f7f7f7f7full) >> 7) & 0x0101010101010101ull;
    std::memcpy(out + 8 * half, &bytes, 8);
  }
}

/// Whether rays[0 .. n) go as one packet: 16 of them, a scene whose streams may go as
/// packets, and one octant or a plan that takes mixed octants for this walk (`ordered`:
/// the closest hit; Accel::Impl::StreamPlan). Closest-hit runs of mixed octants go faster
/// ray by ray, occlusion runs straddling an axis plane (shadow rays) as packets on AVX-512
/// and AVX2 (perf/reports/rays.md).
/// `axes`: mixed_axes of the run, when known (-1: not yet).
/// `mixed`: this call's runs go as packets whatever their octants
/// (Accel::Impl::batch_runs_share_nodes).
template <class Plan>
bool as_packet(const Plan& plan, const Ray* rays, std::size_t n, bool ordered, int axes = -1, bool mixed = false) {
  return n == 16 && plan.packets &&
         (mixed || (ordered ? plan.mixed_closest : plan.mixed_any) || (axes < 0 ? mixed_axes(rays, n) : axes) == 0);
}

/// The rays of a stream left to the stream walk, copied together (per thread, reused), or
/// the whole stream in its place when every run is left to it and no mask sets one aside.
struct Leftover {
  bool whole = false;                ///< the caller's stream as it is, nothing copied
  std::vector<std::size_t> runs;     ///< the first ray of each run left
  std::vector<std::size_t> index;    ///< the rays' places in the caller's stream
  std::vector<Ray> rays;
  std::vector<Hit> hits;
  std::vector<std::uint8_t> blocked;
};

Leftover& leftover() {
  static thread_local Leftover left;
  return left;
}

/// The stream policy for one query. Runs of 16 (the last may be shorter) whose directions
/// spread across two or more axis planes go to the stream walk where the scene has it
/// (Queries::wide) and at least kStreamWalkRays such rays are in the stream: those whose
/// mask meets the wide BVH's (Queries::wide_mask) copied to left.rays, their places to
/// left.index, the others answered as misses by skip(i); or, when that is every run and no
/// masks are given, none copied and left.whole set (bounce rays: the copy was 3-5% of
/// their time). Every other run as as_packet says: packet(first) traces the run from
/// `first` as a packet, single(i) ray i. `mixed`: every run as as_packet says (none left
/// to the stream walk).
template <class Impl, class Packet, class Single, class Skip>
void runs(const Impl& impl, const Ray* rays, const std::uint32_t* masks, std::size_t count, bool ordered, bool mixed,
          Leftover& left, Packet&& packet, Single&& single, Skip&& skip) {
  const auto by_rule = [&](std::size_t first, int axes) {
    const std::size_t n = std::min<std::size_t>(16, count - first);
    if (as_packet(impl.built.queries.stream, rays + first, n, ordered, axes, mixed))
      packet(first);
    else
      for (std::size_t i = first; i < first + n; ++i) single(i);
  };
  left.whole = false;
  left.runs.clear();
  left.index.clear();
  left.rays.clear();
  for (std::size_t first = 0; first < count; first += 16) {
    const std::size_t n = std::min<std::size_t>(16, count - first);
    const int axes = impl.built.queries.wide && !mixed ? mixed_axes(rays + first, n) : -1;
    if (axes >= 2 && !mixed)
      left.runs.push_back(first);
    else
      by_rule(first, axes);
  }
  if (left.runs.size() * 16 < Impl::kStreamWalkRays) {
    for (std::size_t first : left.runs) by_rule(first, 2);
    return;
  }
  if (!masks && left.runs.size() == (count + 15) / 16) {
    left.whole = true;
    return;
  }
  for (std::size_t first : left.runs)
    for (std::size_t i = first; i < std::min(count, first + 16); ++i) {
      if (masks && !(masks[i] & impl.built.queries.wide_mask)) {
        skip(i);
        continue;
      }
      left.index.push_back(i);
      left.rays.push_back(rays[i]);
    }
}

}  // namespace

bool accel::runs_share_nodes(const WideAccel& wide, const Ray* rays, std::size_t count, bool any_hit) {
  if (wide.stats().leaves <= 16) return true;
  std::uint64_t leaves = 0;
  for (std::size_t k = 0; k < kProbeRays; ++k) leaves += wide.walk_counts(rays[k * count / kProbeRays], any_hit).leaves;
  return static_cast<double>(leaves) < kProbeRays * kSharedLeavesPerRay;
}

bool Accel::Impl::batch_runs_share_nodes(const Ray* rays, std::size_t count, bool any_hit) const {
  return built.queries.wide && built.queries.stream.probe_batches && count >= accel::kProbeMinRays &&
         accel::runs_share_nodes(*built.queries.wide, rays, count, any_hit);
}

void Accel::Impl::intersect(const Ray* rays, const std::uint32_t* masks, std::size_t count, Hit* hits,
                            bool mixed_packets) const {
  Leftover& left = leftover();
  runs(
      *this, rays, masks, count, true, mixed_packets, left,
      [&](std::size_t first) {
        RayPacket<16> p;
        volley::load(p, rays + first, 16);
        HitPacket<16> h;
        reset(h);
        intersect(p, h, masks ? masks + first : nullptr);
        store(h, hits + first, 16);
      },
      [&](std::size_t i) { hits[i] = intersect(rays[i], masks ? masks[i] : kMaskAll); },
      [&](std::size_t i) { hits[i] = Hit{}; });
  if (left.whole) {
    std::fill(hits, hits + count, Hit{});
    built.queries.wide->intersect(rays, count, hits);
    for (std::size_t i = 0; i < count; ++i) attribute(hits[i].prim, hits[i].geom);
    return;
  }
  if (left.rays.empty()) return;
  left.hits.assign(left.rays.size(), Hit{});
  built.queries.wide->intersect(left.rays.data(), left.rays.size(), left.hits.data());
  for (std::size_t k = 0; k < left.index.size(); ++k) {
    Hit& h = hits[left.index[k]];
    h = left.hits[k];
    attribute(h.prim, h.geom);
  }
}

void Accel::Impl::occluded(const Ray* rays, const std::uint32_t* masks, std::size_t count, std::uint8_t* blocked,
                           bool mixed_packets) const {
  Leftover& left = leftover();
  // Double packets (AVX2, one wide BVH, no masks): two neighbouring runs of 16 walked as one
  // packet of 32, the first run held back until its neighbour comes or not.
  const bool pair = built.queries.wide && !masks && built.queries.wide->double_packets();
  constexpr std::size_t kNone = ~std::size_t{0};
  std::size_t held = kNone;
  const auto single_run = [&](std::size_t first) {
    RayPacket<16> p;
    volley::load(p, rays + first, 16);
    store_lane_bytes(occluded(p, masks ? masks + first : nullptr), blocked + first);
  };
  runs(
      *this, rays, masks, count, false, mixed_packets, left,
      [&](std::size_t first) {
        if (!pair) return single_run(first);
        if (held == kNone) {
          held = first;
          return;
        }
        if (held + 16 != first) {
          single_run(held);
          held = first;
          return;
        }
        RayPacket<32> p;
        volley::load(p, rays + held, 32);
        const std::uint32_t hit = built.queries.wide->occluded(p);
        store_lane_bytes(hit & 0xffffu, blocked + held);
        store_lane_bytes(hit >> 16, blocked + first);
        held = kNone;
      },
      [&](std::size_t i) { blocked[i] = occluded(rays[i], masks ? masks[i] : kMaskAll) ? 1 : 0; },
      [&](std::size_t i) { blocked[i] = 0; });
  if (held != kNone) single_run(held);
  if (left.whole) {
    built.queries.wide->occluded(rays, count, blocked);
    return;
  }
  if (left.rays.empty()) return;
  left.blocked.resize(left.rays.size());
  built.queries.wide->occluded(left.rays.data(), left.rays.size(), left.blocked.data());
  for (std::size_t k = 0; k < left.index.size(); ++k) blocked[left.index[k]] = left.blocked[k];
}

void Accel::Impl::all_hits(const Ray* rays, std::size_t count, std::vector<Hit>* out) const {
  for (std::size_t first = 0; first < count; first += 16) {
    const std::size_t n = std::min<std::size_t>(16, count - first);
    std::vector<Hit>* lanes = out + first;
    if (!built.queries.stream.every_hit_packets || !as_packet(built.queries.stream, rays + first, n, false)) {
      for (std::size_t i = 0; i < n; ++i) all_hits(rays[first + i], kMaskAll, lanes[i]);
      continue;
    }
    RayPacket<16> p;
    volley::load(p, rays + first, 16);
    std::size_t before[16];
    for (int i = 0; i < 16; ++i) before[i] = lanes[i].size();
    for (const Layer& l : built.layers)
      for (const auto& engine : l.engines) {
        engine->all_hits(p, lanes);
        if (built.quality == BuildQuality::high)
          for (int i = 0; i < 16; ++i) drop_repeated_hits(lanes[i], before[i]);
        for (int i = 0; i < 16; ++i) {
          for (std::size_t k = before[i]; k < lanes[i].size(); ++k) attribute(lanes[i][k].prim, lanes[i][k].geom);
          before[i] = lanes[i].size();
        }
      }
  }
}

}  // namespace volley
