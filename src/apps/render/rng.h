// Deterministic per-sample random numbers: each (pixel, sample) stream is seeded by a hash
// of the scene seed and its index, so an image does not depend on the thread count.
#pragma once
#include <cstdint>

namespace volley::render {

/// PCG32 (O'Neill 2014), XSH-RR output. 16 bytes.
class Rng {
 public:
  Rng(std::uint64_t seed, std::uint64_t stream) {
    inc_ = (stream << 1u) | 1u;
    state_ = 0;
    next();
    state_ += seed;
    next();
  }
  std::uint32_t next() {
    const std::uint64_t old = state_;
    state_ = old * 6364136223846793005ULL + inc_;
    const auto xorshifted = static_cast<std::uint32_t>(((old >> 18u) ^ old) >> 27u);
    const auto rot = static_cast<std::uint32_t>(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((~rot + 1u) & 31u));
  }
  /// Uniform in [0, 1): 24 random bits, so 1.0f is never returned.
  float uniform() { return float(next() >> 8) * 0x1p-24f; }

 private:
  std::uint64_t state_;
  std::uint64_t inc_;
};

}  // namespace volley::render
