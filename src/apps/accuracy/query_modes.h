// How rays reach an Accel: the ISAs of this CPU and the query modes of the public API
// (single ray, packets of K = 4, 8, 16, streams), each answering closest hit and occlusion.
#pragma once
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "volley/accel.h"

namespace volley::accuracy {

/// The scalar oracle first, then every SIMD ISA this CPU runs.
std::vector<Isa> available_isas();
/// SIMD ISAs this CPU lacks (for a message).
std::vector<Isa> missing_isas();

/// How rays are handed to the Accel.
enum class Mode { single, packet4, packet8, packet16, stream };
inline constexpr Mode kModes[] = {Mode::single, Mode::packet4, Mode::packet8, Mode::packet16, Mode::stream};
std::string name(Mode mode);
/// Parses a name of name(Mode); false when unknown.
bool parse_mode(const std::string& text, Mode& mode);

/// Closest hits and occlusion flags of a batch of rays, in one mode.
struct Answers {
  std::vector<Hit> hits;
  std::vector<std::uint8_t> occluded;
  /// Packet modes: occlusion masks that set a lane beyond the packet's active ones (an API
  /// contract violation; must stay 0).
  std::size_t inactive_lane_reports = 0;
};

/// Traces `rays` through `accel` in `mode`: closest hit and occlusion of every ray.
Answers trace(const Accel& accel, std::span<const Ray> rays, Mode mode);
/// Closest hits only (the timed pass of the accuracy runner).
void intersect(const Accel& accel, std::span<const Ray> rays, Mode mode, std::vector<Hit>& hits);

}  // namespace volley::accuracy
