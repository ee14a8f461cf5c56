// The batch shader (render/shade_batch.h) against the one-at-a-time shaders it replaces in
// specialised pipelines: the same image bit for bit, on scenes that exercise every lane
// kind (triangle hits, misses, polygon hits handled one at a time, lights behind surfaces,
// specular highlights, several lights, both integrators) and partial groups of lanes.
#include <doctest/doctest.h>

#include <filesystem>

#include "io/scene_loader.h"
#include "render/pipeline.h"
#include "render/renderer.h"
#include "simd/isa/dispatch.h"

using namespace volley;

namespace {

// Specular spheres over a polygon floor (a mix of triangle and polygon hits), two lights,
// one of them under the floor (lit from behind: no shadow ray), misses at the top.
io::SceneDesc spheres_on_a_floor() {
  const auto file = std::filesystem::path(VOLLEY_SOURCE_DIR) / "scenes" / "meshes" / "sphere.obj";
  io::SceneDesc desc = io::load_scene(file, VOLLEY_SHARED_SCENES);
  desc.mesh.corner_normals.clear();  // flat shading: no normal interpolation stage
  desc.materials.resize(2);
  desc.materials[0].diffuse = {0.6f, 0.3f, 0.2f};
  desc.materials[0].specular = glm::vec3(0.4f);
  desc.materials[0].shininess = 20.0f;
  desc.materials[1].diffuse = glm::vec3(0.5f);
  desc.materials[1].emission = glm::vec3(0.05f);
  desc.polygons.push_back({"floor", {{-3, -1.2f, -3}, {3, -1.2f, -3}, {3, -1.2f, 3}, {-3, -1.2f, 3}}, 1});
  desc.lights = {{{2.0f, 3.0f, -2.0f}, glm::vec3(8.0f)}, {{0.0f, -2.0f, 0.0f}, glm::vec3(3.0f)}};
  desc.has_camera = true;
  desc.camera.eye = {0.0f, 0.5f, -5.0f};
  desc.camera.target = {0.0f, 0.0f, 0.0f};
  desc.camera.up = {0.0f, 1.0f, 0.0f};
  desc.camera.fov_deg = 50.0f;
  return desc;
}

void check_one_isa(const io::SceneDesc& desc, render::IntegratorKind kind, int width, int height,
                   const Options& options) {
  const render::Scene scene(desc, width, height, options);
  render::RenderOptions ro;
  ro.spp = 3;
  ro.integrator = kind;
  ro.max_depth = 4;
  const auto special = render::render(scene, ro);
  ro.specialize = false;
  const auto general = render::render(scene, ro);
  CHECK(special.batch_shaded);
  CHECK_FALSE(general.batch_shaded);
  CHECK(special.stats.total() == general.stats.total());
  CHECK(special.image.pixels == general.image.pixels);
}

// The lanes run at the traversal kernels' ISA: every one this CPU has (the scalar oracle
// shades in SSE4.2 lanes).
std::vector<Isa> lane_isas() {
  std::vector<Isa> out;
  for (Isa isa : {Isa::scalar, Isa::sse42, Isa::avx2, Isa::avx512})
    if (simd::cpu_has(isa)) out.push_back(isa);
  return out;
}

void check_batch_matches_general(const io::SceneDesc& desc, render::IntegratorKind kind, int width, int height) {
  for (Isa isa : lane_isas()) {
    const std::string isa_name(to_string(isa));
    CAPTURE(isa_name);
    Options options;
    options.isa = isa;
    check_one_isa(desc, kind, width, height, options);
  }
}

}  // namespace

TEST_CASE("shade_batch: bit-identical to one-at-a-time shading (Whitted and path)") {
  const io::SceneDesc desc = spheres_on_a_floor();
  // 37 x 23: tiles and 4x4 blocks cut short at the image edges, so streams have lengths
  // that are not multiples of the lane count.
  for (auto kind : {render::IntegratorKind::whitted, render::IntegratorKind::path}) {
    CAPTURE(int(kind));
    check_batch_matches_general(desc, kind, 37, 23);
  }
}

TEST_CASE("shade_batch: without lights (Whitted then reads only the material: no lanes), both integrators") {
  io::SceneDesc desc = spheres_on_a_floor();
  desc.lights.clear();
  for (auto kind : {render::IntegratorKind::whitted, render::IntegratorKind::path}) {
    CAPTURE(int(kind));
    check_batch_matches_general(desc, kind, 37, 23);
  }
}

TEST_CASE("shade_batch: the Cornell box without mirrors or glass, both integrators") {
  const auto file = std::filesystem::path(VOLLEY_SOURCE_DIR) / "scenes" / "cornell-original.json";
  const io::SceneDesc desc = io::load_scene(file, VOLLEY_SHARED_SCENES);
  for (auto kind : {render::IntegratorKind::whitted, render::IntegratorKind::path}) {
    CAPTURE(int(kind));
    check_batch_matches_general(desc, kind, 32, 32);
  }
}

TEST_CASE("shade_batch: only stage sets without per-hit branches are batched, and --stats says so") {
  CHECK(render::batch_shadable(render::kShadows));
  CHECK(render::batch_shadable(0));
  CHECK_FALSE(render::batch_shadable(render::kShadows | render::kMirrors));
  CHECK_FALSE(render::batch_shadable(render::kRefraction));
  CHECK_FALSE(render::batch_shadable(render::kSmoothNormals));
  CHECK_FALSE(render::batch_shadable(render::kAllStages));
  const render::SceneFeatures flat{true, false, false, false, false, false};
  CHECK(render::describe_skipped(render::kShadows, flat).find("SIMD lanes") != std::string::npos);
  CHECK(render::describe_skipped(render::kAllStages, flat).find("SIMD lanes") == std::string::npos);
}
