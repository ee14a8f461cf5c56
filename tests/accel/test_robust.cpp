// Options::robust: the plain (unpadded) slab test against the padded one, on every ISA and
// triangle test, through every query form, and the padding's effect where it matters.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "accel_test_util.h"
#include "accuracy/query_modes.h"

using namespace accel_test;
using volley::Options;

namespace {

std::string name(TriangleTest test, Isa isa, bool robust) {
  return std::string(volley::to_string(test)) + " " + std::string(volley::to_string(isa)) +
         (robust ? " robust" : " fast slabs");
}

/// The answers of one Accel to `rays` by single rays, packets of 16, a stream, and occlusion.
struct Answers {
  std::vector<Hit> single, packet, stream;
  std::vector<std::uint8_t> occluded;
};

Answers answers(const Accel& accel, const std::vector<Ray>& rays) {
  namespace acc = volley::accuracy;
  Answers a;
  acc::intersect(accel, rays, acc::Mode::single, a.single);
  acc::intersect(accel, rays, acc::Mode::packet16, a.packet);
  acc::Answers stream = acc::trace(accel, rays, acc::Mode::stream);
  a.stream = std::move(stream.hits);
  a.occluded = std::move(stream.occluded);
  return a;
}

/// The same answer bit for bit: prim, t, u, v.
bool same(const Hit& a, const Hit& b) {
  return a.prim == b.prim && (!a.hit() || (a.t == b.t && a.u == b.u && a.v == b.v));
}

}  // namespace

TEST_CASE("robust: fast slabs give the robust answers on ordinary rays (every test x ISA, every query form)") {
  // Random soups and the ray mix of every traversal form (incoherent, pinhole blocks,
  // axis-aligned, shadow-like, NaN lanes): no ray grazes a box within rounding, so the
  // padding changes nothing: the same answers, form by form. (Agreement with brute force
  // is test_wide.cpp's business.)
  const Soup soup = random_soup(1500, 31);
  const std::vector<Ray> rays = mixed_rays(120, 10.0f, 7);
  for (TriangleTest test : kTests) {
    for (Isa isa : volley::accuracy::available_isas()) {
      CAPTURE(name(test, isa, false));
      const Answers robust = answers(soup.accel(Options{test, isa, true}), rays);
      const Answers fast = answers(soup.accel(Options{test, isa, false}), rays);
      std::size_t differ[4] = {0, 0, 0, 0}, hits = 0;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        hits += robust.single[i].hit();
        differ[0] += !same(fast.single[i], robust.single[i]);
        differ[1] += !same(fast.packet[i], robust.packet[i]);
        differ[2] += !same(fast.stream[i], robust.stream[i]);
        differ[3] += fast.occluded[i] != robust.occluded[i];
      }
      CHECK(hits > rays.size() / 5);
      CHECK(differ[0] == 0);
      CHECK(differ[1] == 0);
      CHECK(differ[2] == 0);
      CHECK(differ[3] == 0);
    }
  }
}

TEST_CASE("robust: rays aimed at the vertices of lone triangles miss some without the padding (every ISA)") {
  // The mutation check of test_wide.cpp through the public options: lone triangles (one per
  // leaf) and rays aimed exactly at their vertices, which often only touch a leaf box at a
  // corner, where rounding decides. Robust traversal finds every hit brute force finds; the
  // fast slabs must miss some on every ISA, scalar oracle included, or this test could not
  // tell the two apart.
  const VertexAimed case_ = lone_triangles_vertex_aimed();
  const Soup& soup = case_.soup;
  const std::vector<Ray>& rays = case_.rays;
  for (Isa isa : volley::accuracy::available_isas()) {
    // (AVX2 and AVX-512 fuse the watertight shear: their own oracle variant.)
    const std::vector<Hit> want = brute_force_all(soup, TriangleTest::watertight, rays, isa);
    std::size_t wrong[2] = {0, 0};
    for (bool robust : {false, true}) {
      const Accel accel = soup.accel(Options{TriangleTest::watertight, isa, robust});
      for (std::size_t i = 0; i < rays.size(); ++i) wrong[robust] += !agree(accel.intersect(rays[i]), want[i]);
    }
    CAPTURE(std::string(volley::to_string(isa)));
    MESSAGE(std::string(volley::to_string(isa)), ": ", rays.size(), " vertex-aimed rays, wrong with fast slabs ",
            wrong[0], ", robust ", wrong[1]);
    CHECK(wrong[1] == 0);
    CHECK(wrong[0] > 0);
  }
}

TEST_CASE("robust: AccelInfo reports the traversal options") {
  const Soup soup = random_soup(50, 4);
  for (Isa isa : volley::accuracy::available_isas())
    for (bool robust : {true, false}) {
      const volley::AccelInfo info = soup.accel(Options{TriangleTest::moller, isa, robust}).info();
      CHECK(info.robust == robust);
      CHECK(!info.reference_double);
    }
  const volley::AccelInfo ref = soup.accel(Options{TriangleTest::moller, Isa::scalar, true, true}).info();
  CHECK(ref.robust);
  CHECK(ref.reference_double);
}
