// Save and load (Accel::save, Accel::load): a loaded structure answers every query form bit
// for bit as the saved one, at every ISA and test, with geometries, a polygon and a
// disabled geometry; it can be changed and refitted afterwards; and a missing, foreign,
// truncated, corrupted, older or inconsistent file is rejected with a message naming it.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "accel/accel_file.h"
#include "accel_test_util.h"
#include "simd/isa/dispatch.h"
#include "simd/wide/wide_bvh.h"
#include "volley/accel.h"

using volley::Accel;
using volley::Hit;
using volley::Isa;
using volley::Ray;
using volley::TriangleTest;
using accel_test::check_forms;
using accel_test::report;

namespace {

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("volley_test_" + name)).string();
}

std::vector<unsigned char> read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_bytes(const std::string& path, const std::vector<unsigned char>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

/// Three triangle geometries (the middle one disabled) and a square polygon.
struct Scene {
  accel_test::Soup a = accel_test::random_soup(300, 1), b = accel_test::random_soup(200, 2),
                   c = accel_test::random_soup(250, 3);
  std::uint32_t add(Accel& accel, const accel_test::Soup& s) const {
    std::vector<std::uint32_t> idx(3 * s.size());
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
    return accel.add_triangles(s.xyz.data(), 3 * s.size(), idx.data(), s.size());
  }
  Accel make(const volley::Options& options) const {
    Accel accel;
    add(accel, a);
    accel.disable_geometry(add(accel, b));
    const float square[] = {-12, -12, 0.5f, 12, -12, 0.5f, 12, 12, 0.5f, -12, 12, 0.5f};
    accel.add_polygon(square, 4);
    add(accel, c);
    accel.commit(options);
    return accel;
  }
};

std::vector<Hit> answers(const Accel& accel, const std::vector<Ray>& rays) {
  std::vector<Hit> out(rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) out[i] = accel.intersect(rays[i]);
  return out;
}

int differing(const std::vector<Hit>& a, const std::vector<Hit>& b) {
  int n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) n += std::memcmp(&a[i], &b[i], sizeof(Hit)) != 0;
  return n;
}

/// Re-signs a file changed in place (the checksum over everything after the header), so
/// that the checks behind the checksum are reached.
void resign(std::vector<unsigned char>& bytes) {
  namespace file = volley::accel::file;
  file::Checksum sum;
  sum.add(bytes.data() + file::kHeaderBytes, bytes.size() - file::kHeaderBytes);
  const std::uint64_t value = sum.value();
  std::memcpy(bytes.data() + offsetof(file::Header, checksum), &value, sizeof value);
}

/// Where the payload of chunk `tag` starts (chunks follow each other in tag order).
std::size_t payload_of(const std::vector<unsigned char>& bytes, volley::accel::file::Tag tag) {
  namespace file = volley::accel::file;
  std::size_t at = file::kHeaderBytes;
  for (std::uint32_t t = 1; t < static_cast<std::uint32_t>(tag); ++t) {
    std::uint64_t size;
    std::memcpy(&size, bytes.data() + at + 8, 8);
    at += 64 + (size + 63) / 64 * 64;
  }
  std::uint32_t found;
  std::memcpy(&found, bytes.data() + at, 4);
  REQUIRE(found == static_cast<std::uint32_t>(tag));
  return at + 64;
}

/// `bytes` with the 4 bytes at `at` replaced by `value` and the checksum made to match.
std::vector<unsigned char> patched(std::vector<unsigned char> bytes, std::size_t at, std::uint32_t value) {
  std::memcpy(bytes.data() + at, &value, 4);
  resign(bytes);
  return bytes;
}

}  // namespace

TEST_CASE("save/load: a loaded structure gives the saved one's answers bit for bit, every ISA and test") {
  const Scene scene;
  const std::vector<Ray> rays = accel_test::mixed_rays(60, 12.0f, 5);
  const std::string path = temp_path("roundtrip.vacc");
  accel_test::for_each_isa_and_test([&](Isa isa, TriangleTest test) {
    const Accel saved = scene.make({test, isa});
    saved.save(path);
    const Accel loaded = Accel::load(path);
    const std::vector<Hit> want = answers(saved, rays);
    std::size_t hits = 0;
    for (const Hit& h : want) hits += h.hit();
    CHECK(hits > rays.size() / 4);
    CHECK(differing(answers(loaded, rays), want) == 0);
    report(check_forms(loaded, rays, want, 7), "loaded");
    const volley::AccelInfo a = saved.info(), b = loaded.info();
    CHECK(b.loaded);
    CHECK(!a.loaded);
    CHECK(b.isa == a.isa);
    CHECK(b.test == a.test);
    CHECK(b.triangles == a.triangles);
    CHECK(b.polygons == a.polygons);
    CHECK(b.geometries == a.geometries);
    CHECK(b.disabled == 1);
    CHECK(b.nodes == a.nodes);
    CHECK(b.leaves == a.leaves);
    CHECK(b.depth == a.depth);
    CHECK(b.bytes == a.bytes);
    CHECK(b.sah_cost == a.sah_cost);
    CHECK(b.binary_sah_cost == a.binary_sah_cost);
    // Saving what was loaded writes the same file.
    const std::string again = temp_path("roundtrip_again.vacc");
    loaded.save(again);
    CHECK(read_bytes(again) == read_bytes(path));
    std::remove(again.c_str());
  });
  std::remove(path.c_str());
}

TEST_CASE("save/load: a loaded structure can be changed: refit, enable, add, commit again") {
  const Scene scene;
  const std::vector<Ray> rays = accel_test::mixed_rays(40, 12.0f, 9);
  const std::string path = temp_path("change.vacc");
  const Isa isa = volley::simd::cpu_has(Isa::avx2) ? Isa::avx2 : Isa::sse42;
  const Accel saved = scene.make({TriangleTest::watertight, isa});
  saved.save(path);

  // Moved vertices: refitted, and the answers of the same move on the original.
  std::vector<float> moved = scene.a.xyz;
  for (float& x : moved) x *= 1.01f;
  Accel loaded = Accel::load(path);
  loaded.update_vertices(0, moved.data(), moved.size() / 3);
  loaded.commit({TriangleTest::watertight, isa});
  CHECK(loaded.info().refitted);
  CHECK(!loaded.info().loaded);
  Accel reference = scene.make({TriangleTest::watertight, isa});
  reference.update_vertices(0, moved.data(), moved.size() / 3);
  reference.commit({TriangleTest::watertight, isa});
  CHECK(reference.info().refitted);
  CHECK(differing(answers(loaded, rays), answers(reference, rays)) == 0);

  // Enabled and extended: a build over everything, as on the original.
  Accel grown = Accel::load(path);
  grown.enable_geometry(1);
  const accel_test::Soup extra = accel_test::random_soup(50, 11);
  CHECK(scene.add(grown, extra) == 4);
  grown.commit({TriangleTest::watertight, isa});
  Accel built = scene.make({TriangleTest::watertight, isa});
  built.enable_geometry(1);
  scene.add(built, extra);
  built.commit({TriangleTest::watertight, isa});
  CHECK(!grown.info().refitted);
  CHECK(grown.info().geometries == 5);
  CHECK(differing(answers(grown, rays), answers(built, rays)) == 0);
  std::remove(path.c_str());
}

TEST_CASE("save/load: empty and polygon-only scenes") {
  const std::string path = temp_path("small.vacc");
  Accel empty;
  empty.commit();
  empty.save(path);
  const Accel e = Accel::load(path);
  CHECK(!e.intersect(accel_test::make_ray({0, 0, 5}, {0, 0, -1})).hit());
  Accel poly;
  const float square[] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
  poly.add_polygon(square, 4);
  poly.commit();
  poly.save(path);
  const Accel p = Accel::load(path);
  const Hit h = p.intersect(accel_test::make_ray({0.2f, 0.1f, 5}, {0, 0, -1}));
  CHECK(h.hit());
  CHECK(h.t == 5.0f);
  CHECK(h.geom == 0);
  std::remove(path.c_str());
}

TEST_CASE("save/load: bad files are rejected with the path and the fault") {
  using Catch = volley::Error;
  const std::string path = temp_path("bad.vacc"), good = temp_path("good.vacc");
  CHECK_THROWS_WITH_AS(Accel().save(path), doctest::Contains("commit"), Catch);
  CHECK_THROWS_WITH_AS(Accel::load(temp_path("missing.vacc")), doctest::Contains("missing.vacc"), Catch);
  const Scene scene;
  const Isa isa = volley::simd::cpu_has(Isa::avx2) ? Isa::avx2 : Isa::sse42;
  scene.make({TriangleTest::watertight, isa}).save(good);
  const std::vector<unsigned char> bytes = read_bytes(good);
  REQUIRE(bytes.size() > 4096);

  write_bytes(path, {'h', 'e', 'l', 'l', 'o'});
  CHECK_THROWS_WITH_AS(Accel::load(path), doctest::Contains("not a volley structure file"), Catch);
  write_bytes(path, {});
  CHECK_THROWS_WITH_AS(Accel::load(path), doctest::Contains("not a volley structure file"), Catch);
  for (std::size_t cut : {std::size_t{64}, std::size_t{100}, bytes.size() / 2, bytes.size() - 64}) {
    CAPTURE(cut);
    write_bytes(path, std::vector<unsigned char>(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(cut)));
    CHECK_THROWS_WITH_AS(Accel::load(path), doctest::Contains("truncated"), Catch);
  }
  for (std::size_t at = 64; at < bytes.size(); at += bytes.size() / 37) {
    CAPTURE(at);
    std::vector<unsigned char> flipped = bytes;
    flipped[at] ^= 0x10;
    write_bytes(path, flipped);
    CHECK_THROWS_WITH_AS(Accel::load(path), doctest::Contains("checksum"), Catch);
  }
  std::vector<unsigned char> old = bytes;
  old[offsetof(volley::accel::file::Header, version)] = 0;
  write_bytes(path, old);
  CHECK_THROWS_WITH_AS(Accel::load(path), doctest::Contains("format version 0"), Catch);
  std::vector<unsigned char> swapped = bytes;
  std::reverse(swapped.begin() + 12, swapped.begin() + 16);
  write_bytes(path, swapped);
  CHECK_THROWS_WITH_AS(Accel::load(path), doctest::Contains("byte order"), Catch);

  // Faults behind a valid checksum (a file made to pass it): every one is still caught.
  namespace file = volley::accel::file;
  std::vector<unsigned char> isa_bad = bytes;
  isa_bad[offsetof(file::Header, isa)] = 9;
  resign(isa_bad);
  write_bytes(path, isa_bad);
  CHECK_THROWS_WITH_AS(Accel::load(path), doctest::Contains("options are not valid"), Catch);
  // The first node's first child pointed back at the root, outside the nodes, or at
  // blocks that are not there: found by the tree check.
  const std::size_t child0 = payload_of(bytes, file::Tag::nodes) + offsetof(volley::simd::WideNode<8>, child);
  for (std::uint32_t bad_ref : {0u, 256u * 100000u, 0x80000000u | (15u << 27) | 0x7ffffffu}) {
    CAPTURE(bad_ref);
    write_bytes(path, patched(bytes, child0, bad_ref));
    CHECK_THROWS_WITH_AS(Accel::load(path), doctest::Contains("wide BVH: node 0 child 0"), Catch);
  }
  // A triangle id the scene lacks; the polygon's id (3) in a block; a vertex index out of range.
  const std::size_t block0 = payload_of(bytes, file::Tag::blocks);
  const std::size_t prim0 = block0 + (isa == Isa::avx2 ? 8 : 4) * 36;  // WatertightBlock: 36 W bytes of vertices first
  for (std::uint32_t bad_id : {5000u, 300u + 200u}) {
    CAPTURE(bad_id);
    write_bytes(path, patched(bytes, prim0, bad_id));
    CHECK_THROWS_WITH_AS(Accel::load(path), doctest::Contains("names triangle"), Catch);
  }
  write_bytes(path, patched(bytes, payload_of(bytes, file::Tag::indices) + 8, 900));
  CHECK_THROWS_WITH_AS(Accel::load(path), doctest::Contains("geometry 0 has a vertex index out of range"), Catch);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::uint32_t nan_bits;
  std::memcpy(&nan_bits, &nan, 4);
  write_bytes(path, patched(bytes, payload_of(bytes, file::Tag::vertices), nan_bits));
  CHECK_THROWS_WITH_AS(Accel::load(path), doctest::Contains("not finite"), Catch);
  std::remove(path.c_str());
  std::remove(good.c_str());
}

TEST_CASE("save/load: a failed save leaves no file behind") {
  Accel accel;
  accel.commit();
  const std::string dir = temp_path("no_such_dir");
  CHECK_THROWS_WITH_AS(accel.save(dir + "/x.vacc"), doctest::Contains("no_such_dir/x.vacc"), volley::Error);
  CHECK(!std::filesystem::exists(dir));
}
