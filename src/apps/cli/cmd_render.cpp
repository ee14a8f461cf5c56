// volley render: renders a scene to PNG with a progress bar and a summary line.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include "cli/commands.h"
#include "cli/common.h"
#include "cli/progress.h"
#include "io/png_writer.h"
#include "io/scene_loader.h"
#include "render/pipeline.h"
#include "render/renderer.h"

namespace volley::cli {
namespace {

struct RenderArgs {
  std::string scene;
  std::string output;
  int width = 0, height = 0, spp = 0, max_depth = -1, threads = 0;
  std::string integrator;
  long long seed = -1;
  bool stats = false;
  bool no_specialize = false;
  KernelArgs kernel;
};

void print_stats(const render::Scene& scene, const io::SceneDesc& desc, const render::RenderResult& r) {
  const AccelInfo info = scene.accel().info();
  const render::SceneFeatures f = render::with_closure(scene, desc);
  std::printf("rays by kind:");
  for (std::size_t k = 0; k < r.stats.rays.size(); ++k)
    std::printf(" %s %llu%s", std::string(render::kRayKindNames[k]).c_str(),
                (unsigned long long)r.stats.rays[k], k + 1 < r.stats.rays.size() ? "," : "\n");
  std::printf("kernel: test %s, isa %s; BVH %zu nodes, %zu leaves, depth %zu, SAH %.1f, %.1f bytes/primitive, built in %.3f s\n",
              std::string(to_string(info.test)).c_str(), std::string(to_string(info.isa)).c_str(),
              info.nodes, info.leaves, info.depth, info.sah_cost,
              double(info.bytes) / double(std::max<std::size_t>(1, info.triangles + info.polygons)),
              info.build_seconds);
  std::printf("skipped: %s\n", render::describe_skipped(r.stages, f).c_str());
  std::printf("occlusion: %s\n", render::describe_culling(f).c_str());
}

}  // namespace

Runner register_render(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand("render", "Render a scene to a PNG image");
  cmd->add_option("scene", args->scene, "Scene file (.json) or mesh (.obj, .ply)")->required();
  cmd->add_option("-o,--output", args->output, "Output PNG (default out/<scene name>.png)")->check(png_path());
  cmd->add_option("--width", args->width, "Image width in pixels (default: the scene's, else 512)")->check(CLI::Range(2, 16384));
  cmd->add_option("--height", args->height, "Image height in pixels (default: the scene's, else 512)")->check(CLI::Range(2, 16384));
  cmd->add_option("--spp", args->spp, "Samples per pixel (stratified jitter when > 1)")->check(CLI::Range(1, 65536));
  cmd->add_option("--max-depth", args->max_depth, "Bounces after the primary hit")->check(CLI::Range(0, 64));
  add_threads_option(*cmd, args->threads);
  cmd->add_option("--integrator", args->integrator, "whitted (the notes' ray tracer) or path (diffuse interreflection)")
      ->check(CLI::IsMember({"whitted", "path"}));
  cmd->add_option("--seed", args->seed, "Random seed (images are identical for a given seed)")->check(CLI::NonNegativeNumber);
  cmd->add_flag("--stats", args->stats, "Print rays by kind, kernel and BVH facts, what was skipped");
  cmd->add_flag("--no-specialize", args->no_specialize,
                "Run the general pipeline (every stage) instead of one specialised to the scene; same image");
  add_kernel_options(*cmd, args->kernel);

  return [args]() {
    const RenderArgs& a = *args;
    io::SceneDesc desc = io::load_scene(a.scene, shared_scenes_dir(a.kernel.scenes));
    const auto& s = desc.settings;
    const int width = a.width ? a.width : s.width;
    const int height = a.height ? a.height : s.height;
    render::RenderOptions ro;
    ro.spp = a.spp ? a.spp : s.spp;
    ro.max_depth = a.max_depth >= 0 ? a.max_depth : s.max_depth;
    const std::string integrator = a.integrator.empty() ? s.integrator : a.integrator;
    ro.integrator = integrator == "path" ? render::IntegratorKind::path : render::IntegratorKind::whitted;
    ro.seed = a.seed >= 0 ? std::uint64_t(a.seed) : s.seed;
    ro.threads = a.threads;
    ro.specialize = !a.no_specialize;

    const render::Scene scene(desc, width, height, kernel_options(a.kernel));
    ProgressBar bar("rendering");
    ro.progress = [&bar](double f) { bar.update(f); };
    const render::RenderResult r = render::render(scene, ro);
    bar.finish();

    const std::filesystem::path out =
        a.output.empty() ? std::filesystem::path("out") / (std::filesystem::path(a.scene).stem().string() + ".png")
                         : std::filesystem::path(a.output);
    io::write_png(out, r.image.width, r.image.height, r.image.pixels);
    if (a.stats) print_stats(scene, desc, r);
    const double rays = double(r.stats.total());
    std::printf("%s: %dx%d, %d spp, %s, %llu rays in %.3f s, %.2f Mrays/s, %d threads -> %s\n",
                a.scene.c_str(), width, height, ro.spp, integrator.c_str(),
                (unsigned long long)r.stats.total(), r.seconds, rays / r.seconds * 1e-6,
                ro.threads ? ro.threads : int(std::thread::hardware_concurrency()), out.string().c_str());
    return 0;
  };
}

}  // namespace volley::cli
