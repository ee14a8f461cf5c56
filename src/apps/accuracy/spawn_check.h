// Self-intersection of spawned rays (docs/accuracy.md, stress catalogue item 10): rays hit a
// tilted triangle at a given scale, a secondary ray leaves each hit point in a random
// direction (either side: reflection- and transmission-like) from the renderer's spawn
// offset (render/spawn.h), and an occlusion query tells whether it finds its own triangle
// again. Used by tests/render and by `volley accuracy --long`.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "volley/options.h"

namespace volley::accuracy {

struct SpawnRow {
  float scale = 1.0f;
  Isa isa = Isa::scalar;
  std::size_t spawned = 0;  ///< secondary rays tested
  std::size_t rehits = 0;   ///< of them, found their own triangle again
};

/// `count` spawned rays on a triangle of size ~`scale` placed ~`scale` from the origin,
/// traced with `isa` (watertight test). Deterministic for a seed.
SpawnRow spawn_check(float scale, std::size_t count, Isa isa, std::uint64_t seed = 11);

/// The scales the report covers: 1e-3 .. 1e6.
inline const std::vector<float> kSpawnScales = {1e-3f, 1.0f, 1e3f, 1e6f};

}  // namespace volley::accuracy
