// `volley accuracy` end to end on a tiny configuration: the report, the CSV and the plot
// are written and well formed; a missing scenes folder is skipped with a message; bad
// options fail with a message.
#include <doctest/doctest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_run.h"

namespace fs = std::filesystem;

namespace {

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

std::size_t fields(const std::string& line) { return std::size_t(std::count(line.begin(), line.end(), ',')) + 1; }

}  // namespace

TEST_CASE("cli accuracy: a tiny run writes report.md, accuracy.csv and accuracy.png") {
  // Unique per process: several checkouts' test runs may share /tmp.
  const fs::path dir = fs::temp_directory_path() / ("volley_accuracy_test_" + std::to_string(getpid()));
  fs::remove_all(dir);
  const auto r = volley::test::run(
      "accuracy --quick --reps 1 --test watertight,moller --isa scalar --modes single,stream "
      "--scenes /nonexistent/scenes -o " +
      dir.string());
  INFO(r.output);
  REQUIRE(r.status == 0);
  CHECK(r.output.find("accuracy: 8 configurations") != std::string::npos);  // 2 tests x 2 modes x 2 traversals
  CHECK(r.output.find("/nonexistent/scenes not found") != std::string::npos);

  const std::string report = read_text(dir / "report.md");
  CHECK(report.find("## Summary per configuration") != std::string::npos);
  CHECK(report.find("## Robust traversal") != std::string::npos);
  CHECK(report.find("## Image error") != std::string::npos);
  // The query rows: no wrong parity, no wrong inside/outside (scalar: the oracle's rule).
  CHECK(report.find("## Queries beyond the first hit") != std::string::npos);
  CHECK(r.output.find("crossing parity errors 0, contains errors 0") != std::string::npos);
  CHECK(report.find("shared-mesh cases skipped") != std::string::npos);
  CHECK(report.find("nan") == std::string::npos);

  const std::vector<std::string> csv = lines_of(read_text(dir / "accuracy.csv"));
  REQUIRE(csv.size() > 1);
  CHECK(csv[0].rfind("section,set,case,offset,test,isa,mode,traversal,rays", 0) == 0);
  std::size_t ray_rows = 0, image_rows = 0;
  for (const std::string& line : csv) {
    CHECK_MESSAGE(fields(line) == fields(csv[0]), line);
    ray_rows += line.rfind("rays,", 0) == 0;
    image_rows += line.rfind("image,", 0) == 0;
  }
  CHECK(ray_rows == 8 * 3);    // 8 configurations x (2 closed cases + 1 random set)
  CHECK(image_rows == 1 + 2);  // cornell.json: the reference + 2 tests x 1 ISA

  if (std::system("command -v gnuplot > /dev/null 2>&1") == 0) {
    const std::string png = read_text(dir / "accuracy.png");
    CHECK(png.rfind("\x89PNG", 0) == 0);
  } else {
    CHECK(r.output.find("gnuplot not found") != std::string::npos);
  }
  fs::remove_all(dir);
}

TEST_CASE("cli accuracy: --help and bad options") {
  const auto h = volley::test::run("accuracy --help");
  CHECK(h.status == 0);
  CHECK(h.output.find("--long") != std::string::npos);
  const auto bad = volley::test::run("accuracy --test cubic");
  CHECK(bad.status != 0);
  CHECK(bad.output.find("cubic") != std::string::npos);
  const auto unwritable = volley::test::run(
      "accuracy --quick --reps 1 --test watertight --isa scalar --modes single "
      "--no-images --scenes /nonexistent -o /proc/volley_cannot_write_here");
  CHECK(unwritable.status != 0);
  CHECK(unwritable.output.find("/proc/volley_cannot_write_here") != std::string::npos);
}
