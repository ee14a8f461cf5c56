// The renderer: deterministic for a seed whatever the thread count, close to a stored
// reference image, and spawned rays never re-hit the surface they leave.
#include <doctest/doctest.h>

#include <bit>
#include <cmath>
#include <string>
#include <limits>
#include <filesystem>
#include <random>

#include "accuracy/spawn_check.h"
#include "io/png_writer.h"
#include "io/scene_loader.h"
#include "render/renderer.h"
#include "render/pipeline.h"
#include "render/spawn.h"
#include "simd/isa/dispatch.h"

namespace fs = std::filesystem;
using namespace volley;

namespace {

const fs::path kScenes = fs::path(VOLLEY_SOURCE_DIR) / "scenes";

render::RenderResult render_scene(const fs::path& file, int size, int spp, render::IntegratorKind kind, int threads,
                                  Options options = {}) {
  const io::SceneDesc desc = io::load_scene(file, VOLLEY_SHARED_SCENES);
  const render::Scene scene(desc, size, size, options);
  render::RenderOptions ro;
  ro.spp = spp;
  ro.max_depth = desc.settings.max_depth;
  ro.integrator = kind;
  ro.threads = threads;
  ro.seed = 3;
  return render::render(scene, ro);
}

// RMSE in 8-bit sRGB units between two images of the same size.
double rmse_srgb8(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  auto encode = [](float x) {
    x = std::clamp(x, 0.0f, 1.0f);
    return 255.0 * (x <= 0.0031308f ? 12.92 * x : 1.055 * std::pow(double(x), 1.0 / 2.4) - 0.055);
  };
  double sum = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double d = encode(a[i][c]) - encode(b[i][c]);
      sum += d * d;
    }
  return std::sqrt(sum / double(3 * a.size()));
}

}  // namespace

TEST_CASE("render: the same seed gives the same image on 1 and 2 threads") {
  for (auto kind : {render::IntegratorKind::whitted, render::IntegratorKind::path}) {
    const auto one = render_scene(kScenes / "cornell.json", 24, 2, kind, 1);
    const auto two = render_scene(kScenes / "cornell.json", 24, 2, kind, 2);
    CHECK(one.image.pixels == two.image.pixels);
    CHECK(one.stats.rays == two.stats.rays);
  }
}

TEST_CASE("render: cornell.json matches the stored reference within 1.5 sRGB levels RMSE") {
  // Reference: tests/render/reference/cornell_64.png, made by this renderer (Whitted,
  // 64x64, 1 spp, watertight, scalar) and checked by eye. Other tests and ISAs change
  // only edge pixels, hence a small RMSE tolerance rather than equality.
  const fs::path ref = fs::path(VOLLEY_SOURCE_DIR) / "tests/render/reference/cornell_64.png";
  int w = 0, h = 0;
  const std::vector<glm::vec3> expected = io::read_png_linear(ref, w, h);
  REQUIRE(w == 64);
  REQUIRE(h == 64);
  for (auto test : {TriangleTest::plane, TriangleTest::moller, TriangleTest::watertight}) {
    CAPTURE(to_string(test));
    const auto got = render_scene(kScenes / "cornell.json", 64, 1, render::IntegratorKind::whitted, 0, {test, Isa::automatic});
    // Quantise like the stored PNG before comparing.
    const fs::path tmp = fs::temp_directory_path() / "volley_render_test.png";
    io::write_png(tmp, 64, 64, got.image.pixels);
    int w2 = 0, h2 = 0;
    const auto quantised = io::read_png_linear(tmp, w2, h2);
    const double err = rmse_srgb8(quantised, expected);
    MESSAGE("RMSE vs reference (8-bit sRGB levels): " << err);
    CHECK(err < 1.5);
  }
}

TEST_CASE("render: the path integrator shows colour bleeding in the Cornell box") {
  // The white floor next to the red wall picks up red light only through interreflection.
  const auto whitted = render_scene(kScenes / "cornell-original.json", 32, 4, render::IntegratorKind::whitted, 0);
  const auto path = render_scene(kScenes / "cornell-original.json", 32, 16, render::IntegratorKind::path, 0);
  CHECK(path.stats.rays[int(render::RayKind::diffuse)] > 0);
  CHECK(whitted.stats.rays[int(render::RayKind::diffuse)] == 0);
  // Ceiling row near the red (left, x = 556 in scene units, right side of the image from
  // the front... the red wall is at large x, which the camera sees on the left).
  double red_minus_green = 0.0;
  for (int y = 2; y < 8; ++y)
    for (int x = 4; x < 10; ++x) {
      const glm::vec3 c = path.image.pixels[y * 32 + x];
      red_minus_green += c.r - c.g;
    }
  CHECK(red_minus_green > 0.0);
}

TEST_CASE("render: spawned rays do not re-hit their own surface at scales 1e-3 .. 1e6") {
  // 20,000 spawns per scale and ISA here; `volley accuracy --long` runs 1e6 (perf/accuracy/long.md).
  std::vector<Isa> isas = {Isa::scalar};
  for (Isa isa : {Isa::sse42, Isa::avx2, Isa::avx512})
    if (simd::cpu_has(isa)) isas.push_back(isa);
  for (Isa isa : isas)
    for (float scale : accuracy::kSpawnScales) {
      const accuracy::SpawnRow row = accuracy::spawn_check(scale, 20000, isa);
      CAPTURE(scale);
      CAPTURE(std::string(to_string(isa)));
      CHECK(row.spawned == 20000);
      CHECK(row.rehits == 0);
    }
}

TEST_CASE("render: specialised and general pipelines give the same image") {
  // The general pipeline runs every stage (closest-hit shadow rays that pass through
  // glass, mirror and refraction checks, normal interpolation); a scene without those
  // features must come out bit-identical from the pipeline specialised to it.
  for (const char* name : {"cornell-original.json", "polygons.json", "cornell.json"}) {
    CAPTURE(name);
    const io::SceneDesc desc = io::load_scene(kScenes / name, VOLLEY_SHARED_SCENES);
    const render::Scene scene(desc, 40, 30, Options{});
    render::RenderOptions ro;
    ro.spp = 2;
    ro.max_depth = desc.settings.max_depth;
    ro.integrator = desc.settings.integrator == "path" ? render::IntegratorKind::path : render::IntegratorKind::whitted;
    const auto special = render::render(scene, ro);
    ro.specialize = false;
    const auto general = render::render(scene, ro);
    CHECK(special.image.pixels == general.image.pixels);
    CHECK(general.stages == render::kAllStages);
    CHECK(special.stages == render::needed_stages(scene.features()));
  }
  // What the Cornell box without glass or mirrors leaves out, and says so.
  const io::SceneDesc desc = io::load_scene(kScenes / "cornell-original.json", VOLLEY_SHARED_SCENES);
  const render::Scene scene(desc, 8, 8, Options{});
  const unsigned stages = render::needed_stages(scene.features());
  CHECK(stages == render::kShadows);
  const std::string why = render::describe_skipped(stages, scene.features());
  CHECK(why.find("reflection rays (no mirror materials)") != std::string::npos);
  CHECK(why.find("any-hit") != std::string::npos);
}

TEST_CASE("render: a shadow ray leaving a long axis-aligned wall does not re-hit it") {
  // Regression: a point on the plane x = 0 of a 560-unit wall, light far up and inside:
  // the origin offset must cover the triangle test's rounding relative to the far
  // vertices, or the wall is found again at t = -0.
  io::SceneDesc desc;
  desc.has_camera = true;
  desc.camera.eye = {278, 273, -800};
  desc.camera.target = {278, 273, 0};
  desc.mesh.positions = {{0, 0, 559.2f}, {0, 0, 0}, {0, 548.8f, 0}, {0, 548.8f, 559.2f}};
  desc.mesh.indices = {0, 1, 2, 0, 2, 3};
  desc.mesh.material = {0, 0};
  desc.materials.push_back(io::Material{});
  desc.lights.push_back({{278, 400, 279.5f}, glm::vec3(1.0f)});
  const render::Scene scene(desc, 16, 16, Options{});
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> y(1.0f, 547.0f), z(1.0f, 558.0f);
  int rehits = 0;
  for (int i = 0; i < 20000; ++i) {
    const glm::vec3 target(0.0f, y(rng), z(rng));
    const glm::vec3 org(100.0f, 273.0f, -100.0f);
    const glm::vec3 d = target - org;
    const Ray ray{{org.x, org.y, org.z}, 0.0f, {d.x, d.y, d.z}, INFINITY};
    const Hit hit = scene.accel().intersect(ray);
    REQUIRE(hit.hit());
    const render::SurfacePoint s = scene.surface(ray, hit);
    rehits += scene.accel().occluded(render::spawn_shadow_ray(s.p, s.p_error, s.ng, scene.lights()[0].position));
  }
  CHECK(rehits == 0);
}

TEST_CASE("render: next_float is std::nextafter toward +-inf") {
  const float kInf = std::numeric_limits<float>::infinity();
  std::vector<float> xs = {0.0f, -0.0f, 1.0f, -1.0f, std::numeric_limits<float>::denorm_min(),
                           -std::numeric_limits<float>::denorm_min(), std::numeric_limits<float>::min(),
                           std::numeric_limits<float>::max(), -std::numeric_limits<float>::max(), kInf, -kInf};
  std::mt19937 rng(11);
  for (int i = 0; i < 20000; ++i) xs.push_back(std::bit_cast<float>(std::uint32_t(rng())));
  for (float x : xs) {
    if (std::isnan(x)) continue;
    CAPTURE(x);
    CHECK(std::bit_cast<std::uint32_t>(render::next_float<true>(x)) ==
          std::bit_cast<std::uint32_t>(std::nextafter(x, kInf)));
    CHECK(std::bit_cast<std::uint32_t>(render::next_float<false>(x)) ==
          std::bit_cast<std::uint32_t>(std::nextafter(x, -kInf)));
  }
}

TEST_CASE("render: each scene object is a geometry, and a hit on one shades with its own material") {
  // Three objects of one triangle each at z = 1, 2, 3, one material each, then a polygon
  // at z = 0.5: geometries 0, 1, 2 (objects) and 3 (the polygon).
  io::SceneDesc desc;
  for (int k = 0; k < 3; ++k) {
    const float z = float(k + 1);
    desc.mesh.positions.insert(desc.mesh.positions.end(), {{-1, -1, z}, {1, -1, z}, {0, 1, z}});
    const auto b = static_cast<std::uint32_t>(3 * k);
    desc.mesh.indices.insert(desc.mesh.indices.end(), {b, b + 1, b + 2});
    desc.mesh.material.push_back(static_cast<std::uint32_t>(k));
    // (Appended, not "literal" + std::to_string: GCC 12 warns falsely on that form, -Wrestrict.)
    std::string object = "object ", material = "m";
    object += std::to_string(k);
    material += std::to_string(k);
    desc.mesh.objects.push_back({object, static_cast<std::size_t>(k), 1});
    desc.materials.push_back(io::Material{material});
  }
  desc.materials.push_back(io::Material{"polygon"});
  desc.polygons.push_back({"square", {{5, 5, 0.5f}, {6, 5, 0.5f}, {6, 6, 0.5f}, {5, 6, 0.5f}}, 3});
  const render::Scene scene(desc, 8, 8, Options{});
  CHECK(scene.accel().info().geometries == 4);
  for (int k = 0; k < 3; ++k) {
    CAPTURE(k);
    const Ray ray{{0, 0, 0}, 0.5f + float(k), {0, 0, 1}, INFINITY};
    const Hit hit = scene.accel().intersect(ray);
    REQUIRE(hit.hit());
    CHECK(hit.geom == static_cast<std::uint32_t>(k));
    CHECK(hit.prim == 0);
    CHECK(scene.prim_index(hit) == static_cast<std::uint32_t>(k));
    CHECK(scene.surface(ray, hit).material == static_cast<std::uint32_t>(k));
  }
  const Ray down{{5.5f, 5.5f, 2}, 0.0f, {0, 0, -1}, INFINITY};
  const Hit hit = scene.accel().intersect(down);
  REQUIRE(hit.hit());
  CHECK(hit.geom == 3);
  CHECK(scene.surface(down, hit).material == 3);
}
