// The spatial split's bins (bvh_spatial.cpp): a node's box cut into slabs of equal width
// on one axis, and the parts of a triangle that fall in each slab, bounded as the split
// prices them.
#pragma once
#include <algorithm>
#include <cstddef>

#include <glm/glm.hpp>

#include "core/bbox.h"
#include "core/triangle_clip.h"

namespace volley::core::spatial {

/// Bin f (a position in bin units) of nb, clamped; NaN (0 * inf of a tiny extent) and
/// below 0 give 0, so that no float outside int's range is converted.
inline int bin_of(float f, int nb) {
  if (!(f > 0.0f)) return 0;
  return f < static_cast<float>(nb) ? static_cast<int>(f) : nb - 1;
}

/// The spatial bins of a node: `nb` slabs of equal width over its box on each axis.
struct Grid {
  BBox box;
  int nb;
  /// The plane after bin b on `axis` (b = nb: the box's upper face).
  float plane(int axis, int b) const {
    if (b >= nb) return box.hi[axis];
    return box.lo[axis] + (box.hi[axis] - box.lo[axis]) * (static_cast<float>(b) / static_cast<float>(nb));
  }
  int bin(int axis, float x) const {
    const float extent = box.hi[axis] - box.lo[axis];
    return bin_of((x - box.lo[axis]) * (static_cast<float>(nb) / extent), nb);
  }
};

/// Extends bins[first .. last] of `grid` by the parts of triangle v within `ref` that
/// fall in them. Each part is bounded by the triangle's vertices in its bin and the points
/// where the edges cross the bin's two planes; every plane's crossings are computed once,
/// in float: the bins only price the split (bvh_spatial.cpp's spatial_partition cuts the references it makes
/// conservatively).
inline void chop(const glm::vec3* v, const BBox& ref, const Grid& grid, int axis, int first, int last, BBox* bins) {
  int vertex_bin[3];
  for (int k = 0; k < 3; ++k) vertex_bin[k] = std::clamp(grid.bin(axis, v[k][axis]), first, last);
  BBox below;  // the crossings of the plane below bin b (none below the first)
  for (int b = first; b <= last; ++b) {
    const BBox above = b < last ? plane_crossings(v, axis, grid.plane(axis, b + 1)) : BBox{};
    BBox part = below;
    part.extend(above);
    for (int k = 0; k < 3; ++k)
      if (vertex_bin[k] == b) part.extend(v[k]);
    bins[b].extend(box_intersection(part, ref));
    below = above;
  }
}

}  // namespace volley::core::spatial
