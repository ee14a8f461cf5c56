// Ray files (.vray) and hit files (.vhit): the exact bytes of the format, round trips
// that keep every bit (inf, NaN, negative zero), and a named error for each way a file
// can be wrong.
#include <doctest/doctest.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "io/io_test_util.h"
#include "io/load_error.h"
#include "io/ray_file.h"

using namespace volley;
using namespace volley::io;
using namespace volley::io::test;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Little-endian bytes of a header: magic, u32 version, u64 count.
std::string header(const char* magic, std::uint32_t version, std::uint64_t count) {
  std::string s(magic, 4);
  for (int i = 0; i < 4; ++i) s += char((version >> (8 * i)) & 0xff);
  for (int i = 0; i < 8; ++i) s += char((count >> (8 * i)) & 0xff);
  return s;
}

std::string file_bytes(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// The message of the LoadError that f throws ("" when it throws none).
template <class F>
std::string load_error(F&& f) {
  try {
    f();
  } catch (const LoadError& e) {
    return e.what();
  }
  return "";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST_CASE("ray file: the bytes are the documented little-endian layout") {
  TempDir dir;
  const std::vector<Ray> rays = {{{1.0f, 2.0f, 3.0f}, 0.5f, {-1.0f, 0.0f, 0.25f}, kInf}};
  const auto path = dir.path() / "one.vray";
  write_rays(path, rays);
  const std::string bytes = file_bytes(path);
  REQUIRE(bytes.size() == 16 + 32);
  CHECK(bytes.substr(0, 16) == header("VRAY", 1, 1));
  // ox oy oz tmin dx dy dz tmax, each a little-endian binary32.
  const float expected[8] = {1.0f, 2.0f, 3.0f, 0.5f, -1.0f, 0.0f, 0.25f, kInf};
  for (int i = 0; i < 8; ++i) {
    const auto bits = std::bit_cast<std::uint32_t>(expected[i]);
    for (int b = 0; b < 4; ++b) CHECK((unsigned char)bytes[16 + 4 * i + b] == ((bits >> (8 * b)) & 0xff));
  }
}

TEST_CASE("hit file: the bytes are the documented little-endian layout, a miss is inf / 0xffffffff") {
  TempDir dir;
  const std::vector<Hit> hits = {Hit{2.5f, 0.25f, 0.5f, 7, 3, volley::kInvalidId}, Hit{}};
  const auto path = dir.path() / "two.vhit";
  write_hits(path, hits);
  const std::string bytes = file_bytes(path);
  REQUIRE(bytes.size() == 16 + 2 * 24);
  CHECK(bytes.substr(0, 16) == header("VHIT", 2, 2));
  CHECK(bytes.substr(16 + 12, 4) == std::string("\x07\x00\x00\x00", 4));  // prim
  CHECK(bytes.substr(16 + 16, 4) == std::string("\x03\x00\x00\x00", 4));  // geom
  CHECK(bytes.substr(16 + 20, 4) == std::string("\xff\xff\xff\xff", 4));  // inst: none
  CHECK(bytes.substr(40, 4) == std::string("\x00\x00\x80\x7f", 4));       // +inf
  CHECK(bytes.substr(40 + 12, 12) == std::string(12, '\xff'));             // prim, geom, inst of a miss
}

TEST_CASE("hit file: version 1 (16-byte records, scene-wide prim ids) still reads, as geometry 0") {
  TempDir dir;
  const auto path = dir.path() / "old.vhit";
  std::string bytes = header("VHIT", 1, 2);
  const float hit_t = 2.5f, u = 0.25f, v = 0.5f, inf = kInf;
  const std::uint32_t prim = 7, miss = 0xffffffffu, zero = 0;
  for (const void* p : {static_cast<const void*>(&hit_t), static_cast<const void*>(&u),
                        static_cast<const void*>(&v), static_cast<const void*>(&prim)})
    bytes.append(static_cast<const char*>(p), 4);
  for (const void* p : {static_cast<const void*>(&inf), static_cast<const void*>(&zero),
                        static_cast<const void*>(&zero), static_cast<const void*>(&miss)})
    bytes.append(static_cast<const char*>(p), 4);
  std::ofstream(path, std::ios::binary) << bytes;
  const std::vector<Hit> hits = read_hits(path);
  REQUIRE(hits.size() == 2);
  CHECK(hits[0].t == 2.5f);
  CHECK(hits[0].prim == 7);
  CHECK(hits[0].geom == 0);
  CHECK(hits[0].inst == volley::kInvalidId);
  CHECK(!hits[1].hit());
  CHECK(hits[1].geom == volley::kInvalidId);
  // A version-1 header with version-2 sized records is caught by the size check.
  std::ofstream(path, std::ios::binary) << header("VHIT", 1, 1) << std::string(24, '\0');
  CHECK_THROWS_WITH_AS(read_hits(path), doctest::Contains("unexpected bytes"), volley::io::LoadError);
  std::ofstream(path, std::ios::binary) << header("VHIT", 3, 0);
  CHECK_THROWS_WITH_AS(read_hits(path), doctest::Contains("version 3 (expected 2 or 1)"), volley::io::LoadError);
}

TEST_CASE("ray and hit files: round trips keep every bit") {
  TempDir dir;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<Ray> rays = {
      {{0.0f, -0.0f, 1e-38f}, 0.0f, {1.0f, 0.0f, 0.0f}, kInf},
      {{nan, kInf, -kInf}, -1.0f, {0.0f, 0.0f, 0.0f}, 1.0f},
      {{3.0f, 1e30f, -7.5f}, 1e-3f, {1e-20f, -2.0f, 0.1f}, 42.0f},
  };
  for (int i = 0; i < 1000; ++i) rays.push_back({{float(i), 0.5f * i, -float(i)}, 0.0f, {1.0f, float(i), 2.0f}, float(i)});
  write_rays(dir.path() / "r.vray", rays);
  const std::vector<Ray> back = read_rays(dir.path() / "r.vray");
  REQUIRE(back.size() == rays.size());
  CHECK(std::memcmp(back.data(), rays.data(), rays.size() * sizeof(Ray)) == 0);

  std::vector<Hit> hits = {Hit{}, Hit{0.0f, 0.0f, 0.0f, 0}, Hit{1.5f, 0.125f, 0.75f, 0xfffffffeu}};
  write_hits(dir.path() / "h.vhit", hits);
  const std::vector<Hit> hits_back = read_hits(dir.path() / "h.vhit");
  REQUIRE(hits_back.size() == hits.size());
  CHECK(std::memcmp(hits_back.data(), hits.data(), hits.size() * sizeof(Hit)) == 0);
  CHECK(!hits_back[0].hit());

  // Empty files are valid: a header with count 0.
  write_rays(dir.path() / "empty.vray", {});
  CHECK(read_rays(dir.path() / "empty.vray").empty());
  CHECK(file_bytes(dir.path() / "empty.vray") == header("VRAY", 1, 0));
}

TEST_CASE("hit file: occlusion records are t = 0 when blocked, a miss otherwise") {
  const Hit blocked = volley::io::occlusion_record(true);
  const Hit free = volley::io::occlusion_record(false);
  CHECK(blocked.t == 0.0f);
  CHECK(blocked.hit());
  CHECK(free.t == kInf);
  CHECK(free.prim == volley::kInvalidPrim);
}

TEST_CASE("ray file: each kind of bad file is a LoadError naming the file and what was expected") {
  TempDir dir;
  const std::string record(32, '\0');

  const std::string missing = load_error([&] { read_rays(dir.path() / "nope.vray"); });
  CHECK(contains(missing, "nope.vray: file not found"));

  const std::string directory = load_error([&] { read_rays(dir.path()); });
  CHECK(contains(directory, "is a directory"));

  const auto text = dir.write("text.vray", "hello world, not rays at all");
  const std::string bad_magic = load_error([&] { read_rays(text); });
  CHECK(contains(bad_magic, "text.vray: not a ray file (.vray): expected magic \"VRAY\" at byte 0, found \"hell\""));

  const auto binary = dir.write("bin.vray", std::string("\x00\x01\xfe\xff", 4) + header("VRAY", 1, 0).substr(4));
  CHECK(contains(load_error([&] { read_rays(binary); }), "found \"\\x00\\x01\\xfe\\xff\""));

  // A hit file given where rays are expected says so, and the other way round.
  const auto hitfile = dir.write("hits.vhit", header("VHIT", 1, 0));
  CHECK(contains(load_error([&] { read_rays(hitfile); }), "(this is a hit file (.vhit))"));
  const auto rayfile = dir.write("rays.vray", header("VRAY", 1, 0));
  CHECK(contains(load_error([&] { read_hits(rayfile); }), "(this is a ray file (.vray))"));
  CHECK(contains(load_error([&] { read_hits(rayfile); }), "expected magic \"VHIT\""));

  const auto v2 = dir.write("v2.vray", header("VRAY", 2, 1) + record);
  CHECK(contains(load_error([&] { read_rays(v2); }), "v2.vray: unsupported ray file (.vray) version 2 (expected 1)"));

  const auto short_header = dir.write("short.vray", header("VRAY", 1, 1).substr(0, 10));
  CHECK(contains(load_error([&] { read_rays(short_header); }), "short.vray: truncated header: 10 bytes, expected 16"));
  const auto tiny = dir.write("tiny.vray", "VR");
  CHECK(contains(load_error([&] { read_rays(tiny); }), "truncated header: 2 bytes"));

  const auto truncated = dir.write("cut.vray", header("VRAY", 1, 3) + record + record + record.substr(0, 5));
  CHECK(contains(load_error([&] { read_rays(truncated); }),
                 "cut.vray: truncated: header says 3 records of 32 bytes, but only 69 bytes follow the header (room for 2)"));

  const auto trailing = dir.write("long.vray", header("VRAY", 1, 1) + record + "xyz");
  CHECK(contains(load_error([&] { read_rays(trailing); }), "long.vray: 3 unexpected bytes after the 1 records"));

  // A count no file could hold (its byte size overflows 64 bits) is caught before any
  // allocation.
  const auto absurd = dir.write("absurd.vray", header("VRAY", 1, 0xffffffffffffffffull) + record);
  CHECK(contains(load_error([&] { read_rays(absurd); }), "header says 18446744073709551615 records"));

  const auto hits_cut = dir.write("cut.vhit", header("VHIT", 1, 2) + std::string(20, '\0'));
  CHECK(contains(load_error([&] { read_hits(hits_cut); }), "records of 16 bytes, but only 20 bytes"));
}

TEST_CASE("ray file: writing into a missing folder creates it, an unwritable path throws") {
  TempDir dir;
  const auto nested = dir.path() / "a" / "b" / "r.vray";
  write_rays(nested, std::vector<Ray>(3, Ray{{0, 0, 0}, 0, {0, 0, 1}, kInf}));
  CHECK(read_rays(nested).size() == 3);
  CHECK_THROWS_AS(write_rays(dir.path(), {}), std::runtime_error);  // a directory
}
