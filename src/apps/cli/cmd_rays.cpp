// volley rays: writes a workload (primary, shadow or diffuse rays of a scene) as a .vray
// file, so that `volley trace`, the benchmarks and the Embree side by side trace
// identical rays.
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "cli/commands.h"
#include "cli/common.h"
#include "io/ray_file.h"
#include "io/scene_loader.h"
#include "render/scene.h"
#include "render/workloads.h"

namespace volley::cli {
namespace {

struct RaysArgs {
  std::string scene;
  std::string workload;
  std::string output;
  std::string origins;  ///< --origins: the hit each ray leaves (.vhit)
  bool no_offset = false;
  int width = 0, height = 0, threads = 0;
  long long seed = -1;
  KernelArgs kernel;
};

}  // namespace

Runner register_rays(CLI::App& app) {
  auto args = std::make_shared<RaysArgs>();
  CLI::App* cmd = app.add_subcommand(
      "rays",
      "Write a ray workload as a .vray file: primary (camera rays in 4x4 pixel blocks),\n"
      "shadow (from the primary hits to the scene's first light) or diffuse (cosine-weighted\n"
      "about the shading normal at the primary hits)");
  cmd->add_option("scene", args->scene, "Scene file (.json) or mesh (.obj, .ply)")->required();
  cmd->add_option("--workload", args->workload, "Which rays: primary, shadow or diffuse")
      ->required()
      ->check(CLI::IsMember({"primary", "shadow", "diffuse"}));
  cmd->add_option("-o,--output", args->output, "Output ray file (.vray)")->required();
  cmd->add_option("--origins", args->origins,
                  "Also write the hit each ray leaves (.vhit, one per ray; a miss for primary rays): what\n"
                  "`volley trace --exclude` takes, so that each ray passes over the triangle it starts on");
  cmd->add_flag("--no-offset", args->no_offset,
                "Start shadow and diffuse rays on the hit point itself instead of offsetting them off the\n"
                "surface by its error bound: such rays hit their own triangle unless traced with --exclude");
  cmd->add_option("--width", args->width, "Image width in pixels (default: the scene's, else 512)")->check(CLI::Range(2, 16384));
  cmd->add_option("--height", args->height, "Image height in pixels (default: the scene's, else 512)")->check(CLI::Range(2, 16384));
  cmd->add_option("--seed", args->seed, "Random seed of the diffuse directions (default: the scene's)")
      ->check(CLI::NonNegativeNumber);
  add_threads_option(*cmd, args->threads, "Worker threads for tracing the primary hits");
  add_kernel_options(*cmd, args->kernel);

  return [args]() {
    const RaysArgs& a = *args;
    const io::SceneDesc desc = io::load_scene(a.scene, shared_scenes_dir(a.kernel.scenes));
    const int width = a.width ? a.width : desc.settings.width;
    const int height = a.height ? a.height : desc.settings.height;
    const std::uint64_t seed = a.seed >= 0 ? std::uint64_t(a.seed) : desc.settings.seed;
    const render::Workload workload = *render::parse_workload(a.workload);

    const render::Scene scene(desc, width, height, kernel_options(a.kernel));
    const auto start = std::chrono::steady_clock::now();
    std::vector<Hit> origins;
    const render::Spawning spawning{!a.no_offset, a.origins.empty() ? nullptr : &origins};
    const std::vector<Ray> rays = render::make_workload(scene, workload, seed, a.threads, spawning);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    io::write_rays(a.output, rays);
    if (!a.origins.empty()) io::write_hits(a.origins, origins);
    if (rays.empty())
      std::fprintf(stderr, "volley: warning: no %s rays: no primary ray hits the scene (is it behind the camera, or "
                   "nearer than its image plane?)\n", a.workload.c_str());

    const std::size_t pixels = std::size_t(width) * std::size_t(height);
    std::printf("%s: %s rays, %dx%d pixels, %zu rays (%.1f%% of the pixels)%s, made in %.3f s -> %s\n",
                a.scene.c_str(), a.workload.c_str(), width, height, rays.size(),
                100.0 * double(rays.size()) / double(pixels),
                workload == render::Workload::diffuse ? (", seed " + std::to_string(seed)).c_str() : "", seconds,
                a.output.c_str());
    if (!a.origins.empty()) std::printf("the hit each ray leaves -> %s\n", a.origins.c_str());
    return 0;
  };
}

}  // namespace volley::cli
