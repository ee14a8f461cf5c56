// JSON scenes and bare meshes through load_scene, and every validation message.
#include <doctest/doctest.h>

#include <cmath>
#include <string>

#include "io/io_test_util.h"
#include "io/load_error.h"
#include "io/scene_loader.h"
#include "io/text_file.h"

using namespace volley::io;
using namespace volley::io::test;

namespace {

bool near(const glm::vec3& a, const glm::vec3& b, float eps = 1e-5f) { return glm::length(a - b) <= eps; }

std::string error_of(const std::filesystem::path& scene, const std::filesystem::path& shared = {}) {
  try {
    load_scene(scene, shared);
  } catch (const LoadError& e) {
    return e.what();
  }
  return "(no LoadError)";
}

const char* kTriangle = R"({"type": "triangles", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]})";

// The complete example of README.md ("A complete example"), read from there so that it
// stays valid, with its mesh paths pointing at test files.
std::string readme_example() {
  const std::string readme = volley::io::read_text_file(std::string(VOLLEY_SOURCE_DIR) + "/README.md");
  const std::size_t section = readme.find("### A complete example");
  REQUIRE(section != std::string::npos);
  const std::size_t begin = readme.find("```json\n", section) + 8, end = readme.find("```", begin);
  REQUIRE(end != std::string::npos);
  return readme.substr(begin, end - begin);
}

std::string with_test_meshes(std::string json) {
  const auto swap = [&json](const std::string& from, const std::string& to) {
    const std::size_t at = json.find(from);
    REQUIRE(at != std::string::npos);
    json.replace(at, from.size(), to);
  };
  swap("\"meshes/sphere.obj\"", "\"meshes/tri.obj\"");
  swap("\"${scenes}/CornellBox-Original.obj\"", "\"${scenes}/shared.obj\"");
  return json;
}

}  // namespace

TEST_CASE("scene: the complete example loads with every field") {
  TempDir dir;
  TempDir shared;
  dir.write("meshes/tri.obj", "v 1 0 0\nv 0 0 0\nv 0 1 0\nf 1 2 3\n");
  shared.write("shared.obj", "mtllib shared.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl gold\nf 1 2 3\n");
  shared.write("shared.mtl", "newmtl gold\nKd 0.8 0.6 0.2\n");
  const auto file = dir.write("example.json", with_test_meshes(readme_example()));
  const SceneDesc s = load_scene(file, shared.path());

  CHECK(s.source == file.string());
  CHECK(s.has_camera);
  CHECK_FALSE(is_bare_mesh(s));
  CHECK(s.camera.kind == CameraDesc::Kind::look_at);
  CHECK(s.camera.eye == glm::vec3(0, 1, 3.5f));
  CHECK(s.camera.target == glm::vec3(0, 1, 0));
  CHECK(s.camera.fov_deg == 40.0f);

  CHECK(s.settings.width == 320);
  CHECK(s.settings.height == 240);
  CHECK(s.settings.spp == 4);
  CHECK(s.settings.max_depth == 6);
  CHECK(s.settings.integrator == "path");
  CHECK(s.settings.background == glm::vec3(0.05f, 0.05f, 0.1f));
  CHECK(s.settings.seed == 7);

  // Materials in file order, then the OBJ's "gold", then the default (for the unnamed polygon).
  REQUIRE(s.materials.size() == 7);
  CHECK(s.materials[0].name == "white");
  CHECK(s.materials[0].diffuse == glm::vec3(0.75f));
  CHECK(s.materials[0].ambient == glm::vec3(0.1f));  // default kept
  CHECK(s.materials[0].shininess == 64.0f);
  CHECK(s.materials[1].ambient == glm::vec3(0.1f, 0, 0));
  CHECK(s.materials[2].mirror == glm::vec3(0.9f));
  CHECK(s.materials[3].transmittance == glm::vec3(0.95f));
  CHECK(s.materials[3].ior == 1.5f);
  CHECK(s.materials[4].emission == glm::vec3(8, 7, 6));
  CHECK(s.materials[5].name == "gold");
  CHECK(s.materials[6].name == "(default)");

  REQUIRE(s.lights.size() == 2);
  CHECK(s.lights[0].intensity == glm::vec3(4.0f));
  CHECK(s.lights[1].position == glm::vec3(2, 3, 3));
  CHECK(s.lights[1].intensity == glm::vec3(1.0f));

  // Triangles: mesh (1), shared mesh (1), floor (2), in object order.
  REQUIRE(s.mesh.triangle_count() == 4);
  CHECK(s.mesh.material == std::vector<std::uint32_t>{3, 5, 1, 1});
  // Scale 0.3, then 90 degrees about +y (x → -z), then translate by (0.4, 0.3, 0.3):
  // (1,0,0) → (0.4, 0.3, 0), (0,1,0) → (0.4, 0.6, 0.3).
  CHECK(near(s.mesh.positions[0], glm::vec3(0.4f, 0.3f, 0)));
  CHECK(near(s.mesh.positions[2], glm::vec3(0.4f, 0.6f, 0.3f)));
  CHECK(s.mesh.indices == std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5, 6, 8, 7, 6, 9, 8});
  CHECK(s.mesh.corner_normals.empty());

  REQUIRE(s.polygons.size() == 2);
  CHECK(s.polygons[0].name == "L-shape");
  CHECK(s.polygons[0].vertices.size() == 6);
  CHECK(s.polygons[0].material == 2);
  CHECK(s.polygons[1].name == "objects[4]");
  CHECK(s.polygons[1].material == 6);
}

TEST_CASE("scene: scenes/example.json is the README's complete example") {
  CHECK(volley::io::read_text_file(std::string(VOLLEY_SOURCE_DIR) + "/scenes/example.json") == readme_example());
}

TEST_CASE("scene: the notes' camera, grey colours, defaults, a polygon-only scene") {
  TempDir dir;
  const auto file = dir.write("notes.json", R"({
    "camera": {"eye": [0, 0, 5], "u": [1, 0, 0], "v": [0, 1, 0], "w": [0, 0, -1], "f": 2,
               "window": {"left": -0.5, "right": 0.5, "top": 0.25, "bottom": -0.25}},
    "materials": {"grey": {"diffuse": 0.5, "emission": 3}},
    "objects": [{"type": "polygon", "vertices": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], "material": "grey"}]
  })");
  const SceneDesc s = load_scene(file, {});
  CHECK(s.camera.kind == CameraDesc::Kind::notes);
  CHECK(s.camera.w == glm::vec3(0, 0, -1));
  CHECK(s.camera.f == 2.0f);
  CHECK(s.camera.wl == -0.5f);
  CHECK(s.camera.wr == 0.5f);
  CHECK(s.camera.wt == 0.25f);
  CHECK(s.camera.wb == -0.25f);
  CHECK(s.settings.width == 512);
  CHECK(s.settings.integrator == "whitted");
  CHECK(s.materials.size() == 1);
  CHECK(s.materials[0].emission == glm::vec3(3.0f));
  CHECK(s.mesh.triangle_count() == 0);
  CHECK(s.polygons.size() == 1);
  CHECK(s.lights.empty());
}

TEST_CASE("scene: a mesh without a material keeps its MTL materials, a scene material named default in parentheses replaces the default") {
  TempDir dir;
  dir.write("a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const auto file = dir.write("s.json", R"json({
    "materials": {"(default)": {"diffuse": [0.2, 0.3, 0.4]}},
    "objects": [{"type": "mesh", "file": "a.obj"}, )json" + std::string(kTriangle) + "]}");
  const SceneDesc s = load_scene(file, {});
  REQUIRE(s.materials.size() == 1);
  CHECK(s.mesh.material == std::vector<std::uint32_t>{0, 0});
  CHECK(s.materials[0].diffuse == glm::vec3(0.2f, 0.3f, 0.4f));
}

TEST_CASE("scene: bare meshes get no camera, no lights and a default material") {
  TempDir dir;
  const auto obj = dir.write("m.OBJ", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const SceneDesc s = load_scene(obj, {});
  CHECK_FALSE(s.has_camera);
  CHECK(s.lights.empty());
  CHECK(is_bare_mesh(s));
  CHECK(s.source == obj.string());
  REQUIRE(s.materials.size() == 1);
  CHECK(s.materials[0].diffuse == glm::vec3(0.7f));
  CHECK(s.materials[0].specular == glm::vec3(0.1f));
  CHECK(s.mesh.triangle_count() == 1);

  const auto ply = dir.write("m.ply",
                             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                             "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                             "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const SceneDesc p = load_scene(ply, {});
  CHECK(is_bare_mesh(p));
  CHECK(p.mesh.triangle_count() == 1);
  CHECK(p.materials.size() == 1);

  const auto empty = dir.write("empty.obj", "v 0 0 0\n");
  const std::string no_geometry = empty.string() + ": scene has no geometry: the mesh has no faces";
  CHECK_THROWS_WITH_AS(load_scene(empty, {}), no_geometry.c_str(), LoadError);
  const auto txt = dir.write("scene.txt", "{}");
  const std::string unknown = txt.string() + ": unknown scene file type \".txt\" (expected .json, .obj or .ply)";
  CHECK_THROWS_WITH_AS(load_scene(txt, {}), unknown.c_str(), LoadError);
  const std::string missing = (dir.path() / "none.json").string() + ": file not found";
  CHECK_THROWS_WITH_AS(load_scene(dir.path() / "none.json", {}), missing.c_str(), LoadError);
}

TEST_CASE("scene: JSON syntax errors report line and column") {
  TempDir dir;
  const auto comma = dir.write("comma.json", "{\n  \"objects\": [1, 2,]\n}\n");
  CHECK(error_of(comma) == comma.string() +
                               ":2:20: invalid JSON: syntax error while parsing value - unexpected ']'; expected '[', "
                               "'{', or a literal");
  const auto unclosed = dir.write("unclosed.json", "{\n  \"objects\": [\n");
  CHECK(error_of(unclosed).rfind(unclosed.string() + ":3:1: invalid JSON: syntax error", 0) == 0);

  const auto comment = dir.write("comment.json", "{\n  // no comments\n  \"objects\": []\n}\n");
  const std::string message = error_of(comment);
  CHECK(message.rfind(comment.string() + ":2:3: invalid JSON: ", 0) == 0);
  CHECK(message.find("(comments are not allowed in scene files)") != std::string::npos);

  const auto huge = dir.write("huge.json", "{\n  \"render\": {\"width\": 1e400}\n}\n");
  CHECK(error_of(huge) == huge.string() + ":2:23: invalid JSON: number 1e400 is too large");

  // Nested 10^5 deep: parsed and destroyed without recursion (no stack overflow), then
  // rejected by what the key expects.
  const std::string open(100000, '['), close(100000, ']');
  const auto deep = dir.write("deep.json", "{\"objects\": " + open + close + "}");
  CHECK(error_of(deep) == deep.string() + ": objects[0]: expected an object, found an array of 1");
}

TEST_CASE("scene: validation errors name the file and the JSON path") {
  TempDir dir;
  TempDir shared;
  dir.write("ok.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  dir.write("m.stl", "solid\n");
  const std::string tri = kTriangle;
  const std::string obj_with = R"({"objects": [)";
  struct Case {
    const char* name;
    std::string json;
    std::string message;  // after "FILE: "
  };
  const Case cases[] = {
      {"top level not an object", "[1]", "(top level): expected an object, found an array of 1"},
      {"unknown top-level key", R"({"objets": []})",
       R"((top level): unknown key "objets" (allowed keys: camera, render, materials, lights, objects))"},
      {"duplicate key", R"({"objects": [{"type": "polygon", "material": "a", "material": "b"}]})",
       R"(objects[0]: duplicate key "material")"},
      {"duplicate key deeper", R"({"render": {}, "objects": [{}, {"transform": {"scale": 1, "scale": 2}}]})",
       R"(objects[1].transform: duplicate key "scale")"},
      {"empty scene", R"({"objects": []})", R"(scene has no geometry: "objects" holds no triangles or polygons)"},
      {"no objects at all", R"({"lights": []})", R"(scene has no geometry: "objects" holds no triangles or polygons)"},
      {"vertex not 3 numbers", obj_with + R"({"type": "triangles", "vertices": [[0, 0, 0], [1, 0], [0, 1, 0]]}]})",
       "objects[0].vertices[1]: expected an array of 3 numbers, found an array of 2"},
      {"vertex with a string", obj_with + R"({"type": "triangles", "vertices": [[0, 0, 0], [1, 0, "0"], [0, 1, 0]]}]})",
       "objects[0].vertices[1][2]: expected a number, found \"0\""},
      {"index out of range", obj_with + R"({"type": "triangles", "vertices": [[0,0,0],[1,0,0],[0,1,0]],
                                            "indices": [[0, 1, 2], [2, 1, 3]]}]})",
       "objects[0].indices[1][2]: index 3 is out of range (the object has 3 vertices, indices start at 0)"},
      {"negative index", obj_with + R"({"type": "triangles", "vertices": [[0,0,0],[1,0,0],[0,1,0]],
                                        "indices": [[0, -1, 2]]}]})",
       "objects[0].indices[0][1]: expected an integer from 0 to 2, found -1"},
      {"index triple too short", obj_with + R"({"type": "triangles", "vertices": [[0,0,0],[1,0,0],[0,1,0]],
                                                "indices": [[0, 1]]}]})",
       "objects[0].indices[0]: expected an array of 3 vertex indices, found an array of 2"},
      {"soup not a multiple of 3", obj_with + R"({"type": "triangles", "vertices": [[0,0,0],[1,0,0],[0,1,0],[1,1,1]]}]})",
       "objects[0].vertices: without \"indices\" every 3 vertices form a triangle, but there are 4"},
      {"polygon with 2 vertices", obj_with + R"({"type": "polygon", "vertices": [[0,0,0],[1,0,0]]}]})",
       "objects[0].vertices: a polygon needs at least 3 vertices, found 2"},
      {"unknown object type", obj_with + R"({"type": "sphere", "radius": 1}]})",
       R"(objects[0].type: unknown object type "sphere" (expected mesh, triangles, polygon or instance))"},
      {"missing type", obj_with + R"({"file": "ok.obj"}]})", R"(objects[0]: missing key "type" (mesh, triangles, polygon or instance))"},
      {"unknown object key", obj_with + R"({"type": "mesh", "file": "ok.obj", "colour": "red"}]})",
       R"(objects[0]: unknown key "colour" (allowed keys: type, name, file, material, transform, mask))"},
      {"unknown material", R"({"materials": {"white": {}, "red": {}}, "objects": [{"type": "mesh", "file": "ok.obj", "material": "whte"}]})",
       R"(objects[0].material: unknown material "whte" (defined: white, red))"},
      {"unknown material, none defined", obj_with + R"({"type": "mesh", "file": "ok.obj", "material": "white"}]})",
       R"(objects[0].material: unknown material "white" (the scene defines no "materials"))"},
      {"unknown material key", R"({"materials": {"white": {"colour": 1}}})",
       R"(materials.white: unknown key "colour" (allowed keys: ambient, diffuse, specular, shininess, mirror, transmittance, ior, emission))"},
      {"materials not an object", R"({"materials": [{"diffuse": 1}]})",
       "materials: expected an object mapping material names to materials, found an array of 1"},
      {"diffuse 0..255", R"({"materials": {"white": {"diffuse": [255, 255, 255]}}})",
       "materials.white.diffuse: expected a colour (a number or [r, g, b]) with channels from 0 to 1, found [255,255,255]"},
      {"negative emission", R"({"materials": {"lamp": {"emission": [1, -1, 0]}}})",
       "materials.lamp.emission: expected a colour (a number or [r, g, b]) with channels of 0 or more, found [1,-1,0]"},
      {"colour as string", R"({"materials": {"lamp": {"diffuse": "red"}}})",
       "materials.lamp.diffuse: expected a colour (a number or [r, g, b]) with channels from 0 to 1, found \"red\""},
      {"ior zero", R"({"materials": {"glass": {"ior": 0}}})",
       "materials.glass.ior: expected an index of refraction greater than 0"},
      {"width zero", R"({"render": {"width": 0}})", "render.width: expected an integer from 2 to 16384, found 0"},
      {"width one", R"({"render": {"width": 1}})", "render.width: expected an integer from 2 to 16384, found 1"},
      {"width negative", R"({"render": {"width": -512}})", "render.width: expected an integer from 2 to 16384, found -512"},
      {"height absurd", R"({"render": {"height": 16385}})",
       "render.height: expected an integer from 2 to 16384, found 16385"},
      {"width fractional", R"({"render": {"width": 512.5}})", "render.width: expected an integer from 2 to 16384, found 512.5"},
      {"width as string", R"({"render": {"width": "512"}})", "render.width: expected an integer from 2 to 16384, found \"512\""},
      {"spp absurd", R"({"render": {"spp": 70000}})", "render.spp: expected an integer from 1 to 65536, found 70000"},
      {"spp zero", R"({"render": {"spp": 0}})", "render.spp: expected an integer from 1 to 65536, found 0"},
      {"max_depth absurd", R"({"render": {"max_depth": 65}})", "render.max_depth: expected an integer from 0 to 64, found 65"},
      {"integrator", R"({"render": {"integrator": "photon"}})", R"(render.integrator: expected "whitted" or "path", found "photon")"},
      {"seed negative", R"({"render": {"seed": -1}})", "render.seed: expected a non-negative integer, found -1"},
      {"unknown render key", R"({"render": {"samples": 4}})",
       R"(render: unknown key "samples" (allowed keys: width, height, spp, max_depth, integrator, background, seed))"},
      {"fov as string", R"({"camera": {"eye": [0,0,0], "look_at": [0,0,-1], "fov": "40"}})",
       "camera.fov: expected a number, found \"40\""},
      {"fov 180", R"({"camera": {"eye": [0,0,0], "look_at": [0,0,-1], "fov": 180}})",
       "camera.fov: expected a vertical field of view in degrees, strictly between 0 and 180"},
      {"camera forms mixed", R"({"camera": {"eye": [0,0,0], "look_at": [0,0,-1], "w": [0,0,-1]}})",
       "camera: mixes the look_at form (look_at, up, fov) with the notes' form (u, v, w, f, window); use one"},
      {"camera without a form", R"({"camera": {"eye": [0,0,0]}})",
       "camera: expected either \"look_at\" (with optional \"up\", \"fov\") or the notes' \"u\", \"v\", \"w\" (with "
       "optional \"f\", \"window\")"},
      {"camera without eye", R"({"camera": {"look_at": [0,0,-1]}})", R"(camera: missing key "eye")"},
      {"look_at equals eye", R"({"camera": {"eye": [1,2,3], "look_at": [1,2,3]}})",
       R"(camera.look_at: must differ from "eye")"},
      {"up parallel", R"({"camera": {"eye": [0,0,0], "look_at": [0,5,0]}})",
       "camera.up: must not be zero or parallel to the view direction (look_at - eye)"},
      {"notes basis degenerate", R"({"camera": {"eye": [0,0,0], "u": [1,0,0], "v": [2,0,0], "w": [0,0,-1]}})",
       "camera: u, v and w must be non-zero and linearly independent"},
      {"notes window inverted", R"({"camera": {"eye": [0,0,0], "u": [1,0,0], "v": [0,1,0], "w": [0,0,-1],
                                    "window": {"left": 1, "right": -1, "top": 1, "bottom": -1}}})",
       "camera.window: expected left < right"},
      {"notes window incomplete", R"({"camera": {"eye": [0,0,0], "u": [1,0,0], "v": [0,1,0], "w": [0,0,-1],
                                      "window": {"left": 1, "right": -1}}})",
       R"(camera.window: missing key "top")"},
      {"light without position", R"({"lights": [{"intensity": 1}]})", R"(lights[0]: missing key "position")"},
      {"light not an array", R"({"lights": {"position": [0,0,0]}})", "lights: expected an array, found an object"},
      {"scale zero", obj_with + R"({"type": "mesh", "file": "ok.obj", "transform": {"scale": [1, 0, 1]}}]})",
       "objects[0].transform.scale: expected non-zero scale factors, found [1,0,1]"},
      {"rotate without degrees", obj_with + R"({"type": "mesh", "file": "ok.obj", "transform": {"rotate": {"axis": [0,1,0]}}}]})",
       R"(objects[0].transform.rotate: missing key "degrees")"},
      {"rotate zero axis", obj_with + R"({"type": "mesh", "file": "ok.obj", "transform": {"rotate": {"axis": [0,0,0], "degrees": 3}}}]})",
       "objects[0].transform.rotate.axis: expected a non-zero axis"},
      {"unknown transform key", obj_with + R"({"type": "mesh", "file": "ok.obj", "transform": {"translation": [0,0,0]}}]})",
       R"(objects[0].transform: unknown key "translation" (allowed keys: scale, rotate, translate))"},
      {"mesh without file", obj_with + R"({"type": "mesh"}]})", R"(objects[0]: missing key "file")"},
      {"mesh file missing", obj_with + R"({"type": "mesh", "file": "nope.obj"}]})",
       "objects[0].file: mesh file \"nope.obj\" not found (looked for " + (dir.path() / "nope.obj").string() +
           "; relative paths start at the scene file's folder)"},
      {"unsupported mesh format", obj_with + R"({"type": "mesh", "file": "m.stl"}]})",
       R"(objects[0].file: unsupported mesh format ".stl" (expected .obj or .ply))"},
      {"unknown variable", obj_with + R"({"type": "mesh", "file": "${scene}/x.obj"}]})",
       R"(objects[0].file: unknown variable in "${scene}/x.obj" (the only one is ${scenes}/ at the start))"},
      {"shared mesh missing", obj_with + R"({"type": "mesh", "file": "${scenes}/nope.obj"}]})",
       "objects[0].file: shared mesh \"${scenes}/nope.obj\" not found (looked for " +
           (shared.path() / "nope.obj").string() +
           "): get the benchmark meshes with scenes/fetch, or pass --scenes DIR or set VOLLEY_SCENES to the folder "
           "that holds them"},
      {"second object wrong", obj_with + tri + R"(, {"type": "polygon", "vertices": [[0,0,0],[1,0,0],[0,1,"x"]]}]})",
       "objects[1].vertices[2][2]: expected a number, found \"x\""},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const auto file = dir.write("scene.json", c.json);
    CHECK(error_of(file, shared.path()) == file.string() + ": " + c.message);
  }
}

TEST_CASE("scene: missing shared folder, errors inside a referenced mesh") {
  TempDir dir;
  dir.write("bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
  const std::string obj_with = R"({"objects": [)";
  {
    const auto file = dir.write("s.json", obj_with + R"({"type": "mesh", "file": "${scenes}/a.obj"}]})");
    CHECK(error_of(file) == file.string() +
                                ": objects[0].file: shared mesh \"${scenes}/a.obj\" needs the shared scenes folder: "
                                "pass --scenes DIR or set VOLLEY_SCENES");
  }
  {
    const auto file = dir.write("s.json", obj_with + R"({"type": "mesh", "file": "bad.obj"}]})");
    CHECK(error_of(file) == (dir.path() / "bad.obj").string() +
                                ":4:7: vertex index 7 is out of range: the file has 3 vertices");
  }
}

TEST_CASE("scene: each object of triangles is recorded with its run of the merged mesh") {
  TempDir dir;
  const auto file = dir.write("objects.json", R"({
    "objects": [
      {"type": "triangles", "name": "first", "vertices": [[0, 0, 0], [1, 0, 0], [0, 1, 0]]},
      {"type": "polygon", "vertices": [[0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]},
      {"type": "triangles", "vertices": [[0, 0, 2], [1, 0, 2], [0, 1, 2], [1, 1, 2], [2, 1, 2], [1, 2, 2]]}
    ]
  })");
  const SceneDesc s = load_scene(file, {});
  REQUIRE(s.mesh.objects.size() == 2);
  CHECK(s.mesh.objects[0].name == "first");
  CHECK(s.mesh.objects[0].first_triangle == 0);
  CHECK(s.mesh.objects[0].triangle_count == 1);
  CHECK(s.mesh.objects[1].name.find("objects[2]") != std::string::npos);
  CHECK(s.mesh.objects[1].first_triangle == 1);
  CHECK(s.mesh.objects[1].triangle_count == 2);
  CHECK(s.polygons.size() == 1);
}
