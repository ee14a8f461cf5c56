// Which form a batch call's incoherent runs take: packets of 16 or the stream
// walk. Packets win when the 16 rays of a run share most of the nodes they visit (one node
// test serves them all); the stream walk wins when they part ways, since its lists drop a
// ray at the first node it misses (perf/reports/rays.md, the batch form).
#pragma once
#include <cstddef>

#include "accel/wide/wide_accel.h"
#include "volley/ray.h"

namespace volley::accel {

/// The rays a call probes, spread evenly over it, and the fewest a call must have to be
/// probed (the probe's single-ray walks then cost under 2% of the call).
inline constexpr std::size_t kProbeRays = 64;
inline constexpr std::size_t kProbeMinRays = 4096;
/// Below this many leaves a ray the probed rays mostly leave the tree near its root.
inline constexpr double kSharedLeavesPerRay = 0.3;

/// Whether the rays of rays[0 .. count) share what they visit in `wide`: the tree has no
/// more leaves than a packet has lanes (a run's union of nodes is the tree at most), or
/// kProbeRays of them, counted by the single-ray walk (closest hit, or `any_hit`), reach
/// fewer than kSharedLeavesPerRay leaves a ray (bounce rays in rooms leave near the root;
/// rays off a dense mesh go deep into it). Counts, not time, decide: the answer depends on
/// the rays and the tree alone, and so do a batch's answers. count > 0.
bool runs_share_nodes(const WideAccel& wide, const Ray* rays, std::size_t count, bool any_hit);

}  // namespace volley::accel
