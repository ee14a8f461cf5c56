// The one exception type every loader in src/io throws for bad input.
#pragma once
#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace volley::io {

/// The most corners one polygonal face of an OBJ or PLY file may have (a fan of
/// kMaxFaceCorners - 2 triangles). A face beyond it is an error naming the limit: input
/// that is no mesh (or an attack) would otherwise turn into memory without bound.
inline constexpr std::size_t kMaxFaceCorners = 1000000;

/// Bad or unreadable input. what() reads `FILE:LINE:COL: what was expected`, or
/// `FILE:LINE: ...` / `FILE: ...` when the column / line is not known (for JSON
/// validation errors the text after `FILE: ` starts with the JSON path, e.g.
/// `scene.json: objects[2].vertices[1]: expected an array of 3 numbers`).
/// FILE is the path as the caller spelled it. Lines and columns count from 1;
/// a column counts bytes (a tab is one column).
class LoadError : public std::runtime_error {
 public:
  /// Position unknown: `FILE: message`.
  LoadError(const std::filesystem::path& file, const std::string& message);
  /// line > 0; column 0 means unknown: `FILE:LINE: message` or `FILE:LINE:COL: message`.
  LoadError(const std::filesystem::path& file, std::size_t line, std::size_t column,
            const std::string& message);

  const std::filesystem::path& file() const noexcept { return file_; }
  std::size_t line() const noexcept { return line_; }      ///< 0: unknown
  std::size_t column() const noexcept { return column_; }  ///< 0: unknown
  /// The message without the `FILE:LINE:COL: ` prefix.
  const std::string& message() const noexcept { return message_; }

 private:
  std::filesystem::path file_;
  std::size_t line_ = 0;
  std::size_t column_ = 0;
  std::string message_;
};

}  // namespace volley::io
