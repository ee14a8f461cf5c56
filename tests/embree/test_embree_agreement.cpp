// volley against Embree 3 on the shared scenes: the same primary rays through both, for
// each triangle test. Hit/miss must agree on >= 99.99% of the rays, and every difference
// (hit/miss or which triangle) must be explained by an edge case: the reported hit lies
// within 1e-4 (barycentric) of a triangle edge, or the two hits are at the same distance
// (coplanar or overlapping triangles, t equal to 1e-5 relative). The median relative
// difference of t on rays that hit the same triangle must be float rounding (< 1e-5).
// Shadow rays are checked the same way for occlusion (blocked/free agreement >= 99.9%:
// a shadow ray grazes the surface it leaves far more often than a camera ray hits an edge).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "embree_scene.h"
#include "io/scene_loader.h"
#include "render/scene.h"
#include "render/workloads.h"

namespace fs = std::filesystem;
using namespace volley;

namespace {

constexpr int kSize = 128;  // image width and height of the primary rays

// The scene file, or empty after a MESSAGE when the shared meshes are absent.
bool load(const fs::path& scene, io::SceneDesc& desc) {
  const fs::path shared(VOLLEY_SHARED_SCENES);
  if (!fs::is_directory(shared)) {
    MESSAGE("skipped: the shared scenes are not in " << shared);
    return false;
  }
  desc = io::load_scene(scene, shared);
  return true;
}

float min_barycentric(const Hit& h) { return std::min({h.u, h.v, 1.0f - h.u - h.v}); }

bool near_edge(const Hit& h) { return h.hit() && min_barycentric(h) < 1e-4f; }

struct Agreement {
  std::size_t rays = 0, same_hit = 0, both = 0, same_prim = 0, unexplained = 0;
  std::vector<double> t_rel;  // on rays that hit the same triangle
  double hit_rate() const { return double(same_hit) / double(rays); }
  double prim_rate() const { return both ? double(same_prim) / double(both) : 1.0; }
  double median_t() {
    if (t_rel.empty()) return 0.0;
    std::nth_element(t_rel.begin(), t_rel.begin() + t_rel.size() / 2, t_rel.end());
    return t_rel[t_rel.size() / 2];
  }
};

Agreement compare_hits(const std::vector<Hit>& volley_hits, const std::vector<Hit>& embree_hits) {
  Agreement a;
  a.rays = volley_hits.size();
  for (std::size_t i = 0; i < a.rays; ++i) {
    const Hit& v = volley_hits[i];
    const Hit& e = embree_hits[i];
    if (v.hit() != e.hit()) {
      // The engine that hit found the ray within a hair of an edge (a silhouette or a
      // shared edge the other engine's test let the ray through).
      if (!(near_edge(v) || near_edge(e))) ++a.unexplained;
      continue;
    }
    ++a.same_hit;
    if (!v.hit()) continue;
    ++a.both;
    const double t_rel = std::abs(double(v.t) - double(e.t)) / std::max(double(e.t), 1e-30);
    if (v.prim == e.prim) {
      ++a.same_prim;
      a.t_rel.push_back(t_rel);
    } else if (!(near_edge(v) || near_edge(e) || t_rel <= 1e-5)) {
      ++a.unexplained;
    }
  }
  return a;
}

void check_scene(const fs::path& scene_file) {
  io::SceneDesc desc;
  if (!load(scene_file, desc)) return;
  REQUIRE(desc.polygons.empty());
  const bench::EmbreeScene embree(&desc.mesh.positions[0].x, desc.mesh.positions.size(), desc.mesh.indices.data(),
                                  desc.mesh.triangle_count());
  for (TriangleTest test : {TriangleTest::watertight, TriangleTest::moller, TriangleTest::plane}) {
    CAPTURE(to_string(test));
    const render::Scene scene(desc, kSize, kSize, Options{test, Isa::automatic});
    const std::vector<Ray> primary = render::primary_rays(scene.camera());
    const std::vector<Hit> volley_hits = render::trace_all(scene.accel(), primary, 1);
    std::vector<Hit> embree_hits(primary.size());
    for (std::size_t i = 0; i < primary.size(); ++i) embree_hits[i] = embree.intersect(primary[i]);

    Agreement a = compare_hits(volley_hits, embree_hits);
    const std::size_t hits = std::count_if(volley_hits.begin(), volley_hits.end(), [](const Hit& h) { return h.hit(); });
    MESSAGE(scene_file.filename().string() << " primary " << kSize << "x" << kSize << ", test "
            << to_string(test) << ": " << hits << " hits; hit/miss agreement " << 100.0 * a.hit_rate()
            << "% (" << a.rays - a.same_hit << " differ), prim agreement " << 100.0 * a.prim_rate() << "% ("
            << a.both - a.same_prim << " differ), unexplained " << a.unexplained << ", median |dt|/t "
            << a.median_t());
    CHECK(hits > primary.size() / 10);  // the camera sees the scene: the comparison means something
    CHECK(a.hit_rate() >= 0.9999);
    CHECK(a.unexplained == 0);
    CHECK(a.median_t() < 1e-5);

    // Shadow rays from volley's primary hits: occlusion answers.
    const std::vector<Ray> shadow = render::shadow_rays(scene, primary, volley_hits);
    std::size_t same = 0, blocked = 0;
    for (const Ray& r : shadow) {
      const bool v = scene.accel().occluded(r);
      blocked += v;
      same += v == embree.occluded(r);
    }
    const double rate = shadow.empty() ? 1.0 : double(same) / double(shadow.size());
    MESSAGE("  shadow: " << shadow.size() << " rays, " << blocked << " blocked; agreement " << 100.0 * rate << "% ("
            << shadow.size() - same << " differ)");
    CHECK(!shadow.empty());
    CHECK(rate >= 0.999);
  }
}

}  // namespace

TEST_CASE("embree: primary and shadow rays agree on the bunny") {
  check_scene(fs::path(VOLLEY_SOURCE_DIR) / "bench" / "embree" / "bunny.json");
}

TEST_CASE("embree: primary and shadow rays agree on Sponza") {
  check_scene(fs::path(VOLLEY_SOURCE_DIR) / "scenes" / "sponza.json");
}
