#include "accel/instance_tree.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/bvh.h"
#include "simd/wide/wide_traverse.h"

namespace volley::accel {

std::size_t InstanceTree::bytes() const {
  return nodes_.size() * sizeof(nodes_[0]) + ids_.size() * sizeof(ids_[0]) +
         bvh_.nodes.size() * sizeof(bvh_.nodes[0]) + bvh_.prim_index.size() * sizeof(bvh_.prim_index[0]);
}

namespace {

/// A child slot's content: a binary node (interior, or a leaf of several instances: both
/// become a wide node of their own unless opened) or one instance.
struct Item {
  bool instance;
  std::uint32_t index;  ///< binary node or instance
};

/// The binary tree of instance boxes collapsed into wide nodes, depth first: a wide node
/// takes its binary node opened, then keeps opening the child of largest area that still
/// fits, up to 8 slots.
class Collapse {
 public:
  Collapse(const core::Bvh& bvh, const std::vector<core::BBox>& boxes,
           simd::AlignedVector<simd::WideNode<simd::kWideN>>& nodes, std::vector<std::uint32_t>& ids)
      : bvh_(bvh), boxes_(boxes), nodes_(nodes), ids_(ids) {}

  void run() {
    nodes_.emplace_back();
    todo_.push_back({0, 0});
    std::vector<Item> kids;
    while (!todo_.empty()) {
      const Pending p = todo_.back();
      todo_.pop_back();
      gather(p.binary, kids);
      fill(p.wide, kids);
    }
  }

 private:
  struct Pending {
    std::uint32_t binary, wide;
  };

  Item item_of(std::uint32_t n) const {
    const core::BvhNode& b = bvh_.nodes[n];
    return b.is_leaf() && b.count == 1 ? Item{true, bvh_.prim_index[b.first_or_child]} : Item{false, n};
  }
  core::BBox box_of(const Item& it) const { return it.instance ? boxes_[it.index] : bvh_.nodes[it.index].box; }
  /// The slots an opened binary node takes: a leaf's instances, or two children.
  std::uint32_t spread(std::uint32_t n) const {
    const core::BvhNode& b = bvh_.nodes[n];
    return b.is_leaf() ? b.count : 2u;
  }
  /// The items an opened binary node spreads into: its two children, or a leaf's instances.
  void open(std::uint32_t n, std::vector<Item>& out) const {
    const core::BvhNode& b = bvh_.nodes[n];
    if (b.is_leaf()) {
      for (std::uint32_t k = 0; k < b.count; ++k) out.push_back({true, bvh_.prim_index[b.first_or_child + k]});
    } else {
      out.push_back(item_of(b.first_or_child));
      out.push_back(item_of(b.first_or_child + 1));
    }
  }
  /// The slots of the wide node of binary node `binary`.
  void gather(std::uint32_t binary, std::vector<Item>& kids) const {
    kids.clear();
    open(binary, kids);
    for (;;) {
      int best = -1;
      for (int k = 0; k < int(kids.size()); ++k) {
        if (kids[k].instance || kids.size() - 1 + spread(kids[k].index) > simd::kWideN) continue;
        if (best < 0 || box_of(kids[k]).half_area() > box_of(kids[best]).half_area()) best = k;
      }
      if (best < 0) return;
      const std::uint32_t n = kids[best].index;
      kids.erase(kids.begin() + best);
      open(n, kids);
    }
  }
  /// Wide node `wide` from its slots: an instance's id, or a new wide node queued.
  void fill(std::uint32_t wide, const std::vector<Item>& kids) {
    for (int k = 0; k < simd::kWideN; ++k) {
      simd::WideNode<simd::kWideN>& node = nodes_[wide];  // (re-read: emplace_back below may move the array)
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
        todo_.push_back({kids[k].index, static_cast<std::uint32_t>(nodes_.size())});
        nodes_.emplace_back();
      }
    }
  }

  const core::Bvh& bvh_;
  const std::vector<core::BBox>& boxes_;
  simd::AlignedVector<simd::WideNode<simd::kWideN>>& nodes_;
  std::vector<std::uint32_t>& ids_;
  std::vector<Pending> todo_;
};

}  // namespace

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
  // only decides how instances are grouped into nodes; perf/reports/instances.md).
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
  Collapse(bvh, boxes, nodes_, ids_).run();
  view_ = {nodes_.data(), ids_.data(), simd::wide_ref::interior<simd::kWideN>(0)};
}

}  // namespace volley::accel
