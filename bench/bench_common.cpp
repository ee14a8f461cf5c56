// Scene lookup, scene cache and synthetic slowdown for the volley_bench suites.
#include "bench_common.h"

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <exception>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <stdexcept>

#include "io/scene_loader.h"
#include "simd/isa/dispatch.h"

namespace volley::bench {

std::filesystem::path shared_scenes_dir() {
  if (const char* env = std::getenv("VOLLEY_SCENES"); env && *env) return env;
  return VOLLEY_BENCH_SHARED_SCENES;
}

std::filesystem::path project_scenes_dir() { return std::filesystem::path(VOLLEY_BENCH_SOURCE_DIR) / "scenes"; }

std::filesystem::path bench_scenes_dir() { return std::filesystem::path(VOLLEY_BENCH_SOURCE_DIR) / "bench" / "scenes"; }

SceneFile scene_file(const std::string& name) {
  enum class Dir { project, bench, shared };
  static const std::map<std::string, std::pair<Dir, std::string>> kScenes = {
      // name -> (folder, file)
      {"cornell", {Dir::project, "cornell.json"}},                    // 32 triangles + a sphere mesh, mirror and glass
      {"cornell-original", {Dir::project, "cornell-original.json"}},  // the path-traced Cornell box
      {"polygons", {Dir::project, "polygons.json"}},                  // planar polygons only
      {"teapot", {Dir::bench, "teapot.json"}},          // 6.3 k triangles filling the view (the callgrind scene)
      {"bunny", {Dir::bench, "bunny.json"}},            // 69 k triangles, close-up
      {"conference", {Dir::bench, "conference.json"}},  // 331 k triangles, camera inside the room
      {"bunny-bare", {Dir::shared, "stanford-bunny.obj"}},  // a bare mesh: automatic camera and light
      {"kitchen", {Dir::shared, "kitchen_partial.obj"}},    // 1 M triangles, a bare mesh (refit suite)
  };
  const auto it = kScenes.find(name);
  if (it == kScenes.end()) throw std::invalid_argument("unknown benchmark scene " + name);
  const auto& [dir, file] = it->second;
  const std::filesystem::path folder =
      dir == Dir::project ? project_scenes_dir() : dir == Dir::bench ? bench_scenes_dir() : shared_scenes_dir();
  return {name, folder / file};
}

void note_scene(const std::string& name) {
  static std::set<std::string> noted;
  if (noted.insert(name).second) benchmark::AddCustomContext("volley_scene:" + name, scene_file(name).file.string());
}

const io::SceneDesc& scene_desc(const std::string& name) {
  static std::map<std::string, std::unique_ptr<io::SceneDesc>> cache;
  auto& slot = cache[name];
  if (!slot) slot = std::make_unique<io::SceneDesc>(io::load_scene(scene_file(name).file, shared_scenes_dir()));
  return *slot;
}

const io::MeshDesc* mesh_for(benchmark::State& state, const std::string& scene, Isa isa) {
  state.SetLabel(std::string(volley::to_string(isa)));
  try {
    return &scene_desc(scene).mesh;
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return nullptr;
  }
}

std::vector<Ray> incoherent_rays(const io::MeshDesc& mesh) {
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  for (const glm::vec3& p : mesh.positions) lo = glm::min(lo, p), hi = glm::max(hi, p);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.0f, 1.0f), d(-1.0f, 1.0f);
  std::vector<Ray> rays(1 << 16);
  for (Ray& r : rays) {
    const glm::vec3 o = lo + (hi - lo) * glm::vec3(u(rng), u(rng), u(rng));
    r = Ray{{o.x, o.y, o.z}, 0.0f, {d(rng), d(rng), d(rng)}, INFINITY};
  }
  return rays;
}

bool bench_isa(Isa isa) { return isa == Isa::scalar || (isa != Isa::sse42 && simd::cpu_has(isa)); }

double slowdown_factor() {
  static const double factor = [] {
    const char* env = std::getenv("VOLLEY_BENCH_SLOWDOWN");
    if (!env || !*env) return 1.0;
    char* end = nullptr;
    const double f = std::strtod(env, &end);
    return (end != env && std::isfinite(f) && f >= 1.0) ? f : 1.0;
  }();
  return factor;
}

std::size_t slowdown_extra(std::size_t units) {
  return static_cast<std::size_t>(std::llround((slowdown_factor() - 1.0) * static_cast<double>(units)));
}

}  // namespace volley::bench
