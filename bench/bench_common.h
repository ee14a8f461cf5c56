// Shared by the volley_bench suites that use whole scenes (traversal, build, render):
// where the scenes are, loading them once per process, and the synthetic slowdown that
// the regression-tracking tests use (perf/README.md).
#pragma once
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "io/scene_desc.h"
#include "volley/options.h"
#include "volley/ray.h"

namespace benchmark {
class State;
}

namespace volley::bench {

/// Folder of the shared benchmark meshes (`${scenes}/` in scene files): the VOLLEY_SCENES
/// environment variable (bench/main.cpp sets it from --scenes DIR), else
/// <source tree>/../shared/scenes (compile definition VOLLEY_BENCH_SHARED_SCENES).
std::filesystem::path shared_scenes_dir();

/// Folder of the project's own scenes (<source tree>/scenes).
std::filesystem::path project_scenes_dir();

/// Folder of the benchmark scenes (<source tree>/bench/scenes): cameras and lights for
/// the shared meshes, which they name as `${scenes}/...`.
std::filesystem::path bench_scenes_dir();

/// A benchmark scene: a short name for benchmark names and the file it is loaded from
/// (a `.json` scene or a bare mesh).
struct SceneFile {
  std::string name;
  std::filesystem::path file;
};

/// Resolves a scene name used in benchmark names: "cornell", "cornell-original",
/// "polygons" (project scenes), "teapot", "bunny", "conference" (bench/scenes: the shared
/// meshes with a camera that looks at them from close by or from inside), "bunny-bare",
/// "kitchen" (shared meshes as they are).
/// Throws std::invalid_argument for an unknown name.
SceneFile scene_file(const std::string& name);

/// Records the scene's file in the benchmark context as `volley_scene:<name>` (once per
/// name), so that perf/run can hash it. Call while registering, before the run starts.
void note_scene(const std::string& name);

/// The loaded description of a scene, parsed once per process and kept (not thread-safe:
/// benchmarks run one at a time). Throws io::LoadError when the file is missing or bad;
/// callers turn that into State::SkipWithError.
const io::SceneDesc& scene_desc(const std::string& name);

/// The scene's merged mesh, with the ISA as the benchmark's label; null (the benchmark
/// skipped with the reason) when the scene does not load.
const io::MeshDesc* mesh_for(benchmark::State& state, const std::string& scene, Isa isa);

/// 2^16 incoherent rays in the mesh's box: random origins inside it, random directions.
std::vector<Ray> incoherent_rays(const io::MeshDesc& mesh);

/// ISAs the scene suites register: the scalar oracle plus the SIMD ISAs the CPU has,
/// narrowest first. (SSE4.2 is left to the kernel suite to keep the scene suites short.)
bool bench_isa(Isa isa);

/// Synthetic slowdown factor F >= 1 from VOLLEY_BENCH_SLOWDOWN (unset or invalid: 1).
/// Every benchmark that supports it does about F times its work per iteration while
/// counting the same items, so its rate drops by F and its instruction count grows by F.
/// Only the regression-tracking tests set it (a deliberate regression that lives in the
/// benchmark code, never in the library); perf/run records it in the result context.
double slowdown_factor();

/// Extra units of work to repeat per iteration for `units` units of normal work:
/// round((F - 1) * units), 0 without a slowdown.
std::size_t slowdown_extra(std::size_t units);

}  // namespace volley::bench
