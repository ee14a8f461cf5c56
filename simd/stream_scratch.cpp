#include "simd/stream_scratch.h"

#include <algorithm>
#include <vector>

#include "simd/aligned.h"

namespace volley::simd {

struct StreamScratch::Buffers {
  AlignedVector<float> ray_lanes;
  AlignedVector<PreparedRay> prepared;
  std::vector<std::uint32_t> lists;
  std::vector<std::uint32_t> split;
};

StreamScratch::StreamScratch() : buffers_(std::make_unique<Buffers>()) {}
StreamScratch::~StreamScratch() = default;

float* StreamScratch::ray_lanes(std::size_t n) {
  if (buffers_->ray_lanes.size() < 8 * n) buffers_->ray_lanes.resize(8 * n);
  return buffers_->ray_lanes.data();
}

PreparedRay* StreamScratch::prepared(std::size_t n) {
  if (buffers_->prepared.size() < n) buffers_->prepared.resize(n);
  return buffers_->prepared.data();
}

std::uint32_t* StreamScratch::lists(std::size_t n) {
  std::vector<std::uint32_t>& v = buffers_->lists;
  if (v.size() < n) v.resize(std::max(n, 2 * v.size()));
  return v.data();
}

std::uint32_t* StreamScratch::split(std::size_t n) {
  if (buffers_->split.size() < n) buffers_->split.resize(n);
  return buffers_->split.data();
}

StreamScratch& stream_scratch() {
  static thread_local StreamScratch scratch;
  return scratch;
}

}  // namespace volley::simd
