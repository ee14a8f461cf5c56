// The stream walk's working memory (simd/wide/stream_walk.h), one per calling thread and
// kept between calls. Baseline code with out-of-line members: a per-ISA object must not
// define the containers' functions (docs/style.md rule 2).
#pragma once
#include <cstddef>
#include <cstdint>
#include <memory>

#include "simd/prepared_ray.h"

namespace volley::simd {

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
