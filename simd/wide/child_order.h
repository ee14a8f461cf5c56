// The single-ray walk's child order: which entered child is walked next, the others onto
// the stack (the nearest last, so that it pops first).
#pragma once
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "simd/wide/node_lanes.h"
#include "simd/wide/stack.h"

namespace volley::simd {

namespace detail {

/// Any order (no distances, the stack entries never pruned): the first entered child next,
/// the others on the stack. `hits.bits` != 0. Returns the child walked next.
template <class Arch>
[[gnu::always_inline]] inline std::uint32_t push_in_slot_order(const WideNode<8>& node, ChildHits<Arch> hits,
                                                               WideStackItem<Arch>* stack, int& size) {
  for (std::uint32_t bits = hits.bits & (hits.bits - 1); bits != 0; bits &= bits - 1)
    stack[size++].ref = node.child[std::countr_zero(bits)];
  return hits.first_ref;
}

/// Two entered children, i and j: the nearer next, the other on the stack (selects, not a
/// branch: which one is nearer is a coin toss to the predictor).
template <class Arch>
[[gnu::always_inline]] inline std::uint32_t push_farther_of_two(const WideNode<8>& node, const ChildHits<Arch>& hits,
                                                                typename Lanes8<Arch>::V entry, const float* dist,
                                                                int i, int j, WideStackItem<Arch>* stack, int& size) {
  std::uint32_t ci, cj;
  float di, dj;
  if constexpr (kHasMaskRegisters<Arch>) {
    ci = hits.first_ref;
    Lanes8<Arch>::second_and_distances(hits, entry, cj, di, dj);
  } else {
    ci = hits.first_ref, cj = node.child[j];
    di = dist[i], dj = dist[j];
  }
  const bool swap = dj < di;
  stack[size++] = {swap ? ci : cj, swap ? di : dj};
  return swap ? cj : ci;
}

/// Three or four entered children (i, j and those of `bits`; most nodes with three or more
/// hit children): sorted in registers by a stable network of compare-exchanges, the nearest
/// reference never stored and reloaded as in the insertion sort of push_sorted. GCC
/// compiles each exchange to a short branch; branch-free, the nearest would wait for every
/// exchange (the variants measured: perf/reports/traversal.md).
template <class Arch>
[[gnu::always_inline]] inline std::uint32_t push_three_or_four(const WideNode<8>& node, const float* dist, int i, int j,
                                                               std::uint32_t bits, WideStackItem<Arch>* stack,
                                                               int& size) {
  std::uint64_t w[4] = {stack_word(node.child[i], dist[i]), stack_word(node.child[j], dist[j]), 0, 0};
  const int k = std::countr_zero(bits);
  w[2] = stack_word(node.child[k], dist[k]);
  bits &= bits - 1;
  int n = 3;
  if (bits == 0) {
    sort_far_first<3>(w);
  } else {
    const int l = std::countr_zero(bits);
    w[3] = stack_word(node.child[l], dist[l]);
    sort_far_first<4>(w);
    n = 4;
  }
  std::memcpy(&stack[size], w, 8 * static_cast<std::size_t>(n - 1));
  size += n - 1;
  return static_cast<std::uint32_t>(w[n - 1]);
}

/// Five or more: all pushed, the pushed run sorted far to near (insertion sort of at most
/// eight), and the nearest (the top) popped as the next.
template <class Arch>
[[gnu::always_inline]] inline std::uint32_t push_sorted(const WideNode<8>& node, const float* dist, int i, int j,
                                                        std::uint32_t bits, WideStackItem<Arch>* stack, int& size) {
  const int base = size;
  stack[size++] = {node.child[i], dist[i]};
  stack[size++] = {node.child[j], dist[j]};
  for (; bits != 0; bits &= bits - 1) {
    const int k = std::countr_zero(bits);
    stack[size++] = {node.child[k], dist[k]};
  }
  for (int a = base + 1; a < size; ++a) {
    const WideStackItem<Arch> item = stack[a];
    int b = a;
    for (; b > base && stack[b - 1].entry < item.entry; --b) stack[b] = stack[b - 1];
    stack[b] = item;
  }
  return stack[--size].ref;
}

/// Nearest first: the entered children of `node` (two or more in `hits.bits`, entry
/// distances `entry`) but the nearest onto the stack, farthest deepest. Returns the nearest.
template <class Arch>
[[gnu::always_inline]] inline std::uint32_t push_near_first(const WideNode<8>& node, const ChildHits<Arch>& hits,
                                                            typename Lanes8<Arch>::V entry, WideStackItem<Arch>* stack,
                                                            int& size) {
  std::uint32_t bits = hits.bits;
  const int i = std::countr_zero(bits);
  bits &= bits - 1;
  alignas(32) float dist[8];
  Lanes8<Arch>::store(dist, entry);
  const int j = std::countr_zero(bits);
  bits &= bits - 1;
  if (bits == 0) return push_farther_of_two(node, hits, entry, dist, i, j, stack, size);
  if (std::popcount(bits) <= 2) return push_three_or_four(node, dist, i, j, bits, stack, size);
  return push_sorted(node, dist, i, j, bits, stack, size);
}

}  // namespace detail

}  // namespace volley::simd
