// The point queries: the nearest surface point, distance and signed distance. The engines
// walk their BVHs nearest box first (simd/wide/point_walk.h, core/bvh_nearest.h); here the
// layers are combined and the answer attributed. The sign comes from the crossing parity
// of contains().
#include <cmath>
#include <stdexcept>
#include <string>

#include "accel/accel_impl.h"

namespace volley {

ClosestPoint Accel::Impl::closest_point(core::PointQuery& query) const {
  if (built.has_instances)
    throw Error("closest_point: scenes with instances are not supported by the point queries (query the prototypes)");
  try {
    for (const Layer& l : built.layers)
      for (const auto& engine : l.engines) engine->closest_point(query);
  } catch (const std::invalid_argument& e) {  // the wide plane-test engine
    throw Error(std::string("closest_point: ") + e.what() + "; commit with the watertight (default) or Moller test");
  }
  ClosestPoint out;
  if (query.prim == kInvalidPrim) return out;
  out.point[0] = query.q[0], out.point[1] = query.q[1], out.point[2] = query.q[2];
  out.distance = std::sqrt(query.d2);
  out.u = query.u, out.v = query.v;
  out.prim = query.prim;
  attribute(out.prim, out.geom);
  return out;
}

ClosestPoint Accel::closest_point(const float point[3], float max_distance) const {
  if (!impl_->built.committed) throw Error("closest_point: call commit() after adding geometry");
  if (!point) throw Error("closest_point: point is null");
  if (!(max_distance >= 0.0f)) throw Error("closest_point: max_distance must be >= 0 (+inf for no limit)");
  core::PointQuery query;
  for (int k = 0; k < 3; ++k) query.p[k] = point[k];
  query.d2 = max_distance * max_distance;
  return impl_->closest_point(query);
}

float Accel::distance(const float point[3]) const { return closest_point(point).distance; }

float Accel::signed_distance(const float point[3]) const {
  const float d = distance(point);
  return d > 0.0f && contains(point) ? -d : d;
}

}  // namespace volley
