// The real benchmark meshes of ../shared/scenes (SOURCES.md), when present: counts,
// and the quirks each one exercises. kitchen_partial.obj (1M triangles) is left out to
// keep the suite fast; see the load times in the io notes.
#include <doctest/doctest.h>

#include <cmath>
#include <string>

#include "io/io_test_util.h"
#include "io/scene_loader.h"

using volley::io::load_scene;
using volley::io::SceneDesc;
using volley::io::test::CaptureStderr;
using volley::io::test::shared_mesh;
using volley::io::test::TempDir;

namespace {

/// Loads a shared mesh as a bare scene, or returns false after a MESSAGE when absent.
bool load_shared(const std::string& name, SceneDesc& out) {
  const auto file = shared_mesh(name);
  if (file.empty()) {
    MESSAGE("skipped: " << name << " not found in " << VOLLEY_SHARED_SCENES);
    return false;
  }
  out = load_scene(file, VOLLEY_SHARED_SCENES);
  return true;
}

bool all_unit(const std::vector<glm::vec3>& normals) {
  for (const glm::vec3& n : normals)
    if (!(std::fabs(glm::length(n) - 1.0f) < 1e-5f)) return false;
  return true;
}

}  // namespace

TEST_CASE("shared: CornellBox-Original.obj - quads, negative indices, CRLF, tabs, MTL") {
  SceneDesc s;
  if (!load_shared("CornellBox-Original.obj", s)) return;
  CHECK(s.mesh.triangle_count() == 36);  // 18 quads
  CHECK(s.mesh.positions.size() == 72);
  CHECK(s.mesh.corner_normals.empty());
  // Every usemtl of the file names one of its 8 MTL materials, in order of first use.
  REQUIRE(s.materials.size() == 8);
  CHECK(s.materials[0].name == "floor");
  CHECK(s.materials[7].name == "light");
  CHECK(s.materials[7].emission == glm::vec3(17, 12, 4));
  CHECK(s.mesh.material[35] == 7);
  // First quad "f -4 -3 -2 -1" after 4 vertices: triangles (0 1 2) and (0 2 3).
  CHECK(s.mesh.indices[0] == 0);
  CHECK(s.mesh.indices[5] == 3);
  CHECK(s.mesh.positions[0] == glm::vec3(-1.01f, 0.0f, 0.99f));
  // Quirk: the short box's "Bottom Face" is "f -12 -11 -10 -9", which names the vertices
  // of its right face, so triangles 20 and 21 duplicate triangles 16 and 17.
  for (int k = 0; k < 6; ++k) CHECK(s.mesh.indices[3 * 20 + k] == s.mesh.indices[3 * 16 + k]);
}

TEST_CASE("shared: CornellBox-Original.obj through a JSON scene with the scenes variable") {
  if (shared_mesh("CornellBox-Original.obj").empty()) {
    MESSAGE("skipped: CornellBox-Original.obj not found in " << VOLLEY_SHARED_SCENES);
    return;
  }
  TempDir dir;
  const auto file = dir.write("cornell.json", R"({
    "camera": {"eye": [0, 1, 3.9], "look_at": [0, 1, 0], "fov": 37},
    "lights": [{"position": [0, 1.9, 0], "intensity": 1}],
    "objects": [{"type": "mesh", "file": "${scenes}/CornellBox-Original.obj"}]
  })");
  const SceneDesc s = load_scene(file, VOLLEY_SHARED_SCENES);
  CHECK(s.mesh.triangle_count() == 36);
  CHECK(s.materials.size() == 8);
}

TEST_CASE("shared: dragon_100k.obj - a missing dragon.mtl is a warning") {
  CaptureStderr err;
  SceneDesc s;
  if (!load_shared("dragon_100k.obj", s)) return;
  CHECK(s.mesh.triangle_count() == 100000);
  CHECK(s.mesh.positions.size() == 50000);
  CHECK(s.materials.size() == 1);
  CHECK(err.text().find("material library \"dragon.mtl\" not found") != std::string::npos);
}

TEST_CASE("shared: sponza_dabrovic.obj - v/vt/vn, one zero and many non-unit normals") {
  SceneDesc s;
  if (!load_shared("sponza_dabrovic.obj", s)) return;
  CHECK(s.mesh.triangle_count() == 66454);
  CHECK(s.mesh.positions.size() == 39999);
  REQUIRE(s.mesh.corner_normals.size() == 3 * 66454);
  CHECK(all_unit(s.mesh.corner_normals));  // renormalized; the zero vn took the face normal
}

TEST_CASE("shared: bun_zipper.ply matches stanford-bunny.obj") {
  SceneDesc ply;
  if (!load_shared("bun_zipper.ply", ply)) return;
  CHECK(ply.mesh.triangle_count() == 69451);
  CHECK(ply.mesh.positions.size() == 35947);
  SceneDesc obj;
  if (!load_shared("stanford-bunny.obj", obj)) return;
  CHECK(obj.mesh.indices == ply.mesh.indices);
  REQUIRE(obj.mesh.positions.size() == ply.mesh.positions.size());
  float worst = 0.0f;  // the OBJ was written with 6 decimals
  for (std::size_t i = 0; i < obj.mesh.positions.size(); ++i)
    worst = std::max(worst, glm::length(obj.mesh.positions[i] - ply.mesh.positions[i]));
  CHECK(worst < 1e-6f);
}

TEST_CASE("shared: triangle counts of the other meshes as in SOURCES.md") {
  CaptureStderr err;  // staircase2 and classroom name materials without an MTL
  struct Mesh {
    const char* name;
    std::size_t triangles;
    bool normals;
  };
  for (const Mesh& m : {Mesh{"teapot.obj", 6320, false}, Mesh{"staircase2.obj", 31087, true},
                        Mesh{"classroom.obj", 103832, true}, Mesh{"conference.obj", 331179, false}}) {
    INFO(m.name);
    SceneDesc s;
    if (!load_shared(m.name, s)) continue;
    CHECK(s.mesh.triangle_count() == m.triangles);
    CHECK(s.mesh.corner_normals.size() == (m.normals ? 3 * m.triangles : 0));
    if (m.normals) CHECK(all_unit(s.mesh.corner_normals));
  }
}
