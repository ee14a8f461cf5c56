// volley info: what a scene holds, how its BVH came out, what the renderer would skip.
#include <cstdio>
#include <memory>
#include <string>

#include "cli/commands.h"
#include "cli/common.h"
#include "io/scene_loader.h"
#include "render/pipeline.h"
#include "render/scene.h"

namespace volley::cli {

Runner register_info(CLI::App& app) {
  struct InfoArgs {
    std::string scene;
    KernelArgs kernel;
  };
  auto args = std::make_shared<InfoArgs>();
  CLI::App* cmd = app.add_subcommand("info", "Print scene sizes, BVH quality and features");
  cmd->add_option("scene", args->scene, "Scene file (.json) or mesh (.obj, .ply)")->required();
  add_kernel_options(*cmd, args->kernel);

  return [args]() {
    const io::SceneDesc desc = io::load_scene(args->scene, shared_scenes_dir(args->kernel.scenes));
    const render::Scene scene(desc, desc.settings.width, desc.settings.height, kernel_options(args->kernel));
    const AccelInfo info = scene.accel().info();
    const render::SceneFeatures f = render::with_closure(scene, desc);
    std::printf("scene       %s\n", args->scene.c_str());
    std::printf("geometry    %zu triangles (%zu degenerate), %zu polygons, %zu vertices\n", info.triangles,
                info.degenerate, info.polygons, desc.mesh.positions.size());
    std::printf("geometries  %zu (%zu objects of triangles, %zu polygons; each hit names its geometry)\n",
                info.geometries, info.geometries - info.polygons - info.instances, info.polygons);
    if (info.instances > 0)
      std::printf("instances   %zu (%zu triangles through them; sharing their prototypes' structures)\n",
                  info.instances, info.instanced_triangles);
    if (info.layers > 1)
      std::printf("masks       %zu distinct object masks: one BVH each (a ray walks those its mask shares a bit with)\n",
                  info.layers);
    std::printf("materials   %zu; lights %zu%s\n", scene.materials().size(), scene.lights().size(),
                desc.lights.empty() ? " (automatic)" : "");
    std::printf("camera      %s, %dx%d\n", desc.has_camera ? "from scene" : "automatic (frames the bounds)",
                desc.settings.width, desc.settings.height);
    std::printf("kernel      test %s, isa %s, %s box tests, %s triangle tests\n",
                std::string(to_string(info.test)).c_str(), std::string(to_string(info.isa)).c_str(),
                info.robust ? "robust (padded)" : "fast (unpadded)", info.reference_double ? "double" : "float");
    const bool high = info.quality == BuildQuality::high;
    std::printf("bvh         %d-wide, %s quality: %zu nodes (%.2f children each), %zu leaves, depth %zu, %.2f "
                "primitives/leaf, SAH cost %.2f (binary %s tree: %.2f)\n",
                info.width, std::string(to_string(info.quality)).c_str(), info.nodes, info.mean_children, info.leaves,
                info.depth, info.mean_leaf_size, info.sah_cost, high ? "spatial-split SAH" : "binned-SAH",
                info.binary_sah_cost);
    if (high)
      std::printf("references  %zu triangle references in the leaves for %zu triangles (spatial splits)\n",
                  info.references, info.triangles - info.degenerate);
    if (info.blocks)
      std::printf("blocks      %zu of %d triangles, %.0f%% of lanes used\n", info.blocks, info.block_width,
                  100.0 * info.block_fill);
    std::printf("memory      %zu bytes, %.1f bytes/primitive\n", info.bytes,
                double(info.bytes) / double(std::max<std::size_t>(1, info.triangles + info.polygons)));
    std::printf("build       %.3f s (%.2f M primitives/s)\n", info.build_seconds,
                double(info.triangles + info.polygons) / std::max(info.build_seconds, 1e-9) * 1e-6);
    std::printf(
        "features    lights %s, mirrors %s, refraction %s, emission %s, polygons %s, smooth normals %s, "
        "closed %s, opaque %s\n",
        f.lights ? "yes" : "no", f.mirrors ? "yes" : "no", f.refraction ? "yes" : "no", f.emission ? "yes" : "no",
        f.polygons ? "yes" : "no", f.smooth_normals ? "yes" : "no", f.closed ? "yes" : "no",
        f.refraction ? "no" : "yes");
    std::printf("skipped     %s\n",
                render::describe_skipped(render::needed_stages(f), f).c_str());
    std::printf("occlusion   %s\n", render::describe_culling(f).c_str());
    return 0;
  };
}

}  // namespace volley::cli
