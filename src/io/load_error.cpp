#include "io/load_error.h"

namespace volley::io {
namespace {

std::string format(const std::filesystem::path& file, std::size_t line, std::size_t column,
                   const std::string& message) {
  std::string out = file.string();
  if (line > 0) {
    out += ':' + std::to_string(line);
    if (column > 0) out += ':' + std::to_string(column);
  }
  out += ": ";
  out += message;
  return out;
}

}  // namespace

LoadError::LoadError(const std::filesystem::path& file, const std::string& message)
    : LoadError(file, 0, 0, message) {}

LoadError::LoadError(const std::filesystem::path& file, std::size_t line, std::size_t column,
                     const std::string& message)
    : std::runtime_error(format(file, line, column, message)),
      file_(file),
      line_(line),
      column_(line > 0 ? column : 0),
      message_(message) {}

}  // namespace volley::io
