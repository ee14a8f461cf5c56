// Checked access to the values of a parsed JSON scene: every getter either returns a
// valid value or throws LoadError naming the scene file and the JSON path of the value
// (`scene.json: objects[2].vertices[1]: expected an array of 3 numbers`).
// Internal to src/io.
#pragma once
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

namespace volley::io {

/// Scene files keep their key order (materials are numbered in file order).
using Json = nlohmann::ordered_json;

/// Parses `text` strictly (no comments, no duplicate keys). Syntax errors become
/// LoadError `FILE:LINE:COL: ...`; a duplicate key becomes `FILE: PATH: duplicate key "k"`.
Json parse_json(const std::filesystem::path& file, const std::string& text);

/// The scene file plus the JSON path of one value, for messages.
class JsonPath {
 public:
  JsonPath(const std::filesystem::path& file, std::string path) : file_(&file), path_(std::move(path)) {}

  JsonPath operator[](std::string_view key) const;     ///< path.key
  JsonPath operator[](std::size_t index) const;        ///< path[index]
  const std::string& str() const { return path_; }     ///< "(top level)" for the root
  const std::filesystem::path& file() const { return *file_; }

  /// Throws LoadError `FILE: PATH: what`.
  [[noreturn]] void fail(const std::string& what) const;

 private:
  const std::filesystem::path* file_;
  std::string path_;
};

/// A short rendering of `j` for "found ..." in messages.
std::string describe(const Json& j);

/// `j` must be an object whose keys are all in `allowed`.
void check_object(const Json& j, const JsonPath& at, std::initializer_list<std::string_view> allowed);
/// `j` must be an array (of min_size elements or more).
void check_array(const Json& j, const JsonPath& at, std::size_t min_size = 0);

/// A finite number representable as float, in [lo, hi].
float get_float(const Json& j, const JsonPath& at, float lo = -3.4028235e38f, float hi = 3.4028235e38f);
/// An integer (512 or 512.0) in [lo, hi].
std::int64_t get_int(const Json& j, const JsonPath& at, std::int64_t lo, std::int64_t hi);
/// A non-negative integer up to 2^64 - 1.
std::uint64_t get_uint64(const Json& j, const JsonPath& at);
/// An array of 3 finite numbers.
glm::vec3 get_vec3(const Json& j, const JsonPath& at);
/// A colour: one number (grey) or [r, g, b], every channel in [0, max].
glm::vec3 get_colour(const Json& j, const JsonPath& at, float max);
const std::string& get_string(const Json& j, const JsonPath& at);

}  // namespace volley::io
