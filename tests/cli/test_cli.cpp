// The volley command end to end: bad input gives a clear message and a non-zero exit;
// a good render prints its summary line and writes a PNG.
#include <doctest/doctest.h>

#include "cli/cli_run.h"

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;

namespace {

using volley::test::Run;
using volley::test::run;

fs::path temp_file(const std::string& name, const std::string& content) {
  const fs::path dir = fs::temp_directory_path() / "volley_cli_test";
  fs::create_directories(dir);
  const fs::path p = dir / name;
  std::ofstream(p) << content;
  return p;
}

const std::string kScenes = std::string(VOLLEY_SOURCE_DIR) + "/scenes";

// A minimal valid scene around the given objects.
std::string scene_json(const std::string& objects) {
  return R"({"camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0], "up": [0, 1, 0], "fov": 40},
  "materials": {"grey": {"diffuse": 0.5}},
  "lights": [{"position": [0, 5, 5], "intensity": 30}],
  "objects": [)" + objects + "]}";
}

}  // namespace

TEST_CASE("cli: --help explains the subcommands") {
  const Run r = run("--help");
  CHECK(r.status == 0);
  CHECK(r.output.find("render") != std::string::npos);
  const Run h = run("render --help");
  CHECK(h.status == 0);
  CHECK(h.output.find("--spp") != std::string::npos);
  CHECK(h.output.find("--integrator") != std::string::npos);
}

TEST_CASE("cli: a missing scene file names the file") {
  const Run r = run("render /nonexistent/scene.json -o /tmp/x.png");
  CHECK(r.status != 0);
  CHECK(r.output.find("/nonexistent/scene.json") != std::string::npos);
}

TEST_CASE("cli: malformed JSON reports line and column") {
  const fs::path p = temp_file("broken.json", "{\n  \"camera\": {\n    \"eye\": [0, 0,, 5]\n  }\n}\n");
  const Run r = run("render " + p.string());
  CHECK(r.status != 0);
  CHECK(r.output.find("broken.json:3:") != std::string::npos);
}

TEST_CASE("cli: unknown keys are an error, not silence") {
  const fs::path p = temp_file("unknown.json", scene_json(R"({"type": "triangles", "vertices": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,2]], "colour": 3})"));
  const Run r = run("render " + p.string());
  CHECK(r.status != 0);
  CHECK(r.output.find("colour") != std::string::npos);
}

TEST_CASE("cli: zero and absurd image sizes are rejected") {
  const std::string scene = kScenes + "/cornell.json";
  CHECK(run("render " + scene + " --width 0").status != 0);
  CHECK(run("render " + scene + " --height 100000").status != 0);
  CHECK(run("render " + scene + " --spp 0").status != 0);
  CHECK(run("render " + scene + " --isa mmx").status != 0);
}

TEST_CASE("cli: OBJ with an out-of-range index or a NaN coordinate names the line") {
  const fs::path bad_index = temp_file("bad_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
  Run r = run("render " + bad_index.string() + " -o /tmp/volley_bad.png");
  CHECK(r.status != 0);
  CHECK(r.output.find("bad_index.obj:4") != std::string::npos);
  const fs::path nan = temp_file("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
  r = run("render " + nan.string() + " -o /tmp/volley_bad.png");
  CHECK(r.status != 0);
  CHECK(r.output.find("nan.obj:2") != std::string::npos);
}

TEST_CASE("cli: an empty scene is an error") {
  const fs::path p = temp_file("empty.json", scene_json(""));
  const Run r = run("render " + p.string());
  CHECK(r.status != 0);
  CHECK(r.output.find("no geometry") != std::string::npos);
}

TEST_CASE("cli: a non-planar polygon is named with its deviation") {
  const fs::path p = temp_file("bent.json", scene_json(R"({"type": "polygon", "name": "bent-quad", "vertices": [[0,0,0],[1,0,0],[1,1,0.3],[0,1,0]], "material": "grey"})"));
  const Run r = run("render " + p.string() + " -o /tmp/volley_bent.png");
  CHECK(r.status != 0);
  CHECK(r.output.find("bent-quad") != std::string::npos);
  CHECK(r.output.find("planar") != std::string::npos);
}

TEST_CASE("cli: a small render writes the PNG and prints the summary line") {
  const fs::path out = fs::temp_directory_path() / "volley_cli_test" / "cornell_small.png";
  fs::remove(out);
  const Run r = run("render " + kScenes + "/cornell.json --width 32 --height 32 --spp 1 --stats -o " + out.string());
  CHECK(r.status == 0);
  CHECK(fs::exists(out));
  CHECK(r.output.find("Mrays/s") != std::string::npos);
  CHECK(r.output.find("rays by kind") != std::string::npos);
}

TEST_CASE("cli: info and render --stats say whether the geometry is closed and back-face culling admissible") {
  const fs::path quad = temp_file("open_quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
  const Run open = run("info " + quad.string());
  CHECK(open.status == 0);
  CHECK(open.output.find("closed no, opaque yes") != std::string::npos);
  CHECK(open.output.find("occlusion   back-face culling not admissible: open geometry (4 edges") != std::string::npos);
  const Run sphere = run("info " + kScenes + "/meshes/sphere.obj");
  CHECK(sphere.output.find("closed yes, opaque yes") != std::string::npos);
  CHECK(sphere.output.find("back-face culling admissible (all geometry closed, all materials opaque), not used: ") !=
        std::string::npos);
  const fs::path out = fs::temp_directory_path() / "volley_cli_test" / "cornell_culling.png";
  const Run glass = run("render " + kScenes + "/cornell.json --width 16 --height 16 --stats -o " + out.string());
  CHECK(glass.output.find("occlusion: back-face culling not admissible: open geometry") != std::string::npos);
  CHECK(glass.output.find("transmissive materials") != std::string::npos);
}

TEST_CASE("cli: info prints sizes and BVH facts for a bare mesh") {
  const fs::path p = temp_file("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
  const Run r = run("info " + p.string());
  CHECK(r.status == 0);
  CHECK(r.output.find("2 triangles") != std::string::npos);
  CHECK(r.output.find("automatic") != std::string::npos);
}
