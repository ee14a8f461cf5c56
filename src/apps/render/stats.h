// Ray counts by kind, summed over tiles (each tile counts privately, then adds once).
#pragma once
#include <array>
#include <cstdint>
#include <string_view>

namespace volley::render {

enum class RayKind { primary, shadow, reflection, refraction, diffuse, count };

inline constexpr std::array<std::string_view, 5> kRayKindNames = {
    "primary", "shadow", "reflection", "refraction", "diffuse"};

struct RayStats {
  std::array<std::uint64_t, static_cast<int>(RayKind::count)> rays{};
  void add(RayKind kind, std::uint64_t n = 1) { rays[static_cast<int>(kind)] += n; }
  std::uint64_t total() const {
    std::uint64_t sum = 0;
    for (auto r : rays) sum += r;
    return sum;
  }
  RayStats& operator+=(const RayStats& o) {
    for (std::size_t i = 0; i < rays.size(); ++i) rays[i] += o.rays[i];
    return *this;
  }
};

}  // namespace volley::render
