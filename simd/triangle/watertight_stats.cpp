// Storage of the watertight fallback counter (watertight_stats.h).
#include "simd/triangle/watertight_stats.h"

namespace volley::simd {

thread_local constinit std::uint64_t watertight_fallback_lanes = 0;

}  // namespace volley::simd
