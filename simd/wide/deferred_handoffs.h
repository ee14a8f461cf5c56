// The per-lane packet walk's deferred hand-offs (packet_walk.h): the subtrees it leaves to
// single rays, each requested from memory when listed and walked after the packet's own
// walk, so that the cache misses of a tree larger than the caches overlap the packet's
// walk and one another instead of following one another.
#pragma once
#include <bit>
#include <cstdint>

#include "simd/wide_bvh.h"

namespace volley::simd::detail {

/// Up to kMax (subtree, lane) pairs. The count is kept by the walk, with its other
/// changing state, where it stays in a register.
struct DeferredHandoffs {
  static constexpr int kMax = 32;
  std::uint32_t ref[kMax];
  std::uint8_t lane[kMax];

  /// Lists subtree `cur` for each lane of `bits` (count + popcount(bits) <= kMax) and
  /// requests it from memory.
  template <class View>
  [[gnu::always_inline]] void add(const View& bvh, std::uint32_t cur, std::uint32_t bits, int& count) {
    if (cur & wide_ref::kLeafBit)
      wide_ref::request_leaf(bvh.blocks, cur);
    else
      wide_ref::request_node(bvh.nodes, cur);
    for (std::uint32_t b = bits; b != 0; b &= b - 1) {
      ref[count] = cur;
      lane[count++] = static_cast<std::uint8_t>(std::countr_zero(b));
    }
  }

  /// Requests the children of every listed interior subtree, before the listed walks start.
  template <class View>
  [[gnu::always_inline]] void request_children(const View& bvh, int count) const {
    for (int k = 0; k < count; ++k) {
      if (ref[k] & wide_ref::kLeafBit) continue;
      const auto& node = wide_ref::node_at(bvh.nodes, ref[k]);
      for (int j = 0; j < kWideN && node.child[j] != wide_ref::kEmptyRef; ++j) {
        if (node.child[j] & wide_ref::kLeafBit)
          wide_ref::request_leaf(bvh.blocks, node.child[j]);
        else
          wide_ref::request_node(bvh.nodes, node.child[j]);
      }
    }
  }
};

}  // namespace volley::simd::detail
