// OBJ (+ MTL) loading: geometry, fan triangulation, indices, transforms, normals,
// materials, and every kind of bad input with its FILE:LINE:COL message.
#include <doctest/doctest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "io/io_test_util.h"
#include "io/load_error.h"
#include "io/obj_loader.h"

using namespace volley::io;
using namespace volley::io::test;

namespace {

const glm::mat4 kIdentity(1.0f);

SceneDesc load(const std::filesystem::path& file, const glm::mat4& transform = kIdentity,
               std::optional<std::uint32_t> material = std::nullopt) {
  SceneDesc scene;
  load_obj(file, transform, material, scene);
  return scene;
}

/// The OBJ text, written to a file of its own, loaded.
SceneDesc load_text(std::string_view obj, const glm::mat4& transform = kIdentity) {
  TempDir dir;
  return load(dir.write("text.obj", obj), transform);
}

bool near(const glm::vec3& a, const glm::vec3& b, float eps = 1e-6f) { return glm::length(a - b) <= eps; }

}  // namespace

TEST_CASE("obj: fan triangulation in file order, bit-exact positions, default material") {
  TempDir dir;
  const auto file = dir.write("fan.obj",
                              "# a triangle, a quad and a pentagon\n"
                              "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -0.5 0.5 0\n"
                              "v 0.1 0.2 0.3\n"
                              "f 1 2 3\n"
                              "f 1 2 3 4\n"
                              "f 1 2 3 4 5\n");
  const SceneDesc s = load(file);
  REQUIRE(s.mesh.triangle_count() == 6);
  const std::vector<std::uint32_t> expected = {0, 1, 2,  0, 1, 2, 0, 2, 3,  0, 1, 2, 0, 2, 3, 0, 3, 4};
  CHECK(s.mesh.indices == expected);
  REQUIRE(s.mesh.positions.size() == 6);  // unused vertices are kept
  CHECK(s.mesh.positions[5] == glm::vec3(0.1f, 0.2f, 0.3f));
  CHECK(s.mesh.positions[4] == glm::vec3(-0.5f, 0.5f, 0.0f));
  CHECK(s.mesh.corner_normals.empty());
  REQUIRE(s.materials.size() == 1);
  CHECK(s.materials[0].name == "(default)");
  CHECK(s.materials[0].diffuse == glm::vec3(0.7f));
  CHECK(s.mesh.material == std::vector<std::uint32_t>(6, 0));
}

TEST_CASE("obj: negative indices, CRLF line ends, tabs, comments after data, w and colours ignored") {
  TempDir dir;
  const auto file = dir.write("rel.obj",
                              "v\t0 0 0 1.0\r\n"
                              "v  1 0 0 0.5 0.5 0.5\r\n"
                              "v 1 1 0   \r\n"
                              "v 0 1 0 # comment\r\n"
                              "\r\n"
                              "f -4 -3 -2 -1 \r\n"
                              "v 5 5 5\r\n"
                              "f\t-5\t-3\t-1\r\n"  // refers back past the previous block
                              "f 1/1 2/2 3/3\r\n"
                              "f 1//1 2//1 3//1 # normals would be 1\r\n"
                              "vn 0 0 1\r\n");
  const SceneDesc s = load(file);
  REQUIRE(s.mesh.triangle_count() == 5);
  const std::vector<std::uint32_t> expected = {0, 1, 2, 0, 2, 3, 0, 2, 4, 0, 1, 2, 0, 1, 2};
  CHECK(s.mesh.indices == expected);
  CHECK(s.mesh.positions[4] == glm::vec3(5.0f));
  // Only the last face has normals; the others get their geometric normal.
  REQUIRE(s.mesh.corner_normals.size() == 15);
  CHECK(s.mesh.corner_normals[0] == glm::vec3(0, 0, 1));
  CHECK(near(s.mesh.corner_normals[6], glm::normalize(glm::vec3(5, -5, 0))));  // triangle (0,0,0) (1,1,0) (5,5,5)
  CHECK(s.mesh.corner_normals[14] == glm::vec3(0, 0, 1));
}

TEST_CASE("obj: corner normals in corner order, v/vt/vn, renormalized, zero normal falls back") {
  const SceneDesc s = load_text(
      "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
      "vt 0 0\n"
      "vn 0 0 2\nvn 0 1 0\nvn 1 0 0\nvn 0 0 0\n"
      "f 1/1/1 2/1/2 3/1/3 4/1/4\n");
  REQUIRE(s.mesh.triangle_count() == 2);
  // Triangle 0 = corners 1 2 3, triangle 1 = corners 1 3 4 (vn 4 is zero: geometric +z).
  const std::vector<glm::vec3> want = {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}, {1, 0, 0}, {0, 0, 1}};
  CHECK(s.mesh.corner_normals == want);
}

TEST_CASE("obj: transform maps positions, the inverse transpose maps normals") {
  const glm::mat4 m = glm::translate(glm::mat4(1.0f), glm::vec3(10, 0, 0)) *
                      glm::scale(glm::mat4(1.0f), glm::vec3(2, 1, 1));
  const SceneDesc s = load_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 1 1 0\nf 1//1 2//1 3//1\n", m);
  CHECK(s.mesh.positions[1] == glm::vec3(12, 0, 0));
  CHECK(s.mesh.positions[2] == glm::vec3(10, 1, 0));
  // Non-uniform scale: the normal of the plane x + y = c becomes (0.5, 1, 0) renormalized.
  CHECK(near(s.mesh.corner_normals[0], glm::normalize(glm::vec3(0.5f, 1.0f, 0.0f))));
  CHECK(std::fabs(glm::length(s.mesh.corner_normals[2]) - 1.0f) < 1e-6f);
}

TEST_CASE("obj: appending keeps indices, materials and the 3-normals-per-triangle invariant") {
  TempDir dir;
  const auto plain = dir.write("plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const auto with_normals = dir.write("normals.obj", "v 0 0 0\nv 0 1 0\nv 1 0 0\nvn 1 2 3\nf 1//1 2//1 3//1\n");

  SUBCASE("plain, then with normals: earlier triangles get geometric normals") {
    SceneDesc s;
    load_obj(plain, kIdentity, std::nullopt, s);
    load_obj(with_normals, kIdentity, std::nullopt, s);
    REQUIRE(s.mesh.triangle_count() == 2);
    CHECK(s.mesh.indices == std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5});
    REQUIRE(s.mesh.corner_normals.size() == 6);
    CHECK(s.mesh.corner_normals[0] == glm::vec3(0, 0, 1));
    CHECK(near(s.mesh.corner_normals[3], glm::normalize(glm::vec3(1, 2, 3))));
    CHECK(s.materials.size() == 1);  // one shared default material
    CHECK(s.mesh.material == std::vector<std::uint32_t>{0, 0});
  }
  SUBCASE("with normals, then plain: later triangles get geometric normals") {
    SceneDesc s;
    load_obj(with_normals, kIdentity, std::nullopt, s);
    load_obj(plain, kIdentity, std::nullopt, s);
    REQUIRE(s.mesh.corner_normals.size() == 6);
    CHECK(s.mesh.corner_normals[5] == glm::vec3(0, 0, 1));
  }
  SUBCASE("material override is used for every triangle") {
    SceneDesc s;
    s.materials.resize(3);
    load_obj(plain, kIdentity, 2u, s);
    CHECK(s.mesh.material == std::vector<std::uint32_t>{2});
    CHECK(s.materials.size() == 3);
    CHECK_THROWS_AS(load_obj(plain, kIdentity, 3u, s), std::invalid_argument);
  }
}

TEST_CASE("obj: MTL materials are mapped, appended once in order of first use") {
  TempDir dir;
  dir.write("sub/m.mtl",
            "newmtl unused\nKd 1 0 0\n"
            "newmtl glass\r\n  Ka 0 0 0\r\n  Kd 0.1 0.1 0.1\r\n  Ks 0.5 0.5 0.5\r\n  Ns 100\r\n  Ni 1.5\r\n"
            "  Tf 0.9 0.8 0.7\r\n  illum 7\r\n"
            "newmtl mirror\nKd 0 0 0\nKs 0.9 0.9 0.9\nillum 3\n"
            "newmtl lamp\nKa 0.2 0.2 0.2 # grey\nKd 0.5 0.6 0.7\nKe 17 12 4\nillum 2\n"
            "newmtl veil\nKd 1 1 1\nd 0.25\n");
  const auto file = dir.write("sub/m.obj",
                              "mtllib m.mtl\n"
                              "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                              "f 1 2 3\n"  // before any usemtl: default
                              "usemtl lamp\nf 1 2 3\n"
                              "usemtl glass\nf 1 2 3\n"
                              "usemtl lamp\nf 1 2 3\n"
                              "usemtl mirror\nf 1 2 3\n"
                              "usemtl veil\nf 1 2 3\n"
                              "usemtl nowhere\nf 1 2 3\n");
  CaptureStderr err;
  const SceneDesc s = load(file);
  REQUIRE(s.materials.size() == 5);
  CHECK(s.materials[0].name == "lamp");
  CHECK(s.materials[1].name == "glass");
  CHECK(s.materials[2].name == "mirror");
  CHECK(s.materials[3].name == "veil");
  CHECK(s.materials[4].name == "(default)");
  CHECK(s.mesh.material == std::vector<std::uint32_t>{4, 0, 1, 0, 2, 3, 4});

  const auto& lamp = s.materials[0];
  CHECK(near(lamp.ambient, glm::vec3(0.2f)));
  CHECK(near(lamp.diffuse, glm::vec3(0.5f, 0.6f, 0.7f)));
  CHECK(lamp.emission == glm::vec3(17, 12, 4));
  CHECK(lamp.mirror == glm::vec3(0.0f));
  CHECK(lamp.transmittance == glm::vec3(0.0f));
  const auto& glass = s.materials[1];
  CHECK(near(glass.specular, glm::vec3(0.5f)));
  CHECK(glass.shininess == 100.0f);
  CHECK(glass.ior == doctest::Approx(1.5f));
  CHECK(near(glass.transmittance, glm::vec3(0.9f, 0.8f, 0.7f)));
  CHECK(near(s.materials[2].mirror, glm::vec3(0.9f)));
  CHECK(near(s.materials[3].transmittance, glm::vec3(0.75f)));
  CHECK(err.text().find("\"nowhere\"") != std::string::npos);
}

TEST_CASE("obj: a missing MTL is a warning, not an error, and an override skips the MTL") {
  TempDir dir;
  const auto file = dir.write("a.obj", "mtllib gone.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n");
  {
    CaptureStderr err;
    const SceneDesc s = load(file);
    CHECK(s.mesh.triangle_count() == 1);
    REQUIRE(s.materials.size() == 1);
    CHECK(s.materials[0].name == "(default)");
    CHECK(err.text().find(file.string() + ":1: material library \"gone.mtl\" not found") != std::string::npos);
  }
  {
    CaptureStderr err;
    SceneDesc s;
    s.materials.resize(1);
    load_obj(file, kIdentity, 0u, s);
    CHECK(s.materials.size() == 1);
    CHECK(err.text().empty());
  }
}

TEST_CASE("obj: a file without faces is not an error, and underflow reads as 0") {
  TempDir dir;
  const auto file = dir.write("empty.obj", "# nothing\nv 1e-50 0 0\n");
  const SceneDesc s = load(file);
  CHECK(s.mesh.triangle_count() == 0);
  REQUIRE(s.mesh.positions.size() == 1);
  CHECK(s.mesh.positions[0].x == 0.0f);
}

TEST_CASE("obj: bad input throws LoadError with FILE:LINE:COL and what was expected") {
  TempDir dir;
  const std::string header = "v 0 0 0\nv 1 0 0\nv 1 1 0\n";
  struct Case {
    const char* name;
    std::string body;       // appended to the 3-vertex header (line 4 on)
    const char* position;   // ":LINE:COL"
    const char* message;
  };
  const Case cases[] = {
      {"positive index past the end", "f 1 2 4\n", ":4:7", "vertex index 4 is out of range: the file has 3 vertices"},
      {"forward reference past the end", "f 1 2 3\nf 1 2 5\nv 2 2 2\n", ":5:7",
       "vertex index 5 is out of range: the file has 4 vertices"},
      {"relative index before the first", "f -1 -2 -4\n", ":4:9",
       "relative vertex index -4 is out of range: only 3 vertices are defined above this line"},
      {"index 0", "f 0 1 2\n", ":4:3",
       "vertex index 0 is not valid: OBJ indices start at 1 (negative ones count back from the last vertex)"},
      {"normal index past the end", "vn 0 0 1\nf 1//1 2//1 3//2\n", ":5:16",
       "normal index 2 is out of range: the file has 1 normals"},
      {"relative normal index", "f 1//-1 2 3\n", ":4:6",
       "relative normal index -1 is out of range: only 0 normals are defined above this line"},
      {"NaN coordinate", "v 1 1 nan\n", ":4:7", "expected a finite vertex coordinate, found \"nan\""},
      {"inf coordinate", "v\t-inf 1 1\n", ":4:3", "expected a finite vertex coordinate, found \"-inf\""},
      {"NaN normal", "vn 0 NaN 1\n", ":4:6", "expected a finite normal coordinate, found \"NaN\""},
      {"overflow", "v 1 1e39 1\n", ":4:5", "expected a vertex coordinate, found \"1e39\" (out of float range)"},
      {"garbage number", "v 1 2.5x 1\n", ":4:5", "expected a vertex coordinate, found \"2.5x\""},
      {"too few coordinates", "v 1 2\n", ":4:6", "expected a vertex coordinate (x y z), found the end of the line"},
      {"face with two vertices", "f 1 2\n", ":4:1", "a face needs at least 3 vertices, found 2"},
      {"malformed corner", "f 1 2 3/1/1/1\n", ":4:7",
       "expected a face corner v, v/vt, v//vn or v/vt/vn, found \"3/1/1/1\""},
      {"word instead of an index", "f 1 two 3\n", ":4:5", "expected a vertex index, found \"two\""},
      {"usemtl without a name", "usemtl   \n", ":4:10", "expected a material name after usemtl"},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const auto file = dir.write("bad.obj", header + c.body);
    const std::string expected = file.string() + c.position + ": " + c.message;
    SceneDesc s;
    s.mesh.positions.push_back(glm::vec3(7.0f));
    CHECK_THROWS_WITH_AS(load_obj(file, kIdentity, std::nullopt, s), expected.c_str(), LoadError);
    // Strong guarantee: nothing was appended.
    CHECK(s.mesh.positions.size() == 1);
    CHECK(s.materials.empty());
  }
}

TEST_CASE("obj: unreadable files and non-finite results of the transform") {
  TempDir dir;
  const auto missing = dir.path() / "missing.obj";
  const std::string not_found = missing.string() + ": file not found";
  CHECK_THROWS_WITH_AS(load(missing), not_found.c_str(), LoadError);
  const std::string is_dir = dir.path().string() + ": is a directory, expected a file";
  CHECK_THROWS_WITH_AS(load(dir.path()), is_dir.c_str(), LoadError);

  const std::string device = "/dev/zero: is not a regular file, expected a file";
  CHECK_THROWS_WITH_AS(load("/dev/zero"), device.c_str(), LoadError);
  // An MTL that is a device is a warning (as a missing one), never an endless read.
  const auto device_mtl = dir.write("device_mtl.obj", "mtllib /dev/zero\nusemtl x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  CHECK(load(device_mtl).mesh.indices.size() == 3);

  // A face beyond the corner limit (10^7 corners: 3 x 10^7 bytes of file would become a
  // fan of 10^7 triangles) fails at the first corner past it.
  std::string corners = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf";
  for (std::size_t i = 0; i <= volley::io::kMaxFaceCorners; ++i) corners += " 1";
  const auto many = dir.write("many_corners.obj", corners + "\n");
  const std::string too_many = many.string() + ":4:" + std::to_string(3 + 2 * volley::io::kMaxFaceCorners) +
                               ": a face has more than 1000000 corners (the limit of one face)";
  CHECK_THROWS_WITH_AS(load(many), too_many.c_str(), LoadError);

  const auto big = dir.write("big.obj", "v 3e38 0 0\nv 0 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::string overflow = big.string() + ": vertex 1 is not finite after the object transform";
  CHECK_THROWS_WITH_AS(load(big, glm::scale(glm::mat4(1.0f), glm::vec3(10.0f))), overflow.c_str(), LoadError);
}

TEST_CASE("obj: LoadError exposes its parts") {
  TempDir dir;
  const auto file = dir.write("p.obj", "v 0 0 0\nv 1 x 0\n");
  try {
    load(file);
    FAIL("no LoadError");
  } catch (const LoadError& e) {
    CHECK(e.file() == file);
    CHECK(e.line() == 2);
    CHECK(e.column() == 5);
    CHECK(e.message() == "expected a vertex coordinate, found \"x\"");
  }
}
