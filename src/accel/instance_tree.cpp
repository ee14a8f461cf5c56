#include "accel/instance_tree.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/bvh.h"
#include "simd/wide_traverse.h"

namespace volley::accel {

std::size_t InstanceTree::bytes() const {
  return nodes_.size() * sizeof(nodes_[0]) + ids_.size() * sizeof(ids_[0]) +
         bvh_.nodes.size() * sizeof(bvh_.nodes[0]) + bvh_.prim_index.size() * sizeof(bvh_.prim_index[0]);
}

void InstanceTree::build(const std::vector<core::BBox>& boxes, Isa isa, bool robust) {
  nodes_.clear();
  ids_.clear();
  bvh_ = {};
  view_ = {nullptr, nullptr, simd::wide_ref::kEmptyRef};
  robust_ = robust;
  walk_ = nullptr;
  walk_packet_ = nullptr;
  if (boxes.empty()) return;
  if (boxes.size() >= simd::wide_ref::kMaxBlocks)
    throw std::invalid_argument("more than " + std::to_string(simd::wide_ref::kMaxBlocks - 1) +
                                " instances in one layer");
  // Leaves of up to 8 instances where the SAH says so (priced low: the collapse spreads a
  // leaf's instances over slots of a wide node, each with a box of its own, so a leaf here
  // only decides how instances are grouped into nodes; perf/instances.md).
  core::BvhBuildOptions options;
  options.max_leaf_size = 8;
  options.intersection_cost = 0.3f;
  core::Bvh bvh = core::build_bvh(boxes, options);
  if (bvh.nodes.empty()) return;
  if (isa == Isa::scalar) {
    bvh_ = std::move(bvh);  // the oracle's walk over the binary tree
    return;
  }
  // The triangle test plays no part in the top level: the kernels of the test whose rays
  // need the least preparation.
  simd::visit_arch(isa, [&]<class Arch>(Arch) {
    if (robust) {
      using Kernels = simd::WideKernels<Arch, TriangleTest::moller, true>;
      walk_ = &Kernels::walk_instances, walk_packet_ = &Kernels::walk_instances;
    } else {
      using Kernels = simd::WideKernels<Arch, TriangleTest::moller, false>;
      walk_ = &Kernels::walk_instances, walk_packet_ = &Kernels::walk_instances;
    }
  });

  // A child slot's content: a binary node (interior, or a leaf of several instances: both
  // become a wide node of their own unless opened) or one instance.
  struct Item {
    bool instance;
    std::uint32_t index;  // binary node or instance
  };
  auto item_of = [&](std::uint32_t n) {
    const core::BvhNode& b = bvh.nodes[n];
    return b.is_leaf() && b.count == 1 ? Item{true, bvh.prim_index[b.first_or_child]} : Item{false, n};
  };
  auto box_of = [&](const Item& it) { return it.instance ? boxes[it.index] : bvh.nodes[it.index].box; };
  // The items an opened binary node spreads into: its two children, or a leaf's instances.
  auto open = [&](std::uint32_t n, std::vector<Item>& out) {
    const core::BvhNode& b = bvh.nodes[n];
    if (b.is_leaf()) {
      for (std::uint32_t k = 0; k < b.count; ++k) out.push_back({true, bvh.prim_index[b.first_or_child + k]});
    } else {
      out.push_back(item_of(b.first_or_child));
      out.push_back(item_of(b.first_or_child + 1));
    }
  };
  auto spread = [&](const core::BvhNode& b) { return b.is_leaf() ? b.count : 2u; };

  // Depth first: a wide node takes its binary node opened, then keeps opening the child of
  // largest area that still fits, up to 8 slots.
  struct Pending {
    std::uint32_t binary, wide;
  };
  nodes_.emplace_back();
  std::vector<Pending> todo{{0, 0}};
  std::vector<Item> kids;
  while (!todo.empty()) {
    const Pending p = todo.back();
    todo.pop_back();
    kids.clear();
    open(p.binary, kids);
    for (;;) {
      int best = -1;
      for (int k = 0; k < int(kids.size()); ++k) {
        if (kids[k].instance || kids.size() - 1 + spread(bvh.nodes[kids[k].index]) > 8) continue;
        if (best < 0 || box_of(kids[k]).half_area() > box_of(kids[best]).half_area()) best = k;
      }
      if (best < 0) break;
      const std::uint32_t n = kids[best].index;
      kids.erase(kids.begin() + best);
      open(n, kids);
    }
    for (int k = 0; k < simd::kWideN; ++k) {
      simd::WideNode<simd::kWideN>& node = nodes_[p.wide];  // (re-read: emplace_back below may move the array)
      if (k >= int(kids.size())) {
        for (int a = 0; a < 3; ++a) node.bounds[2 * a][k] = INFINITY, node.bounds[2 * a + 1][k] = -INFINITY;
        node.child[k] = simd::wide_ref::kEmptyRef;
        continue;
      }
      const core::BBox b = box_of(kids[k]);
      for (int a = 0; a < 3; ++a) node.bounds[2 * a][k] = b.lo[a], node.bounds[2 * a + 1][k] = b.hi[a];
      if (kids[k].instance) {
        node.child[k] = simd::wide_ref::leaf(ids_.size(), 1);
        ids_.push_back(kids[k].index);
      } else {
        node.child[k] = simd::wide_ref::interior<simd::kWideN>(nodes_.size());
        todo.push_back({kids[k].index, static_cast<std::uint32_t>(nodes_.size())});
        nodes_.emplace_back();
      }
    }
  }
  view_ = {nodes_.data(), ids_.data(), simd::wide_ref::interior<simd::kWideN>(0)};
}

}  // namespace volley::accel
