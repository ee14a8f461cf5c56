// Every scene shipped in scenes/ loads, builds and renders a tiny image with no NaN
// (scenes that use the shared meshes are skipped when those are absent).
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>

#include "io/load_error.h"
#include "io/scene_loader.h"
#include "render/renderer.h"

namespace fs = std::filesystem;
using namespace volley;

TEST_CASE("scenes: every shipped scene loads and renders") {
  int rendered = 0;
  for (const auto& entry : fs::directory_iterator(fs::path(VOLLEY_SOURCE_DIR) / "scenes")) {
    if (entry.path().extension() != ".json") continue;
    CAPTURE(entry.path().string());
    io::SceneDesc desc;
    try {
      desc = io::load_scene(entry.path(), VOLLEY_SHARED_SCENES);
    } catch (const io::LoadError& e) {
      // Only a missing shared mesh may stop a shipped scene.
      const std::string what = e.what();
      CHECK(what.find("VOLLEY_SCENES") != std::string::npos);
      MESSAGE("skipped (shared mesh missing): " << entry.path().filename().string());
      continue;
    }
    const render::Scene scene(desc, 24, 16, Options{});
    render::RenderOptions ro;
    ro.max_depth = desc.settings.max_depth;
    const auto r = render::render(scene, ro);
    bool finite = true;
    double sum = 0.0;
    for (const auto& p : r.image.pixels) {
      finite &= std::isfinite(p.r) && std::isfinite(p.g) && std::isfinite(p.b);
      sum += p.r + p.g + p.b;
    }
    CHECK(finite);
    CHECK(sum > 0.0);  // something is lit
    ++rendered;
  }
  CHECK(rendered >= 3);  // cornell, cornell-original, polygons need no shared mesh
}
