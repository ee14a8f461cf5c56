// The long leak run: at least N vertex/edge/diagonal-aimed rays per ISA (and per query
// mode) from inside the closed meshes at every offset, watertight test, robust traversal.
#pragma once
#include <functional>
#include <string>
#include <vector>

#include "accuracy/query_modes.h"

namespace volley::accuracy {

struct LongRow {
  Isa isa = Isa::scalar;
  Mode mode = Mode::single;
  std::string mesh;
  double offset = 0;
  std::size_t rays = 0;
  std::size_t leaks = 0;  ///< rays that intersect() or occluded() let through
  std::size_t nan = 0;
  double seconds = 0;  ///< closest hit + occlusion of all rays: thread CPU time
};

/// Traces, per ISA and mode, at least `rays_per_isa` distinct rays spread over the closed
/// cases (grid cube, icosphere) at every offset of kOffsets.
std::vector<LongRow> long_run(std::size_t rays_per_isa, const std::vector<Isa>& isas, const std::vector<Mode>& modes,
                              const std::function<void(double)>& progress);

}  // namespace volley::accuracy
