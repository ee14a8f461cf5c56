// The batch forms of the crossing and point queries: arrays of rays or points split over
// threads (the caller's oneTBB arena, or an arena of the thread count asked for), each
// element answered by the single form.
#include <algorithm>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "accel/accel_impl.h"

namespace volley {
namespace {

/// Calls body(begin, end) over [0, count) in chunks: on the current arena (threads = 0),
/// on the calling thread alone (1), or on an arena of `threads`.
template <class Body>
void for_chunks(const char* caller, std::size_t count, int threads, Body&& body) {
  if (threads < 0) throw Error(std::string(caller) + ": threads must be >= 0 (0: the caller's oneTBB arena)");
  if (count == 0) return;
  if (threads == 1) {
    body(std::size_t{0}, count);
    return;
  }
  auto run = [&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 256),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
  };
  if (threads == 0) {
    run();
  } else {
    tbb::task_arena arena(threads);
    arena.execute(run);
  }
}

void require(const char* caller, const void* p, std::size_t count, const char* what) {
  if (!p && count > 0) throw Error(std::string(caller) + ": " + what + " is null with count > 0");
}

}  // namespace

HitLists Accel::intersect_all(const Ray* rays, std::size_t count, int threads) const {
  if (!impl_->committed) throw Error("intersect_all: call commit() after adding geometry");
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
      for (std::size_t i = c * kChunk; i < std::min(count, (c + 1) * kChunk); ++i) {
        const std::size_t first = out.size();
        impl_->all_hits(rays[i], kMaskAll, out);
        sort_hits(out.data() + first, out.data() + out.size());
        counts[i] = static_cast<std::uint32_t>(out.size() - first);
      }
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
  if (!impl_->committed) throw Error("count_intersections: call commit() after adding geometry");
  require("count_intersections", rays, count, "rays");
  require("count_intersections", counts, count, "counts");
  for_chunks("count_intersections", count, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) counts[i] = count_intersections(rays[i]);
  });
}

void Accel::contains(const float* xyz, std::size_t count, std::uint8_t* inside, int threads) const {
  if (!impl_->committed) throw Error("contains: call commit() after adding geometry");
  require("contains", xyz, count, "xyz");
  require("contains", inside, count, "inside");
  for_chunks("contains", count, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) inside[i] = contains(xyz + 3 * i) ? 1 : 0;
  });
}

void Accel::closest_points(const float* xyz, std::size_t count, ClosestPoint* out, float max_distance,
                           int threads) const {
  if (!impl_->committed) throw Error("closest_points: call commit() after adding geometry");
  require("closest_points", xyz, count, "xyz");
  require("closest_points", out, count, "out");
  for_chunks("closest_points", count, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) out[i] = closest_point(xyz + 3 * i, max_distance);
  });
}

void Accel::distances(const float* xyz, std::size_t count, float* out, bool is_signed, int threads) const {
  if (!impl_->committed) throw Error("distances: call commit() after adding geometry");
  require("distances", xyz, count, "xyz");
  require("distances", out, count, "out");
  for_chunks("distances", count, threads, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) out[i] = is_signed ? signed_distance(xyz + 3 * i) : distance(xyz + 3 * i);
  });
}

}  // namespace volley
