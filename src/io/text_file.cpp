#include "io/text_file.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "io/load_error.h"

namespace volley::io {

std::string read_text_file(const std::filesystem::path& file) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (!std::filesystem::exists(status)) throw LoadError(file, "file not found");
  if (std::filesystem::is_directory(status)) throw LoadError(file, "is a directory, expected a file");
  // A device or pipe (/dev/zero, /dev/stdin) could be endless: regular files only.
  if (!std::filesystem::is_regular_file(status)) throw LoadError(file, "is not a regular file, expected a file");

  // stdio rather than iostreams: one fread of the whole file is the fastest portable read.
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(file.c_str(), "rb"), &std::fclose);
  if (!f) throw LoadError(file, std::string("cannot open file (") + std::strerror(errno) + ")");
  // Read straight into the string; keep reading past the stat size in case the file grew.
  std::string bytes;
  const auto size = std::filesystem::file_size(file, ec);
  bytes.resize(ec ? 0 : static_cast<std::size_t>(size));
  bytes.resize(std::fread(bytes.data(), 1, bytes.size(), f.get()));
  char chunk[1 << 16];
  for (std::size_t n; (n = std::fread(chunk, 1, sizeof chunk, f.get())) > 0;) bytes.append(chunk, n);
  if (std::ferror(f.get())) throw LoadError(file, std::string("cannot read file (") + std::strerror(errno) + ")");
  return bytes;
}

TextPosition position_of(std::string_view text, std::size_t offset) {
  offset = std::min(offset, text.size());
  const std::string_view before = text.substr(0, offset);
  TextPosition pos;
  pos.line = 1 + static_cast<std::size_t>(std::count(before.begin(), before.end(), '\n'));
  const std::size_t line_start = before.rfind('\n');
  pos.column = offset - (line_start == std::string_view::npos ? 0 : line_start + 1) + 1;
  return pos;
}

}  // namespace volley::io
