// The stream walk's working memory (simd/wide/stream_walk.h), one per calling thread and
// kept between calls. Baseline code with out-of-line members: a per-ISA object must not
// define the containers' functions (docs/style.md rule 2).
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>

#include "simd/rays/prepared_ray.h"

namespace volley::simd {

/// The stream walk takes a stream this many rays at a time (its lists and ray data then
/// stay within the L2 cache), and hands a subtree whose list holds fewer than
/// kStreamSwitchRays rays to the single-ray walk, ray by ray (perf/reports/rays.md: 4096 and 16
/// against 1024 to 8192 and 8 to 32).
inline constexpr std::size_t kStreamBatch = 4096;
inline constexpr std::uint32_t kStreamSwitchRays = 16;
/// A closest-hit leaf list of kStreamLeafList rays or more is tested L rays at a time in
/// lanes while kStreamLeafLanes rays of it are left, the rest ray by ray (perf/reports/rays.md,
/// "long leaf lists of the stream walk in lanes": shorter lists lost on the bunny's bounce rays).
inline constexpr std::uint32_t kStreamLeafList = 64;
inline constexpr std::uint32_t kStreamLeafLanes = 4;

class StreamScratch {
 public:
  StreamScratch();
  ~StreamScratch();
  StreamScratch(const StreamScratch&) = delete;
  StreamScratch& operator=(const StreamScratch&) = delete;

  /// 8 floats per ray for n rays, 64-byte aligned (contents not kept when it grows).
  float* ray_lanes(std::size_t n);
  /// n prepared rays (contents not kept when it grows).
  PreparedRay* prepared(std::size_t n);
  /// The lists of ray ids, at least n entries; what it held is kept when it grows.
  std::uint32_t* lists(std::size_t n);
  /// A node's children's lists while it is split: at least n entries.
  std::uint32_t* split(std::size_t n);

 private:
  struct Buffers;
  std::unique_ptr<Buffers> buffers_;
};

/// The calling thread's scratch.
StreamScratch& stream_scratch();

}  // namespace volley::simd
