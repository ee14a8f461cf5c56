// The ray workloads of `volley rays` (render/workloads.h): primary rays in 4x4 blocks,
// shadow rays to the light, cosine-distributed diffuse rays, and the file `volley rays`
// writes. `volley trace` is tested in test_trace.cpp.
#include <doctest/doctest.h>

#include "cli/cli_run.h"

#include <cmath>
#include <cstring>
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "io/ray_file.h"
#include "io/scene_loader.h"
#include "render/scene.h"
#include "render/workloads.h"

namespace fs = std::filesystem;
using namespace volley;
using namespace volley::test;

namespace {

// A 20 x 20 floor at y = 0 seen from above, a light over it: every primary ray hits and
// the shading normal is +y everywhere.
const std::string kFloor = R"({"camera": {"eye": [0, 5, 0], "look_at": [0, 0, 0], "up": [0, 0, -1], "fov": 60},
  "render": {"width": 24, "height": 20},
  "materials": {"grey": {"diffuse": 0.5}},
  "lights": [{"position": [1, 4, 2], "intensity": 30}],
  "objects": [{"type": "triangles", "vertices": [[-10,0,-10],[10,0,-10],[10,0,10],[-10,0,10]],
               "indices": [[0,2,1],[0,3,2]], "material": "grey"}]})";

render::Scene load_scene(const std::string& file, int width, int height) {
  return render::Scene(io::load_scene(file, VOLLEY_SHARED_SCENES), width, height, Options{});
}

}  // namespace

TEST_CASE("workloads: block order covers every pixel once, 4x4 blocks first, clipped at the edges") {
  for (const auto& size : {std::pair{8, 8}, std::pair{6, 5}, std::pair{2, 2}, std::pair{17, 3}}) {
    const int w = size.first, h = size.second;  // not a structured binding: CAPTURE takes them by reference (clang 14)
    CAPTURE(w);
    CAPTURE(h);
    const auto order = render::block_order(w, h);
    REQUIRE(order.size() == std::size_t(w * h));
    std::set<std::pair<int, int>> seen(order.begin(), order.end());
    CHECK(seen.size() == order.size());
    for (auto [x, y] : order) CHECK((x >= 0 && x < w && y >= 0 && y < h));
  }
  // 8x8: the first 16 rays are exactly the top-left 4x4 block, row by row.
  const auto order = render::block_order(8, 8);
  for (int i = 0; i < 16; ++i) CHECK(order[i] == std::pair{i % 4, i / 4});
  CHECK(order[16] == std::pair{4, 0});
  // 6x5: the top-right block is clipped to 2x4, so the next block starts at ray 24.
  const auto clipped = render::block_order(6, 5);
  CHECK(clipped[16] == std::pair{4, 0});
  CHECK(clipped[17] == std::pair{5, 0});
  CHECK(clipped[18] == std::pair{4, 1});
  CHECK(clipped[24] == std::pair{0, 4});
}

TEST_CASE("workloads: primary rays are the camera's rays, in block order") {
  const render::Scene scene = load_scene(kCornell, 12, 8);
  const std::vector<Ray> rays = render::primary_rays(scene.camera());
  const auto order = render::block_order(12, 8);
  REQUIRE(rays.size() == 96);
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const auto r = scene.camera().ray(float(order[i].first), float(order[i].second));
    CHECK(rays[i].org[0] == r.org.x);
    CHECK(rays[i].dir[2] == r.dir.z);
    CHECK(rays[i].tmin == 0.0f);
    CHECK(std::isinf(rays[i].tmax));
  }
}

TEST_CASE("workloads: shadow rays start at the primary hits and end at the light") {
  const render::Scene scene = load_scene(kCornell, 16, 16);
  const std::vector<Ray> primary = render::primary_rays(scene.camera());
  const std::vector<Hit> hits = render::trace_all(scene.accel(), primary, 1);
  const std::vector<Ray> shadow = render::shadow_rays(scene, primary, hits);
  std::size_t hit_count = 0;
  for (const Hit& h : hits) hit_count += h.hit();
  CHECK(!shadow.empty());
  CHECK(shadow.size() <= hit_count);
  const glm::vec3 light = scene.lights().front().position;
  for (const Ray& r : shadow) {
    CHECK(r.tmin == 0.0f);
    CHECK(r.tmax == 1.0f);
    for (int k = 0; k < 3; ++k) CHECK(r.org[k] + r.dir[k] == doctest::Approx(light[k]).epsilon(1e-5));
  }
  // Origins are the primary hit points (moved off the surface by a rounding-error bound).
  std::size_t next = 0;
  for (std::size_t i = 0; i < primary.size() && next < shadow.size(); ++i) {
    if (!hits[i].hit()) continue;
    const render::SurfacePoint s = scene.surface(primary[i], hits[i]);
    if (!(glm::dot(light - s.p, s.ng) > 0.0f)) continue;
    const glm::vec3 o(shadow[next].org[0], shadow[next].org[1], shadow[next].org[2]);
    CHECK(glm::length(o - s.p) < 1e-3f * scene.extent());
    ++next;
  }
  CHECK(next == shadow.size());
}

TEST_CASE("workloads: diffuse rays are cosine-distributed about the normal and depend on the seed only") {
  const fs::path floor = temp_file("floor.json", kFloor);
  const render::Scene scene = load_scene(floor.string(), 64, 64);
  const std::vector<Ray> a = render::make_workload(scene, render::Workload::diffuse, 7, 1);
  const std::vector<Ray> b = render::make_workload(scene, render::Workload::diffuse, 7, 2);
  const std::vector<Ray> c = render::make_workload(scene, render::Workload::diffuse, 8, 1);
  REQUIRE(a.size() == 64 * 64);  // every pixel sees the floor, a flat floor drops no ray
  REQUIRE(b.size() == a.size());
  CHECK(std::memcmp(a.data(), b.data(), a.size() * sizeof(Ray)) == 0);  // thread count does not matter
  CHECK(std::memcmp(a.data(), c.data(), a.size() * sizeof(Ray)) != 0);  // the seed does
  // Cosine-weighted about +y: E[cos] = 2/3, E[cos^2] = 1/2; azimuth uniform (E[x] = E[z] = 0).
  double cos1 = 0, cos2 = 0, mx = 0, mz = 0;
  for (const Ray& r : a) {
    CHECK(r.dir[1] > 0.0f);
    CHECK(std::sqrt(r.dir[0] * r.dir[0] + r.dir[1] * r.dir[1] + r.dir[2] * r.dir[2]) == doctest::Approx(1.0).epsilon(1e-5));
    CHECK(r.org[1] >= 0.0f);  // offset to the side the ray leaves
    cos1 += r.dir[1];
    cos2 += double(r.dir[1]) * r.dir[1];
    mx += r.dir[0];
    mz += r.dir[2];
  }
  const double n = double(a.size());
  CHECK(cos1 / n == doctest::Approx(2.0 / 3.0).epsilon(0.02));
  CHECK(cos2 / n == doctest::Approx(0.5).epsilon(0.03));
  CHECK(std::abs(mx / n) < 0.03);
  CHECK(std::abs(mz / n) < 0.03);
}

TEST_CASE("rays: writes the workload file, the same bytes for the same seed") {
  const fs::path out = temp_path("cornell_primary.vray");
  const Run r = run("rays " + kCornell + " --workload primary --width 16 --height 12 -o " + out.string());
  REQUIRE(r.status == 0);
  CHECK(has(r.output, "192 rays"));
  const std::vector<Ray> rays = io::read_rays(out);
  const std::vector<Ray> expected = render::primary_rays(load_scene(kCornell, 16, 12).camera());
  REQUIRE(rays.size() == expected.size());
  CHECK(std::memcmp(rays.data(), expected.data(), rays.size() * sizeof(Ray)) == 0);

  const fs::path d1 = temp_path("d1.vray"), d2 = temp_path("d2.vray"), d3 = temp_path("d3.vray");
  const std::string base = "rays " + kCornell + " --workload diffuse --width 16 --height 16 ";
  REQUIRE(run(base + "--seed 3 -o " + d1.string()).status == 0);
  REQUIRE(run(base + "--seed 3 --threads 1 -o " + d2.string()).status == 0);
  REQUIRE(run(base + "--seed 4 -o " + d3.string()).status == 0);
  CHECK(bytes_of(d1) == bytes_of(d2));
  CHECK(bytes_of(d1) != bytes_of(d3));
}
