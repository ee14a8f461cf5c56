// Counter of the watertight kernels' double-precision fallback (docs/accuracy.md: on grid-like
// input an edge function is exactly 0 in several percent of tests).
#pragma once
#include <cstdint>

namespace volley::simd {

/// (ray, triangle) lanes whose edge functions the watertight kernels recomputed in double
/// on this thread since it started (or since the caller last reset it). Incremented by
/// the kernels (constinit: no TLS wrapper function, so no untagged weak symbol in the
/// per-ISA objects); defined in watertight_stats.cpp. Thread-local: no synchronization.
extern thread_local constinit std::uint64_t watertight_fallback_lanes;

}  // namespace volley::simd
