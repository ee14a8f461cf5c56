#include "accel/instance_tree.h"

#include <algorithm>
#include <cmath>

#include "core/bvh.h"

namespace volley::accel {

void InstanceTree::build(const std::vector<core::BBox>& boxes) {
  nodes_.clear();
  if (boxes.empty()) return;
  // One instance per leaf: an instance's "test" is a whole walk of its prototype.
  core::BvhBuildOptions options;
  options.max_leaf_size = 1;
  const core::Bvh bvh = core::build_bvh(boxes, options);
  if (bvh.nodes.empty()) return;

  // Collapse: each wide node takes the binary node's children, then opens its interior
  // child of largest area until it has 8 (or only leaves are left); depth first, so a
  // node's children are written after it.
  struct Pending {
    std::uint32_t binary;  // the binary node the wide node stands for
    std::uint32_t wide;    // its index in nodes_
  };
  auto area = [&](std::uint32_t n) { return bvh.nodes[n].box.half_area(); };
  nodes_.emplace_back();
  std::vector<Pending> todo{{0, 0}};
  while (!todo.empty()) {
    const Pending p = todo.back();
    todo.pop_back();
    std::vector<std::uint32_t> kids;
    if (bvh.nodes[p.binary].is_leaf()) {
      kids.push_back(p.binary);  // a root that is a leaf
    } else {
      kids = {bvh.nodes[p.binary].first_or_child, bvh.nodes[p.binary].first_or_child + 1};
      while (kids.size() < 8) {
        int best = -1;
        for (int k = 0; k < int(kids.size()); ++k)
          if (!bvh.nodes[kids[k]].is_leaf() && (best < 0 || area(kids[k]) > area(kids[best]))) best = k;
        if (best < 0) break;
        const std::uint32_t open = kids[best];
        kids[best] = bvh.nodes[open].first_or_child;
        kids.push_back(bvh.nodes[open].first_or_child + 1);
      }
    }
    for (int k = 0; k < 8; ++k) {
      Node& node = nodes_[p.wide];  // (re-read: emplace_back below may move the array)
      if (k >= int(kids.size())) {
        for (int a = 0; a < 3; ++a) node.lo[a][k] = INFINITY, node.hi[a][k] = -INFINITY;
        node.child[k] = kEmpty;
        continue;
      }
      const core::BvhNode& b = bvh.nodes[kids[k]];
      for (int a = 0; a < 3; ++a) node.lo[a][k] = b.box.lo[a], node.hi[a][k] = b.box.hi[a];
      if (b.is_leaf()) {
        node.child[k] = kLeaf | bvh.prim_index[b.first_or_child];
      } else {
        node.child[k] = static_cast<std::uint32_t>(nodes_.size());
        todo.push_back({kids[k], static_cast<std::uint32_t>(nodes_.size())});
        nodes_.emplace_back();
      }
    }
  }
}

}  // namespace volley::accel
