// What the top level of an instanced scene hands the kernels (WideKernels::walk_instances)
// and what their walk of it calls back: plain types, so that baseline code (the Accel's
// instance tree) names them without the kernels' headers.
#pragma once
#include <cstdint>

#include "simd/wide/wide_bvh.h"
#include "volley/packet.h"
#include "volley/ray.h"

namespace volley::simd {

/// The top level of an instanced scene (accel::InstanceTree): wide nodes whose leaves name
/// runs of instance ids.
using InstanceView = WideView<std::uint32_t>;

/// What the walk of a top level asks (WideKernels::walk_instances).
enum class InstanceWalk {
  closest,  ///< near first; a visit that returns true lowers the bound, farther boxes are dropped
  any,      ///< any order; the first visit that returns true ends the walk
  every,    ///< any order, nothing dropped (visits return false)
};

/// The action at each instance the top level's walk reaches, type-erased (one call per
/// instance: the instance's own walk costs far more): visit(context, instance, bound)
/// queries `instance` with the walk's ray (the visitor holds it) over [tmin, bound) and
/// returns true after lowering `bound` to a hit (closest) or on any hit (any).
struct InstanceVisit {
  bool (*visit)(void* context, std::uint32_t instance, float& bound);
  void* context;
};

/// The packet form: visit(context, instance, lanes, bound) queries `instance` with the
/// lanes `lanes` of the walk's packet (lane i over [tmin, bound[i])) and returns the lanes
/// that hit, after lowering their bound (closest; any: the lanes blocked).
struct InstancePacketVisit {
  std::uint32_t (*visit)(void* context, std::uint32_t instance, std::uint32_t lanes, float* bound);
  void* context;
};

}  // namespace volley::simd
