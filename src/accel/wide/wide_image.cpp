// The check of a wide BVH read from a file (WideAccel::adopt): the walks trust their tree
// (no bounds checks per step), so a loaded one is proven sound once, before any query.
#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "accel/wide/wide_accel.h"
#include "core/kernel_constants.h"

namespace volley::accel {

std::size_t check_wide_tree(const simd::WideNode<simd::kWideN>* nodes, std::size_t node_count,
                            std::size_t block_count, std::uint32_t root) {
  namespace ref = simd::wide_ref;
  constexpr std::size_t kNodeBytes = sizeof(simd::WideNode<simd::kWideN>);
  auto fail = [](const std::string& what) { throw std::invalid_argument("wide BVH: " + what); };
  auto check_leaf = [&](std::uint32_t r, auto where) {
    if (std::size_t{ref::leaf_first(r)} + ref::leaf_count(r) > block_count)
      fail(where() + " names blocks " + std::to_string(ref::leaf_first(r)) + " + " +
           std::to_string(ref::leaf_count(r)) + " of " + std::to_string(block_count));
  };
  if (root & ref::kLeafBit) {
    if (node_count != 0) fail("a leaf root with " + std::to_string(node_count) + " nodes beside it");
    check_leaf(root, [] { return std::string("the root leaf"); });
    return 0;
  }
  if (root != 0) fail("the root is not node 0");
  if (node_count == 0) fail("an interior root without nodes");
  std::vector<unsigned char> met(node_count, 0);
  struct Item {
    std::size_t index, depth;
  };
  std::vector<Item> stack{{0, 0}};
  met[0] = 1;
  std::size_t deepest = 0;
  while (!stack.empty()) {
    const Item at = stack.back();
    stack.pop_back();
    const simd::WideNode<simd::kWideN>& node = nodes[at.index];
    for (int c = 0; c < simd::kWideN; ++c) {
      const std::uint32_t r = node.child[c];
      auto where = [&] { return "node " + std::to_string(at.index) + " child " + std::to_string(c); };
      if (r & ref::kLeafBit) {
        check_leaf(r, where);
        if (r != ref::kEmptyRef) deepest = std::max(deepest, at.depth + 1);
        continue;
      }
      const std::size_t index = r / kNodeBytes;
      if (r % kNodeBytes != 0 || index >= node_count) fail(where() + " points outside the nodes");
      if (index <= at.index) fail(where() + " points back to node " + std::to_string(index));
      if (met[index]) fail(where() + " points to node " + std::to_string(index) + ", which has another parent");
      if (at.depth + 1 >= std::size_t(core::kBvhMaxDepth))
        fail("interior nodes " + std::to_string(core::kBvhMaxDepth) + " levels deep (the walks' stacks hold fewer)");
      met[index] = 1;
      stack.push_back({index, at.depth + 1});
    }
  }
  return deepest;
}

void check_block_ids(const unsigned char* blocks, std::size_t count, std::size_t first_block, const WideAccel& layout,
                     const ImageIds& ids) {
  const std::size_t bytes = layout.block_bytes(), offset = layout.prim_offset();
  const int w = layout.block_width();
  const std::vector<std::uint32_t>& others = *ids.not_triangles;
  for (std::size_t b = 0; b < count; ++b) {
    const unsigned char* prim = blocks + b * bytes + offset;
    for (int l = 0; l < w; ++l) {
      std::uint32_t id;
      std::memcpy(&id, prim + 4 * l, 4);
      if (id == kInvalidPrim) continue;
      if (id >= ids.id_limit || (!others.empty() && std::binary_search(others.begin(), others.end(), id)))
        throw std::invalid_argument("wide BVH: block " + std::to_string(first_block + b) + " lane " +
                                    std::to_string(l) + " names triangle " + std::to_string(id) +
                                    ", which the scene does not have");
    }
  }
}

}  // namespace volley::accel
