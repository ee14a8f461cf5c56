// volley trace's tracers: what one query mode does with a chunk of the ray file (single
// rays, packets of K, the stream API per chunk or the whole file as one batch; crossings;
// the excluding forms), and the timed pass that spreads the chunks over threads.
#pragma once
#include <tbb/task_arena.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "volley/accel.h"

namespace volley::cli {

/// Rays per unit of work handed to a thread: a multiple of every packet width, so a
/// chunk never splits a packet (and a 4x4 block of primary rays stays in one packet).
constexpr std::size_t kChunk = 1024;
static_assert(kChunk % 16 == 0, "chunks hold whole packets");

/// The answers of one pass: closest hits, one byte per ray for occlusion, crossings per
/// ray (--count), or every hit per ray (--all).
struct Answers {
  std::vector<Hit> hits;
  std::vector<std::uint8_t> blocked;
  std::vector<std::uint32_t> counts;
  std::vector<std::vector<Hit>> lists;
  std::vector<float> normals;  ///< --normals: 3 per ray
};

/// Traces rays[begin, end) into `out` (the same indices).
using ChunkTracer = std::function<void(std::size_t begin, std::size_t end, Answers& out)>;

/// The tracer of one query mode (single, packet, stream, batch); `masks` (one per ray, or
/// null) picks the masked forms, `excluded` (one per ray, or null) the excluding forms,
/// `crossings` the crossing queries (out.lists non-empty: every hit, else counts).
ChunkTracer make_tracer(const Accel& accel, const std::vector<Ray>& rays, const std::uint32_t* masks,
                        const Hit* excluded, const std::string& mode, int packet, bool occluded, bool crossings,
                        int threads);

/// `trace`, then the geometric normals of the hits it found (--normals), on `threads` as
/// the batch mode's call (1 where the caller spreads the chunks).
ChunkTracer with_normals(const Accel& accel, ChunkTracer trace, int threads);

/// One timed pass over all rays, in kChunk chunks: on the calling thread for one thread
/// (no scheduler in the measurement), else spread by oneTBB inside `arena`; `whole`: in one
/// call (the batch mode, which spreads the rays itself). Returns its seconds.
double timed_pass(const ChunkTracer& trace, std::size_t count, int threads, tbb::task_arena& arena, Answers& out,
                  bool whole);

}  // namespace volley::cli
