// The batch forms of the crossing and point queries: arrays of rays or points split over
// threads (the caller's oneTBB arena, or an arena of the thread count asked for), each
// element answered by the single form.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "accel/accel_impl.h"
#include "accel/parallel.h"

namespace volley {
namespace {

using accel::for_chunks;

/// The points' indices in Morton (Z-curve) order of their positions in the points' box, 10
/// bits per axis: neighbours in the order are neighbours in space, so consecutive queries
/// walk the same nodes (cache) and each can start from its predecessor's answer. Non-finite
/// points go last. Two 16-bit radix passes.
std::vector<std::uint32_t> morton_order(const float* xyz, std::size_t n) {
  float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (std::size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a)
      if (std::isfinite(xyz[3 * i + a])) lo[a] = std::min(lo[a], xyz[3 * i + a]), hi[a] = std::max(hi[a], xyz[3 * i + a]);
  auto spread = [](std::uint32_t x) {  // 10 bits -> every third bit
    x = (x | (x << 16)) & 0x030000ffu;
    x = (x | (x << 8)) & 0x0300f00fu;
    x = (x | (x << 4)) & 0x030c30c3u;
    return (x | (x << 2)) & 0x09249249u;
  };
  std::vector<std::uint32_t> code(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t c = 0;
    bool finite = true;
    for (int a = 0; a < 3; ++a) {
      const float x = xyz[3 * i + a];
      finite = finite && std::isfinite(x);
      const float f = hi[a] > lo[a] ? (x - lo[a]) / (hi[a] - lo[a]) : 0.0f;
      const std::uint32_t q = f > 0.0f ? (f < 1.0f ? std::uint32_t(f * 1023.0f) : 1023u) : 0u;
      c |= spread(q) << a;
    }
    code[i] = finite ? c : 0xffffffffu;
  }
  std::vector<std::uint32_t> order(n), tmp(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = static_cast<std::uint32_t>(i);
  for (int shift : {0, 16}) {
    std::vector<std::size_t> count(65537, 0);
    for (std::uint32_t i : order) ++count[((code[i] >> shift) & 0xffffu) + 1];
    for (std::size_t k = 1; k < count.size(); ++k) count[k] += count[k - 1];
    for (std::uint32_t i : order) tmp[count[(code[i] >> shift) & 0xffffu]++] = i;
    order.swap(tmp);
  }
  return order;
}

/// closest_point of point p, its search first bounded by the previous point's answer (the
/// distance from p to that surface point, padded: the nearest triangle is within it, so
/// the answer is the unbounded one), then unbounded should that find nothing.
}  // namespace

ClosestPoint Accel::Impl::closest_after(const float* p, float max_d2, const ClosestPoint& previous) const {
  core::PointQuery q;
  for (int k = 0; k < 3; ++k) q.p[k] = p[k];
  q.d2 = max_d2;
  if (previous.found()) {
    float s = 0.0f;
    for (int k = 0; k < 3; ++k) s += (p[k] - previous.point[k]) * (p[k] - previous.point[k]);
    s = s * (1.0f + 0x1p-6f) + std::numeric_limits<float>::min();
    if (s < q.d2) {
      q.d2 = s;
      const ClosestPoint seeded = closest_point(q);
      if (seeded.found()) return seeded;
      q = core::PointQuery{};
      for (int k = 0; k < 3; ++k) q.p[k] = p[k];
      q.d2 = max_d2;
    }
  }
  return closest_point(q);
}

namespace {

/// Calls each(i, hits of ray i) for rays[begin .. end), traced 16 at a time through the
/// stream policy (packets where they pay), in buffers each thread keeps.
template <class Impl, class Each>
void for_runs(const Impl& impl, const Ray* rays, std::size_t begin, std::size_t end, Each&& each) {
  thread_local std::vector<Hit> kept[16];
  std::vector<Hit>* const lists = accel::thread_buffer(kept);
  for (std::size_t first = begin; first < end; first += 16) {
    const std::size_t n = std::min<std::size_t>(16, end - first);
    for (std::size_t i = 0; i < n; ++i) lists[i].clear();
    impl.all_hits(rays + first, n, lists);
    for (std::size_t i = 0; i < n; ++i) each(first + i, lists[i]);
  }
}

void require(const char* caller, const void* p, std::size_t count, const char* what) {
  if (!p && count > 0) throw Error(std::string(caller) + ": " + what + " is null with count > 0");
}

}  // namespace

HitLists Accel::intersect_all(const Ray* rays, std::size_t count, int threads) const {
  if (!impl_->built.committed) throw Error("intersect_all: call commit() after adding geometry");
  require("intersect_all", rays, count, "rays");
  // Each chunk gathers its rays' hits in order; the lists are then joined in ray order.
  std::vector<std::uint32_t> counts(count);
  std::vector<std::vector<Hit>> chunk_hits;
  std::vector<std::size_t> chunk_first;
  const std::size_t kChunk = 1024;
  const std::size_t chunks = (count + kChunk - 1) / kChunk;
  chunk_hits.resize(chunks);
  for_chunks("intersect_all", chunks, threads, [&](std::size_t c0, std::size_t c1) {
    for (std::size_t c = c0; c < c1; ++c) {
      std::vector<Hit>& out = chunk_hits[c];
      const std::size_t end = std::min(count, (c + 1) * kChunk);
      for_runs(*impl_, rays, c * kChunk, end, [&](std::size_t i, std::vector<Hit>& hits) {
        sort_hits(hits.data(), hits.data() + hits.size());
        out.insert(out.end(), hits.begin(), hits.end());
        counts[i] = static_cast<std::uint32_t>(hits.size());
      });
    }
  });
  HitLists lists;
  lists.offsets.resize(count + 1);
  lists.offsets[0] = 0;
  for (std::size_t i = 0; i < count; ++i) lists.offsets[i + 1] = lists.offsets[i] + counts[i];
  lists.hits.reserve(lists.offsets[count]);
  for (const std::vector<Hit>& h : chunk_hits) lists.hits.insert(lists.hits.end(), h.begin(), h.end());
  return lists;
}

void Accel::count_intersections(const Ray* rays, std::size_t count, std::uint32_t* counts, int threads) const {
  if (!impl_->built.committed) throw Error("count_intersections: call commit() after adding geometry");
  require("count_intersections", rays, count, "rays");
  require("count_intersections", counts, count, "counts");
  for_chunks("count_intersections", count, threads, [&](std::size_t b, std::size_t e) {
    for_runs(*impl_, rays, b, e, [&](std::size_t i, const std::vector<Hit>& hits) {
      counts[i] = static_cast<std::uint32_t>(hits.size());
    });
  });
}

void Accel::contains(const float* xyz, std::size_t count, std::uint8_t* inside, int threads) const {
  if (!impl_->built.committed) throw Error("contains: call commit() after adding geometry");
  require("contains", xyz, count, "xyz");
  require("contains", inside, count, "inside");
  // In Morton order: the rays of neighbouring points share a direction and nearly an
  // origin, so runs of 16 go as packets (the stream policy) through the same nodes.
  const std::vector<std::uint32_t> order = morton_order(xyz, count);
  for_chunks("contains", count, threads, [&](std::size_t b, std::size_t e) {
    thread_local std::vector<Ray> kept;
    std::vector<Ray>& rays = *accel::thread_buffer(&kept);
    rays.clear();
    for (std::size_t k = b; k < e; ++k) rays.push_back(contains_ray(xyz + 3 * std::size_t{order[k]}));
    for_runs(*impl_, rays.data(), 0, rays.size(), [&](std::size_t i, const std::vector<Hit>& hits) {
      inside[order[b + i]] = hits.size() % 2 == 1 ? 1 : 0;
    });
  });
}

void Accel::closest_points(const float* xyz, std::size_t count, ClosestPoint* out, float max_distance,
                           int threads) const {
  if (!impl_->built.committed) throw Error("closest_points: call commit() after adding geometry");
  require("closest_points", xyz, count, "xyz");
  require("closest_points", out, count, "out");
  if (!(max_distance >= 0.0f)) throw Error("closest_points: max_distance must be >= 0 (+inf for no limit)");
  impl_->closest_batch(xyz, count, threads, max_distance, [&](std::size_t i, const ClosestPoint& c) { out[i] = c; });
}

void Accel::distances(const float* xyz, std::size_t count, float* out, bool is_signed, int threads) const {
  if (!impl_->built.committed) throw Error("distances: call commit() after adding geometry");
  require("distances", xyz, count, "xyz");
  require("distances", out, count, "out");
  impl_->closest_batch(xyz, count, threads, INFINITY, [&](std::size_t i, const ClosestPoint& c) {
    out[i] = is_signed && c.distance > 0.0f && contains(xyz + 3 * i) ? -c.distance : c.distance;
  });
}

void Accel::Impl::closest_batch(const float* xyz, std::size_t count, int threads, float max_distance,
                                const std::function<void(std::size_t, const ClosestPoint&)>& out) const {
  const std::vector<std::uint32_t> order = morton_order(xyz, count);
  const float max_d2 = max_distance * max_distance;
  for_chunks("closest_points", count, threads, [&](std::size_t b, std::size_t e) {
    ClosestPoint previous;
    for (std::size_t k = b; k < e; ++k) {
      const std::uint32_t i = order[k];
      previous = closest_after(xyz + 3 * std::size_t{i}, max_d2, previous);
      out(i, previous);
    }
  });
}

}  // namespace volley
