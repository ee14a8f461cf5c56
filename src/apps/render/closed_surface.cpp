#include "render/closed_surface.h"

#include <algorithm>
#include <bit>
#include <utility>

namespace volley::core {
namespace {

// The exact position as integers, -0 as +0 (so that the two weld).
std::array<std::uint32_t, 3> key_of(const glm::vec3& p) {
  return {std::bit_cast<std::uint32_t>(p.x + 0.0f), std::bit_cast<std::uint32_t>(p.y + 0.0f),
          std::bit_cast<std::uint32_t>(p.z + 0.0f)};
}

}  // namespace

void ClosureCheck::add_face(const glm::vec3* corners, std::size_t n) {
  const auto base = std::uint32_t(points_.size());
  points_.insert(points_.end(), corners, corners + n);
  for (std::uint32_t i = 0; i < n; ++i) edges_.push_back({base + i, base + std::uint32_t((i + 1) % n)});
}

void ClosureCheck::add_triangles(const std::vector<glm::vec3>& positions, const std::vector<std::uint32_t>& indices) {
  const auto base = std::uint32_t(points_.size());
  points_.insert(points_.end(), positions.begin(), positions.end());
  edges_.reserve(edges_.size() + indices.size());
  for (std::size_t i = 0; i + 2 < indices.size(); i += 3)
    for (int k = 0; k < 3; ++k) edges_.push_back({base + indices[i + k], base + indices[i + (k + 1) % 3]});
}

ClosureReport ClosureCheck::finish() {
  // Weld: every point gets the id of the first point at its exact position. Sorted as
  // (x, y) and (z, point) bit patterns: two 64-bit compares instead of four.
  std::vector<std::pair<std::uint64_t, std::uint64_t>> keyed(points_.size());
  for (std::uint32_t i = 0; i < points_.size(); ++i) {
    const auto k = key_of(points_[i]);
    keyed[i] = {std::uint64_t(k[0]) << 32 | k[1], std::uint64_t(k[2]) << 32 | i};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::uint32_t> weld(points_.size());
  const auto same_position = [](const auto& a, const auto& b) {
    return a.first == b.first && (a.second >> 32) == (b.second >> 32);
  };
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    const auto point = std::uint32_t(keyed[i].second);
    weld[point] = i > 0 && same_position(keyed[i], keyed[i - 1]) ? weld[std::uint32_t(keyed[i - 1].second)] : point;
  }
  // Undirected edges as (smaller id, larger id, direction) in one integer (ids < 2^31);
  // zero-length ones dropped.
  std::vector<std::uint64_t> undirected;
  undirected.reserve(edges_.size());
  for (const auto& e : edges_) {
    const std::uint32_t a = weld[e[0]], b = weld[e[1]];
    if (a != b)
      undirected.push_back(std::uint64_t(std::min(a, b)) << 33 | std::uint64_t(std::max(a, b)) << 1 | (a < b));
  }
  std::sort(undirected.begin(), undirected.end());
  // Each edge must come exactly twice, once each way (sorted: backward, then forward).
  ClosureReport report;
  report.edges = undirected.size();
  for (std::size_t i = 0; i < undirected.size();) {
    std::size_t j = i + 1;
    while (j < undirected.size() && undirected[j] >> 1 == undirected[i] >> 1) ++j;
    if (!(j - i == 2 && (undirected[i] & 1) == 0 && (undirected[i + 1] & 1) == 1)) report.unmatched += j - i;
    i = j;
  }
  points_ = {};
  edges_ = {};
  return report;
}

}  // namespace volley::core
