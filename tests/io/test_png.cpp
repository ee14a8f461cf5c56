// PNG writing (clamp, sRGB curve, 8 bit) and reading back as linear RGB.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "io/io_test_util.h"
#include "io/load_error.h"
#include "io/png_writer.h"

using namespace volley::io;
using namespace volley::io::test;

TEST_CASE("png: the sRGB curve at known points, and its inverse") {
  CHECK(linear_to_srgb(0.0f) == 0.0f);
  CHECK(linear_to_srgb(1.0f) == doctest::Approx(1.0f).epsilon(1e-6));
  CHECK(linear_to_srgb(0.0031308f) == doctest::Approx(0.04045f).epsilon(1e-4));  // where the pieces meet
  CHECK(linear_to_srgb(0.5f) == doctest::Approx(0.735357f).epsilon(1e-5));
  CHECK(linear_to_srgb(0.18f) == doctest::Approx(0.461356f).epsilon(1e-5));
  CHECK(linear_to_srgb(0.001f) == doctest::Approx(0.01292f).epsilon(1e-6));  // linear segment
  for (float x : {0.0f, 0.002f, 0.01f, 0.2f, 0.5f, 0.9f, 1.0f})
    CHECK(srgb_to_linear(linear_to_srgb(x)) == doctest::Approx(x).epsilon(1e-5));
}

TEST_CASE("png: write clamps and encodes, read returns linear values of the 8-bit codes") {
  TempDir dir;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<glm::vec3> pixels = {
      {0.0f, 1.0f, 0.5f},       {0.2158605f, 2.0f, -1.0f},  {nan, 0.0031308f, 1e-4f},
      {0.18f, 0.9f, 0.999f},    {0.001f, 0.002f, 0.003f},  {1.0f, 1.0f, 1.0f},
  };
  const auto file = dir.path() / "nested" / "folder" / "out.png";  // folders are created
  write_png(file, 3, 2, pixels);
  int w = 0, h = 0;
  const std::vector<glm::vec3> back = read_png_linear(file, w, h);
  CHECK(w == 3);
  CHECK(h == 2);
  REQUIRE(back.size() == 6);
  // Expected 8-bit codes: round(255 * srgb(clamp(x))).
  const int codes[6][3] = {{0, 255, 188}, {128, 255, 0}, {0, 10, 0}, {118, 243, 255}, {3, 7, 10}, {255, 255, 255}};
  for (int i = 0; i < 6; ++i)
    for (int c = 0; c < 3; ++c) {
      CAPTURE(i);
      CAPTURE(c);
      CHECK(back[i][c] == doctest::Approx(srgb_to_linear(codes[i][c] / 255.0f)).epsilon(1e-6));
      CHECK(std::lround(255.0f * linear_to_srgb(back[i][c])) == codes[i][c]);
    }
}

TEST_CASE("png: size mismatches and unwritable or unreadable files are errors") {
  TempDir dir;
  CHECK_THROWS_AS(write_png(dir.path() / "a.png", 2, 2, std::vector<glm::vec3>(3)), std::invalid_argument);
  CHECK_THROWS_AS(write_png(dir.path() / "a.png", 0, 0, {}), std::invalid_argument);

  const auto blocker = dir.write("blocker", "a file, not a folder");
  try {
    write_png(blocker / "x.png", 1, 1, {glm::vec3(0.5f)});
    FAIL("no exception");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).rfind((blocker / "x.png").string() + ": cannot write PNG (", 0) == 0);
  }

  int w = 0, h = 0;
  const auto missing = dir.path() / "missing.png";
  const std::string not_found = missing.string() + ": file not found";
  CHECK_THROWS_WITH_AS(read_png_linear(missing, w, h), not_found.c_str(), LoadError);
  const auto text = dir.write("text.png", "not a png");
  CHECK_THROWS_AS(read_png_linear(text, w, h), LoadError);
}
