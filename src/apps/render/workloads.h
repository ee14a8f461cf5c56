// Ray workloads for benchmarks and `volley rays`: the primary, shadow and diffuse rays a
// renderer of the scene would trace, as plain AoS ray arrays (written to .vray files and
// traced by `volley trace`, volley_bench and volley_vs_embree on identical input).
#pragma once
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "render/camera.h"
#include "render/scene.h"
#include "volley/ray.h"

namespace volley::render {

/// Which rays a workload holds.
enum class Workload {
  primary,  ///< camera rays, one per pixel, in 4x4 pixel blocks (coherent)
  shadow,   ///< from the primary hits to the scene's first light (coherent-ish, any-hit)
  diffuse,  ///< cosine-distributed about the shading normal at the primary hits (incoherent)
};

/// Names as used on the command line ("primary", "shadow", "diffuse").
std::string_view to_string(Workload workload);
/// Parses a command-line name; std::nullopt for an unknown name.
std::optional<Workload> parse_workload(std::string_view name);

/// How the secondary rays of a workload leave their hit points.
struct Spawning {
  /// Origins offset off the surface by the hit point's error bound (spawn.h), so that no ray
  /// meets the triangle it leaves; false: origins on the computed hit point itself, for
  /// the excluding queries, which pass over that triangle by its id (Accel::intersect_excluding).
  bool offset = true;
  /// When not null: the hit each ray leaves, one per ray (a miss for primary rays).
  std::vector<Hit>* from = nullptr;
};

/// Pixel size of a primary-ray block: any 16 consecutive rays of a block are one packet.
inline constexpr int kBlock = 4;

/// Pixel coordinates of primary ray i, in the order primary_rays() emits them: blocks of
/// 4x4 pixels in row-major block order, row-major inside a block. Blocks on the right
/// and bottom edges of an image whose size is not a multiple of 4 are clipped to the
/// image (fewer than 16 rays), so packets after them straddle two neighbouring blocks.
/// width, height >= 1; returns width * height pairs (x, y), x left to right, y top down.
std::vector<std::pair<int, int>> block_order(int width, int height);

/// One camera ray per pixel through the pixel point (x, y) — the notes' pixel positions,
/// as the renderer samples with 1 sample per pixel — in block_order(). tmin = 0,
/// tmax = +inf, direction = pixel point - eye (not normalized).
std::vector<Ray> primary_rays(const core::Camera& camera);

/// Closest hits of `rays` (parallel over oneTBB worker threads, `threads` = 0: all).
std::vector<Hit> trace_all(const Accel& accel, std::span<const Ray> rays, int threads = 0);

/// Shadow rays from the hits of `primary` (hits[i] answers primary[i]) toward the scene's
/// first light (Scene adds a light to bare meshes). One ray per primary ray that hit
/// something and whose geometric normal (facing the viewer) faces the light; the others
/// (misses, and surfaces the light is behind, which the renderer never tests either) give
/// none. Each is spawn_shadow_ray(): origin offset off the surface, direction = light -
/// origin, interval [0, 1). Order follows the primary rays. Throws volley::Error when the
/// scene has no light.
std::vector<Ray> shadow_rays(const Scene& scene, std::span<const Ray> primary, std::span<const Hit> hits,
                             const Spawning& spawning = {});

/// Diffuse bounce rays from the hits of `primary`: a unit direction drawn cosine-weighted
/// about the shading normal (Malley's method), from a PCG32 stream seeded with (seed,
/// index of the primary ray), so the result depends on seed only. Rays that the shading
/// normal sends below the geometric surface are dropped (as the path tracer does), misses
/// give none. Each is spawn_ray(): offset origin, interval [0, +inf). Order follows the
/// primary rays.
std::vector<Ray> diffuse_rays(const Scene& scene, std::span<const Ray> primary, std::span<const Hit> hits,
                              std::uint64_t seed, const Spawning& spawning = {});

/// The whole workload for the scene's camera: primary_rays(), and for shadow / diffuse
/// their hits (trace_all) turned into secondary rays as above. `threads` as trace_all.
std::vector<Ray> make_workload(const Scene& scene, Workload workload, std::uint64_t seed, int threads = 0,
                               const Spawning& spawning = {});

}  // namespace volley::render
