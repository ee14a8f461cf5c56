// BVH statistics (bvh.h: bvh_stats): node and leaf counts, depth, SAH cost, bytes.
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/bvh.h"

namespace volley::core {

namespace {
// One subtree's terms of BvhStats. Its two halves in parallel for the top six levels (2^6
// tasks: enough for 16 threads), below a depth-first walk with an explicit stack, left child
// first (the order the builder lays nodes out in, so the walk reads the array nearly
// sequentially). Summed in a fixed order: the same for any number of threads.
struct SubtreeStats {
  double cost = 0.0;
  std::size_t prims = 0, leaves = 0, depth = 0;
};
SubtreeStats subtree_stats(const Bvh& bvh, const BvhBuildOptions& options, std::uint32_t root, std::size_t root_depth) {
  SubtreeStats s;
  const BvhNode& top = bvh.nodes[root];
  if (root_depth < 6 && !top.is_leaf()) {
    SubtreeStats l, r;
    const std::uint32_t c = top.first_or_child;
    tbb::parallel_invoke([&] { l = subtree_stats(bvh, options, c, root_depth + 1); },
                         [&] { r = subtree_stats(bvh, options, c + 1, root_depth + 1); });
    return {options.traversal_cost * top.box.half_area() + l.cost + r.cost, l.prims + r.prims, l.leaves + r.leaves,
            std::max(l.depth, r.depth)};
  }
  std::vector<std::pair<std::uint32_t, std::size_t>> stack{{root, root_depth}};
  while (!stack.empty()) {
    const auto [index, depth] = stack.back();
    stack.pop_back();
    const BvhNode& node = bvh.nodes[index];
    const double area = node.box.half_area();
    s.depth = std::max(s.depth, depth);
    if (node.is_leaf()) {
      ++s.leaves;
      s.prims += node.count;
      s.cost += options.intersection_cost * area * node.count;
    } else {
      s.cost += options.traversal_cost * area;
      stack.push_back({node.first_or_child + 1, depth + 1});
      stack.push_back({node.first_or_child, depth + 1});
    }
  }
  return s;
}
}  // namespace

BvhStats bvh_stats(const Bvh& bvh, const BvhBuildOptions& options) {
  BvhStats s;
  s.nodes = bvh.nodes.size();
  s.bytes = bvh.nodes.size() * sizeof(BvhNode) + bvh.prim_index.size() * sizeof(std::uint32_t);
  if (bvh.nodes.empty()) return s;
  const SubtreeStats t = subtree_stats(bvh, options, 0, 0);
  s.depth = t.depth;
  s.leaves = t.leaves;
  const double root_area = bvh.nodes[0].box.half_area();
  s.sah_cost =
      root_area > 0.0 && std::isfinite(root_area) ? t.cost / root_area : std::numeric_limits<double>::quiet_NaN();
  s.mean_leaf_size = static_cast<double>(t.prims) / static_cast<double>(s.leaves);
  return s;
}

}  // namespace volley::core
