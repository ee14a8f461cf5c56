// Whole-file reading and byte-offset → line:column conversion shared by the
// text loaders (OBJ, PLY, JSON). Internal to src/io.
#pragma once
#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

namespace volley::io {

/// The bytes of `file`. Throws LoadError naming the file when it is missing, is
/// not a regular file, or cannot be read.
std::string read_text_file(const std::filesystem::path& file);

/// 1-based line and byte column of `offset` in `text` (offset may equal size()).
struct TextPosition {
  std::size_t line = 1;
  std::size_t column = 1;
};
TextPosition position_of(std::string_view text, std::size_t offset);

}  // namespace volley::io
