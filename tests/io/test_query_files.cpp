// The query files (.vpts .vcnt .vocc .vdst .vclp .vall): written and read back bit for
// bit; a file of another kind, a short or long payload and inconsistent offsets are named.
#include <doctest/doctest.h>

#include <cstring>
#include <filesystem>
#include <cmath>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "io/load_error.h"
#include "io/query_files.h"

namespace fs = std::filesystem;
using namespace volley;

namespace {
fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "volley_query_files_test";
  fs::create_directories(dir);
  return dir / name;
}
void write_bytes(const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }
std::string what_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const io::LoadError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("query files: every kind reads back what was written") {
  const std::vector<float> xyz = {1, 2, 3, -4.5f, 5e-30f, INFINITY};
  io::write_points(scratch("a.vpts"), xyz);
  CHECK(io::read_points(scratch("a.vpts")) == xyz);
  const std::vector<std::uint32_t> counts = {0, 3, 0xffffffffu};
  io::write_counts(scratch("a.vcnt"), counts);
  CHECK(io::read_counts(scratch("a.vcnt")) == counts);
  const std::vector<std::uint8_t> inside = {1, 0, 0, 1, 1};
  io::write_occupancy(scratch("a.vocc"), inside);
  CHECK(io::read_occupancy(scratch("a.vocc")) == inside);
  CHECK(fs::file_size(scratch("a.vocc")) == 16 + 5);
  const std::vector<float> d = {0.5f, -1.0f};
  io::write_distances(scratch("a.vdst"), d);
  CHECK(io::read_distances(scratch("a.vdst")) == d);
  ClosestPoint c;
  c.point[0] = 1, c.point[1] = 2, c.point[2] = 3, c.prim = 7, c.geom = 2, c.distance = 1;
  const std::vector<io::ClosestRecord> recs = {io::closest_record(c), io::closest_record(ClosestPoint{})};
  io::write_closest(scratch("a.vclp"), recs);
  const auto back = io::read_closest(scratch("a.vclp"));
  REQUIRE(back.size() == 2);
  CHECK(back[0].x == 1.0f);
  CHECK(back[0].primitive == 7);
  CHECK(back[0].geometry == 2);
  CHECK(back[1].primitive == kInvalidPrim);
  CHECK(std::isinf(back[1].x));
  HitLists lists;
  lists.offsets = {0, 2, 2, 3};
  lists.hits = {Hit{1, 0.1f, 0.2f, 4, 0}, Hit{2, 0, 0, 5, 1}, Hit{7, 0.5f, 0.5f, 0, 3, 9}};
  io::write_hit_lists(scratch("a.vall"), lists);
  const HitLists got = io::read_hit_lists(scratch("a.vall"));
  CHECK(got.offsets == lists.offsets);
  REQUIRE(got.hits.size() == 3);
  CHECK(std::memcmp(got.hits.data(), lists.hits.data(), 3 * sizeof(Hit)) == 0);
}

TEST_CASE("query files: bad files are named with the fault") {
  io::write_counts(scratch("b.vcnt"), std::vector<std::uint32_t>{1, 2});
  CHECK(what_of([] { io::read_points(scratch("b.vcnt")); }).find("expected magic \"VPTS\"") != std::string::npos);
  write_bytes(scratch("short.vpts"), std::string("VPTS\x01\0\0\0\x02\0\0\0\0\0\0\0", 16) + std::string(12, '\0'));
  CHECK(what_of([] { io::read_points(scratch("short.vpts")); }).find("truncated") != std::string::npos);
  write_bytes(scratch("v2.vocc"), std::string("VOCC\x02\0\0\0\0\0\0\0\0\0\0\0", 16));
  CHECK(what_of([] { io::read_occupancy(scratch("v2.vocc")); }).find("version 2") != std::string::npos);
  // .vall: offsets that do not end at the hits that follow, a count no file holds.
  HitLists lists;
  lists.offsets = {0, 1};
  lists.hits = {Hit{}};
  io::write_hit_lists(scratch("c.vall"), lists);
  std::string bytes;
  {
    std::ifstream f(scratch("c.vall"), std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(f), {});
  }
  bytes[24] = 2;  // offsets[1] = 2, one hit follows
  write_bytes(scratch("d.vall"), bytes);
  CHECK(what_of([] { io::read_hit_lists(scratch("d.vall")); }).find("offsets") != std::string::npos);
  std::string huge = bytes;
  for (int i = 8; i < 16; ++i) huge[i] = '\xff';
  write_bytes(scratch("e.vall"), huge);
  CHECK(what_of([] { io::read_hit_lists(scratch("e.vall")); }).find("truncated") != std::string::npos);
  CHECK(what_of([] { io::read_points(scratch("missing.vpts")); }).find("not found") != std::string::npos);
}
