// ASCII PLY loading and its bad-input messages.
#include <doctest/doctest.h>

#include <string>

#include <glm/gtc/matrix_transform.hpp>

#include "io/io_test_util.h"
#include "io/load_error.h"
#include "io/ply_loader.h"

using volley::io::LoadError;
using volley::io::load_ply;
using volley::io::SceneDesc;
using volley::io::test::TempDir;

namespace {

const glm::mat4 kIdentity(1.0f);

const std::string kHeader =
    "ply\n"
    "format ascii 1.0\n"
    "comment made by hand\n"
    "element vertex 4\n"
    "property float x\n"
    "property float y\n"
    "property float z\n"
    "property float confidence\n"
    "element face 2\n"
    "property list uchar int vertex_indices\n"
    "end_header\n";  // the body starts on line 12

}  // namespace

TEST_CASE("ply: vertices with extra properties, fan-triangulated faces, other elements skipped") {
  TempDir dir;
  const auto file = dir.write("quad.ply",
                              "ply\r\n"
                              "format ascii 1.0\r\n"
                              "element vertex 5\r\n"
                              "property float x\r\nproperty float y\r\nproperty float z\r\n"
                              "property uchar red\r\nproperty list uchar int extra\r\n"
                              "element face 2\r\n"
                              "property uchar flags\r\n"
                              "property list uchar uint vertex_index\r\n"
                              "element edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\n"
                              "end_header\r\n"
                              "0 0 0 255 0\r\n"
                              "1 0 0 255 2 7 8\r\n"
                              "1 1 0 255 0\r\n"
                              "0 1 0 255 0\r\n"
                              "0.5 0.5 1e-3 255 0\r\n"
                              "9 4 0 1 2 3\r\n"
                              "0 3 4 0 1\r\n"
                              "0 1\r\n");
  SceneDesc s;
  load_ply(file, kIdentity, std::nullopt, s);
  REQUIRE(s.mesh.triangle_count() == 3);
  CHECK(s.mesh.indices == std::vector<std::uint32_t>{0, 1, 2, 0, 2, 3, 4, 0, 1});
  REQUIRE(s.mesh.positions.size() == 5);
  CHECK(s.mesh.positions[4] == glm::vec3(0.5f, 0.5f, 1e-3f));
  REQUIRE(s.materials.size() == 1);
  CHECK(s.materials[0].name == "(default)");
  CHECK(s.mesh.material == std::vector<std::uint32_t>{0, 0, 0});
  CHECK(s.mesh.corner_normals.empty());
}

TEST_CASE("ply: transform, material override, appending after triangles with normals") {
  TempDir dir;
  const auto file = dir.write("t.ply", kHeader + "0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n3 0 1 2\n3 0 2 3\n");
  SceneDesc s;
  s.materials.resize(2);
  s.mesh.positions = {glm::vec3(0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0)};
  s.mesh.indices = {0, 1, 2};
  s.mesh.material = {0};
  s.mesh.corner_normals = {glm::vec3(0, 0, 1), glm::vec3(0, 0, 1), glm::vec3(0, 0, 1)};
  load_ply(file, glm::translate(glm::mat4(1.0f), glm::vec3(0, 0, 5)) * glm::scale(glm::mat4(1.0f), glm::vec3(2.0f)),
           1u, s);
  REQUIRE(s.mesh.triangle_count() == 3);
  CHECK(s.mesh.positions[3 + 2] == glm::vec3(2, 2, 5));
  CHECK(s.mesh.indices == std::vector<std::uint32_t>{0, 1, 2, 3, 4, 5, 3, 5, 6});
  CHECK(s.mesh.material == std::vector<std::uint32_t>{0, 1, 1});
  CHECK(s.materials.size() == 2);
  REQUIRE(s.mesh.corner_normals.size() == 9);
  CHECK(s.mesh.corner_normals[8] == glm::vec3(0, 0, 1));
}

TEST_CASE("ply: bad input throws LoadError with FILE:LINE:COL") {
  TempDir dir;
  const std::string vertices = "0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n";  // lines 12-15
  struct Case {
    const char* name;
    std::string text;
    const char* position;
    const char* message;
  };
  std::string binary = kHeader;
  binary.replace(binary.find("ascii"), 5, "binary_little_endian");
  std::string not_ply = kHeader;
  not_ply.replace(0, 3, "plx");
  std::string no_x = kHeader;
  no_x.replace(no_x.find("property float x"), 16, "property float w");
  std::string unknown_type = kHeader;
  unknown_type.replace(unknown_type.find("float y"), 5, "real ");
  const Case cases[] = {
      {"binary", binary + "\x01\x02", ":2:8",
       "binary PLY not supported (format binary_little_endian); convert the file to ASCII"},
      {"not a PLY file", not_ply, ":1:1", "expected \"ply\" on the first line (not a PLY file)"},
      {"unknown type", unknown_type, ":6:10", "unknown PLY type \"real\""},
      {"no end_header", "ply\nformat ascii 1.0\nelement vertex 0\n", ":4:1",
       "file ends in the header: expected end_header"},
      {"index out of range", kHeader + vertices + "3 0 1 2\n3 0 4 2\n", ":17:5",
       "vertex index 4 is out of range: the file has 4 vertices (indices start at 0)"},
      {"negative index", kHeader + vertices + "3 0 1 2\n3 0 -1 2\n", ":17:5",
       "vertex index -1 is out of range: the file has 4 vertices (indices start at 0)"},
      {"NaN coordinate", kHeader + "0 0 0 1\n1 nan 0 1\n1 1 0 1\n0 1 0 1\n", ":13:3",
       "expected a finite vertex coordinate, found \"nan\""},
      {"garbage coordinate", kHeader + "0 0 0 1\n1 0 0,5 1\n1 1 0 1\n0 1 0 1\n", ":13:5",
       "expected a vertex coordinate, found \"0,5\""},
      {"a face beyond the corner limit", kHeader + vertices + "3 0 1 2\n1000001 0 1 2\n", ":17:1",
       "a face has 1000001 corners, more than 1000000 (the limit of one face)"},
      {"face with two vertices", kHeader + vertices + "2 0 1\n", ":16:1", "a face needs at least 3 vertices, found 2"},
      {"file ends early", kHeader + vertices + "3 0 1 2\n3 0 1", ":17:6", "file ends early: expected a vertex index"},
      {"trailing data", kHeader + vertices + "3 0 1 2\n3 0 1 2\n7\n", ":18:1", "unexpected data after the last element"},
  };
  for (const Case& c : cases) {
    INFO(c.name);
    const auto file = dir.write("bad.ply", c.text);
    const std::string expected = file.string() + c.position + ": " + c.message;
    SceneDesc s;
    CHECK_THROWS_WITH_AS(load_ply(file, kIdentity, std::nullopt, s), expected.c_str(), LoadError);
    CHECK(s.mesh.positions.empty());
  }

  const auto no_x_file = dir.write("nox.ply", no_x + vertices);
  const std::string expected = no_x_file.string() + ": the vertex element has no scalar property x";
  SceneDesc s;
  CHECK_THROWS_WITH_AS(load_ply(no_x_file, kIdentity, std::nullopt, s), expected.c_str(), LoadError);
  const auto missing = dir.path() / "missing.ply";
  const std::string not_found = missing.string() + ": file not found";
  CHECK_THROWS_WITH_AS(load_ply(missing, kIdentity, std::nullopt, s), not_found.c_str(), LoadError);
}

TEST_CASE("ply: a header that claims more than the file holds fails before allocating it") {
  TempDir dir;
  // 10^12 vertices of 3 floats would be 12 TB: the message names the claim and what the
  // body can hold, and nothing that large is reserved (std::bad_alloc was the message).
  const auto huge = dir.write("huge.ply",
                              "ply\nformat ascii 1.0\nelement vertex 1000000000000\nproperty float x\n"
                              "property float y\nproperty float z\nend_header\n0 0 0\n");
  SceneDesc s;
  const std::string expected = huge.string() +
                               ": the header claims 1000000000000 vertex records, but the 6 bytes after end_header "
                               "hold at most 1 (truncated or corrupt file)";
  CHECK_THROWS_WITH_AS(load_ply(huge, kIdentity, std::nullopt, s), expected.c_str(), LoadError);
  // An element without properties holds no data whatever its count: skipped at once.
  const auto empty_elements = dir.write("empty_elements.ply",
                                        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float "
                                        "y\nproperty float z\nelement nothing 1000000000000000\nelement face 1\n"
                                        "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  load_ply(empty_elements, kIdentity, std::nullopt, s);
  CHECK(s.mesh.indices.size() == 3);
  // Not a regular file: /dev/zero would never end.
  const std::string device = "/dev/zero: is not a regular file, expected a file";
  CHECK_THROWS_WITH_AS(load_ply("/dev/zero", kIdentity, std::nullopt, s), device.c_str(), LoadError);
}
