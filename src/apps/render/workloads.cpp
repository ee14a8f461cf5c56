#include "render/workloads.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "render/rng.h"
#include "render/sampling.h"
#include "render/spawn.h"

namespace volley::render {
namespace {

// Runs body(begin, end) over [0, count) in chunks on `threads` workers (0: all).
template <class Body>
void parallel_chunks(std::size_t count, int threads, const Body& body) {
  const int n = threads > 0 ? threads : tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(n);
  arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1024),
                      [&](const tbb::blocked_range<std::size_t>& r) { body(r.begin(), r.end()); });
  });
}

// Secondary rays from the hits, one optional ray per primary ray, made in parallel and
// compacted in primary order (so the result does not depend on the thread count); the hit
// each leaves into `from` when it is not null.
template <class Make>
std::vector<Ray> from_hits(std::span<const Ray> primary, std::span<const Hit> hits, const Make& make,
                           std::vector<Hit>* from) {
  if (primary.size() != hits.size())
    throw std::invalid_argument("workload: " + std::to_string(hits.size()) + " hits for " +
                                std::to_string(primary.size()) + " rays");
  std::vector<Ray> candidate(primary.size());
  std::vector<unsigned char> keep(primary.size(), 0);
  parallel_chunks(primary.size(), 0, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      if (hits[i].hit()) keep[i] = make(i, candidate[i]) ? 1 : 0;
  });
  std::vector<Ray> out;
  out.reserve(primary.size());
  if (from) from->clear();
  for (std::size_t i = 0; i < primary.size(); ++i) {
    if (!keep[i]) continue;
    out.push_back(candidate[i]);
    if (from) from->push_back(hits[i]);
  }
  return out;
}

}  // namespace

std::string_view to_string(Workload workload) {
  switch (workload) {
    case Workload::primary: return "primary";
    case Workload::shadow: return "shadow";
    case Workload::diffuse: return "diffuse";
  }
  return "?";
}

std::optional<Workload> parse_workload(std::string_view name) {
  for (Workload w : {Workload::primary, Workload::shadow, Workload::diffuse})
    if (name == to_string(w)) return w;
  return std::nullopt;
}

std::vector<std::pair<int, int>> block_order(int width, int height) {
  std::vector<std::pair<int, int>> order;
  order.reserve(std::size_t(std::max(width, 0)) * std::size_t(std::max(height, 0)));
  for (int by = 0; by < height; by += kBlock)
    for (int bx = 0; bx < width; bx += kBlock)
      for (int y = by; y < std::min(by + kBlock, height); ++y)
        for (int x = bx; x < std::min(bx + kBlock, width); ++x) order.emplace_back(x, y);
  return order;
}

std::vector<Ray> primary_rays(const core::Camera& camera) {
  const auto order = block_order(camera.width(), camera.height());
  std::vector<Ray> rays(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    const auto r = camera.ray(float(order[i].first), float(order[i].second));
    rays[i] = Ray{{r.org.x, r.org.y, r.org.z}, r.tmin, {r.dir.x, r.dir.y, r.dir.z}, r.tmax};
  }
  return rays;
}

std::vector<Hit> trace_all(const Accel& accel, std::span<const Ray> rays, int threads) {
  std::vector<Hit> hits(rays.size());
  parallel_chunks(rays.size(), threads, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) hits[i] = accel.intersect(rays[i]);
  });
  return hits;
}

std::vector<Ray> shadow_rays(const Scene& scene, std::span<const Ray> primary, std::span<const Hit> hits,
                             const Spawning& spawning) {
  if (scene.lights().empty()) throw Error("the scene has no light: no shadow rays to make");
  const glm::vec3 light = scene.lights().front().position;
  return from_hits(primary, hits, [&](std::size_t i, Ray& out) {
    const SurfacePoint s = scene.surface(primary[i], hits[i]);
    // A light behind the surface (seen from the viewer's side) is never tested.
    if (!(glm::dot(light - s.p, s.ng) > 0.0f)) return false;
    const glm::vec3 d = light - s.p;
    out = spawning.offset ? spawn_shadow_ray(s.p, s.p_error, s.ng, light) : Ray{{s.p.x, s.p.y, s.p.z}, 0.0f, {d.x, d.y, d.z}, 1.0f};
    return true;
  }, spawning.from);
}

std::vector<Ray> diffuse_rays(const Scene& scene, std::span<const Ray> primary, std::span<const Hit> hits,
                              std::uint64_t seed, const Spawning& spawning) {
  return from_hits(primary, hits, [&](std::size_t i, Ray& out) {
    const SurfacePoint s = scene.surface(primary[i], hits[i]);
    Rng rng(seed, i);
    const glm::vec3 w = cosine_direction(s.ns, rng);
    if (!(glm::dot(w, s.ng) > 0.0f)) return false;  // the shading normal sent it below the surface
    out = spawning.offset ? spawn_ray(s.p, s.p_error, s.ng, w)
                          : Ray{{s.p.x, s.p.y, s.p.z}, 0.0f, {w.x, w.y, w.z}, std::numeric_limits<float>::infinity()};
    return true;
  }, spawning.from);
}

std::vector<Ray> make_workload(const Scene& scene, Workload workload, std::uint64_t seed, int threads,
                               const Spawning& spawning) {
  std::vector<Ray> primary = primary_rays(scene.camera());
  if (workload == Workload::primary) {
    if (spawning.from) spawning.from->assign(primary.size(), Hit{});  // camera rays leave no surface
    return primary;
  }
  const std::vector<Hit> hits = trace_all(scene.accel(), primary, threads);
  return workload == Workload::shadow ? shadow_rays(scene, primary, hits, spawning)
                                      : diffuse_rays(scene, primary, hits, seed, spawning);
}

}  // namespace volley::render
