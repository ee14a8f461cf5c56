#include "cli/trace_tracers.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>

#include "volley/packet.h"

namespace volley::cli {
namespace {

/// The crossing queries, ray by ray (they have no packet forms): counts or hit lists.
void trace_crossings(const Accel& accel, const Ray* r, const std::uint32_t* masks, std::size_t begin, std::size_t end,
                     Answers& out) {
  for (std::size_t i = begin; i < end; ++i) {
    const std::uint32_t mask = masks ? masks[i] : kMaskAll;
    if (out.lists.empty()) {
      out.counts[i] = accel.count_intersections(r[i], mask);
      continue;
    }
    std::vector<Hit>& list = out.lists[i];
    list.resize(list.capacity() > 8 ? list.capacity() : 8);
    const std::size_t n = accel.intersect_all(r[i], list.data(), list.size(), mask);
    if (n > list.size()) {
      list.resize(n);
      accel.intersect_all(r[i], list.data(), n, mask);
    }
    list.resize(n);
  }
}

/// Packets of K consecutive rays; `masks` (one per ray) picks the masked query forms.
template <int K>
void trace_packets(const Accel& accel, const Ray* rays, const std::uint32_t* masks, std::size_t begin, std::size_t end,
                   bool occluded, Answers& out) {
  RayPacket<K> packet;
  HitPacket<K> hits;
  for (std::size_t i = begin; i < end; i += K) {
    const int count = int(std::min<std::size_t>(K, end - i));
    load(packet, rays + i, count);
    if (occluded) {
      const std::uint32_t mask = masks ? accel.occluded(packet, masks + i) : accel.occluded(packet);
      for (int l = 0; l < count; ++l) out.blocked[i + l] = std::uint8_t((mask >> l) & 1u);
    } else {
      reset(hits);
      masks ? accel.intersect(packet, hits, masks + i) : accel.intersect(packet, hits);
      store(hits, out.hits.data() + i, count);
    }
  }
}

/// The excluding forms (--exclude: excluded[i] for ray i): single rays, or the batch call of
/// the stream API per chunk (stream) or on the whole file (batch).
ChunkTracer make_excluding_tracer(const Accel& accel, const Ray* r, const std::uint32_t* masks, const Hit* excluded,
                                  bool single, bool occluded, int api_threads) {
  if (single)
    return [&accel, r, masks, excluded, occluded](std::size_t begin, std::size_t end, Answers& out) {
      for (std::size_t i = begin; i < end; ++i) {
        const std::uint32_t mask = masks ? masks[i] : kMaskAll;
        if (occluded)
          out.blocked[i] = accel.occluded_excluding(r[i], excluded[i], mask) ? 1 : 0;
        else
          out.hits[i] = accel.intersect_excluding(r[i], excluded[i], mask);
      }
    };
  return [&accel, r, masks, excluded, occluded, api_threads](std::size_t begin, std::size_t end, Answers& out) {
    const QueryArguments args{masks ? masks + begin : nullptr, excluded + begin, api_threads};
    if (occluded)
      accel.occluded(r + begin, end - begin, out.blocked.data() + begin, args);
    else
      accel.intersect(r + begin, end - begin, out.hits.data() + begin, args);
  };
}

}  // namespace

ChunkTracer make_tracer(const Accel& accel, const std::vector<Ray>& rays, const std::uint32_t* masks,
                        const Hit* excluded, const std::string& mode, int packet, bool occluded, bool crossings,
                        int threads) {
  const Ray* r = rays.data();
  if (excluded)
    return make_excluding_tracer(accel, r, masks, excluded, mode == "single", occluded, mode == "batch" ? threads : 1);
  if (crossings && (mode == "stream" || mode == "batch") && !masks) {
    // --count on the stream API (Accel::count_intersections on a ray array: runs of rays
    // go as packets), per chunk on the calling thread or the whole file on `threads`.
    const int api_threads = mode == "batch" ? threads : 1;
    return [&accel, r, api_threads](std::size_t begin, std::size_t end, Answers& out) {
      accel.count_intersections(r + begin, end - begin, out.counts.data() + begin, api_threads);
    };
  }
  if (crossings)
    return [&accel, r, masks](std::size_t begin, std::size_t end, Answers& out) {
      trace_crossings(accel, r, masks, begin, end, out);
    };
  if (mode == "packet") {
    return [&accel, r, masks, packet, occluded](std::size_t begin, std::size_t end, Answers& out) {
      if (packet == 4)
        trace_packets<4>(accel, r, masks, begin, end, occluded, out);
      else if (packet == 8)
        trace_packets<8>(accel, r, masks, begin, end, occluded, out);
      else
        trace_packets<16>(accel, r, masks, begin, end, occluded, out);
    };
  }
  if (mode == "stream" || mode == "batch") {
    // The stream API: on the calling thread (stream: the chunks are spread over threads by
    // the caller), or on `threads` (batch: the whole file in one call, the library spreads it).
    const int api_threads = mode == "batch" ? threads : 1;
    return [&accel, r, masks, occluded, api_threads](std::size_t begin, std::size_t end, Answers& out) {
      const std::uint32_t* m = masks ? masks + begin : nullptr;
      if (occluded) {
        m ? accel.occluded(r + begin, m, end - begin, out.blocked.data() + begin, api_threads)
          : accel.occluded(r + begin, end - begin, out.blocked.data() + begin, api_threads);
      } else {
        m ? accel.intersect(r + begin, m, end - begin, out.hits.data() + begin, api_threads)
          : accel.intersect(r + begin, end - begin, out.hits.data() + begin, api_threads);
      }
    };
  }
  return [&accel, r, masks, occluded](std::size_t begin, std::size_t end, Answers& out) {
    if (occluded) {
      for (std::size_t i = begin; i < end; ++i)
        out.blocked[i] = (masks ? accel.occluded(r[i], masks[i]) : accel.occluded(r[i])) ? 1 : 0;
    } else {
      for (std::size_t i = begin; i < end; ++i)
        out.hits[i] = masks ? accel.intersect(r[i], masks[i]) : accel.intersect(r[i]);
    }
  };
}

ChunkTracer with_normals(const Accel& accel, ChunkTracer trace, int threads) {
  return [&accel, trace = std::move(trace), threads](std::size_t begin, std::size_t end, Answers& out) {
    trace(begin, end, out);
    accel.geometric_normals(out.hits.data() + begin, end - begin, out.normals.data() + 3 * begin, threads);
  };
}

double timed_pass(const ChunkTracer& trace, std::size_t count, int threads, tbb::task_arena& arena, Answers& out,
                  bool whole) {
  const auto start = std::chrono::steady_clock::now();
  if (whole) {
    trace(0, count, out);
  } else if (threads == 1) {
    for (std::size_t b = 0; b < count; b += kChunk) trace(b, std::min(count, b + kChunk), out);
  } else {
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, (count + kChunk - 1) / kChunk, 1),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t c = r.begin(); c < r.end(); ++c)
                            trace(c * kChunk, std::min(count, (c + 1) * kChunk), out);
                        });
    });
  }
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace volley::cli
