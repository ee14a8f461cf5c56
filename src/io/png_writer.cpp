#include "io/png_writer.h"

// Debian's libstb (linked through pkg-config) holds the stb implementations, so the
// headers are included for declarations only.
#include <stb/stb_image.h>
#include <stb/stb_image_write.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>

#include "io/load_error.h"

namespace volley::io {
namespace {

[[noreturn]] void cannot_write(const std::filesystem::path& file, const std::string& why) {
  throw std::runtime_error(file.string() + ": cannot write PNG (" + why + ")");
}

void append_bytes(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<unsigned char>*>(context);
  const auto* bytes = static_cast<const unsigned char*>(data);
  out->insert(out->end(), bytes, bytes + size);
}

}  // namespace

float linear_to_srgb(float linear) {
  return linear <= 0.0031308f ? 12.92f * linear : 1.055f * std::pow(linear, 1.0f / 2.4f) - 0.055f;
}

float srgb_to_linear(float encoded) {
  return encoded <= 0.04045f ? encoded / 12.92f : std::pow((encoded + 0.055f) / 1.055f, 2.4f);
}

void write_png(const std::filesystem::path& file, int width, int height, const std::vector<glm::vec3>& linear_rgb) {
  if (width <= 0 || height <= 0 || linear_rgb.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height))
    throw std::invalid_argument("write_png: " + std::to_string(linear_rgb.size()) + " pixels for a " +
                                std::to_string(width) + " x " + std::to_string(height) + " image");

  std::vector<unsigned char> rgb(3 * linear_rgb.size());
  for (std::size_t i = 0; i < linear_rgb.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const float v = linear_rgb[i][c];
      const float clamped = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;  // NaN → 0 (comparisons are false)
      rgb[3 * i + c] = static_cast<unsigned char>(linear_to_srgb(clamped) * 255.0f + 0.5f);
    }
  }
  std::vector<unsigned char> png;
  if (!stbi_write_png_to_func(&append_bytes, &png, width, height, 3, rgb.data(), 3 * width))
    cannot_write(file, "PNG encoding failed");

  std::error_code ec;
  if (file.has_parent_path() && !std::filesystem::exists(file.parent_path())) {
    std::filesystem::create_directories(file.parent_path(), ec);
    if (ec) cannot_write(file, "cannot create folder " + file.parent_path().string() + ": " + ec.message());
  }
  const std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(file.c_str(), "wb"), &std::fclose);
  if (!f) cannot_write(file, std::strerror(errno));
  if (std::fwrite(png.data(), 1, png.size(), f.get()) != png.size() || std::fflush(f.get()) != 0)
    cannot_write(file, std::strerror(errno));
}

std::vector<glm::vec3> read_png_linear(const std::filesystem::path& file, int& width, int& height) {
  if (!std::filesystem::exists(file)) throw LoadError(file, "file not found");
  int channels = 0;
  const std::unique_ptr<unsigned char, void (*)(void*)> pixels(
      stbi_load(file.c_str(), &width, &height, &channels, 3), &stbi_image_free);
  if (!pixels) throw LoadError(file, std::string("cannot read image (") + stbi_failure_reason() + ")");

  std::array<float, 256> to_linear;
  for (int i = 0; i < 256; ++i) to_linear[i] = srgb_to_linear(static_cast<float>(i) / 255.0f);
  const std::size_t count = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  std::vector<glm::vec3> out(count);
  for (std::size_t i = 0; i < count; ++i)
    out[i] = {to_linear[pixels.get()[3 * i]], to_linear[pixels.get()[3 * i + 1]], to_linear[pixels.get()[3 * i + 2]]};
  return out;
}

}  // namespace volley::io
