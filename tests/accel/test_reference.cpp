// Options::reference_double: the scalar oracle with the triangle tests in double precision,
// the reference of the accuracy report. It agrees with the float oracle away from edges,
// its t is the long-double t to within double rounding, it refuses SIMD ISAs, and
// `volley trace --reference` runs it end to end.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <regex>
#include <string>
#include <vector>

#include "accel_test_util.h"
#include "cli/cli_run.h"
#include "core/triangle.h"

using namespace accel_test;
using volley::Options;

namespace {

/// Distance of a hit from its triangle's edges in barycentric terms (min of u, v, 1-u-v).
float edge_margin(const Hit& h) { return std::min({h.u, h.v, 1.0f - h.u - h.v}); }

/// The triangle test of `test` in precision T on the widened ray and vertices.
template <class T>
bool intersect_in(TriangleTest test, const Ray& ray, const Soup& soup, std::size_t prim, volley::core::TriHit<T>& hit) {
  using V = volley::core::Vec3<T>;
  const volley::core::RayT<T> r{V(ray.org[0], ray.org[1], ray.org[2]), T(ray.tmin),
                                V(ray.dir[0], ray.dir[1], ray.dir[2]), T(ray.tmax)};
  return volley::core::intersect_triangle<T>(test, r, V(soup.vertex(prim, 0)), V(soup.vertex(prim, 1)),
                                             V(soup.vertex(prim, 2)), hit);
}

/// Rays from around a soup toward random points inside it (ordinary, incoherent).
std::vector<Ray> ordinary_rays(int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-10.0f, 10.0f);
  std::vector<Ray> rays;
  for (int i = 0; i < n; ++i) {
    const glm::vec3 o(2.0f * pos(rng), 2.0f * pos(rng), 2.0f * pos(rng));
    rays.push_back(make_ray(o, glm::vec3(pos(rng), pos(rng), pos(rng)) - o));
  }
  return rays;
}

std::string name(TriangleTest test) { return std::string(volley::to_string(test)); }

}  // namespace

TEST_CASE("reference: agrees with the float oracle on hit and miss away from edges (every test)") {
  const Soup soup = random_soup(1500, 41);
  const std::vector<Ray> rays = ordinary_rays(20000, 3);
  for (TriangleTest test : kTests) {
    CAPTURE(name(test));
    const Accel fast = soup.accel(Options{test, Isa::scalar});
    const Accel ref = soup.accel(Options{test, Isa::scalar, true, true});
    std::size_t hits = 0, near_edge = 0, disagree = 0;
    double worst_t = 0.0;
    for (const Ray& ray : rays) {
      const Hit f = fast.intersect(ray), r = ref.intersect(ray);
      CHECK(ref.occluded(ray) == r.hit());
      hits += r.hit();
      // A float answer may flip only where some hit lies within rounding of an edge.
      const bool edgy = (f.hit() && edge_margin(f) < 1e-4f) || (r.hit() && edge_margin(r) < 1e-4f);
      near_edge += edgy;
      if (edgy) continue;
      disagree += f.prim != r.prim;
      if (f.hit() && f.prim == r.prim) worst_t = std::max(worst_t, std::abs(double(f.t) - r.t) / r.t);
    }
    MESSAGE(name(test), ": ", hits, " hits of ", rays.size(), ", ", near_edge,
            " near an edge, worst relative t difference float vs reference ", worst_t);
    CHECK(hits > rays.size() / 10);
    CHECK(disagree == 0);
    CHECK(worst_t < 1e-4);
    // Packets and streams of the reference answer as its single rays do.
    const std::vector<Ray> some(rays.begin(), rays.begin() + 2000);
    std::vector<Hit> singles;
    for (const Ray& ray : some) singles.push_back(ref.intersect(ray));
    report(check_forms(ref, some, singles, 6), "reference " + name(test));
  }
}

TEST_CASE("reference: t is the long-double t rounded (double error ~1e-16 relative)") {
  // Per hit: the double test's t against the same test in long double (64-bit mantissa on
  // x86) on the same widened input, and the reference's float t against the long-double t
  // rounded to float.
  const Soup soup = random_soup(1500, 43);
  const std::vector<Ray> rays = ordinary_rays(5000, 8);
  for (TriangleTest test : kTests) {
    CAPTURE(name(test));
    const Accel ref = soup.accel(Options{test, Isa::scalar, true, true});
    std::vector<double> rel;
    std::size_t rounded_off = 0;
    for (const Ray& ray : rays) {
      const Hit h = ref.intersect(ray);
      if (!h.hit()) continue;
      volley::core::TriHit<double> d;
      volley::core::TriHit<long double> ld;
      REQUIRE(intersect_in(test, ray, soup, h.prim, d));
      REQUIRE(intersect_in(test, ray, soup, h.prim, ld));
      rel.push_back(double(std::abs((static_cast<long double>(d.t) - ld.t) / ld.t)));
      CHECK(h.t == static_cast<float>(d.t));
      // Double rounding (long double -> double -> float) may move t by one float ulp at most.
      const float want = static_cast<float>(ld.t);
      rounded_off += h.t != want;
      CHECK(std::abs(h.t - want) <= std::nextafter(want, INFINITY) - want);
    }
    REQUIRE(rel.size() > 100);
    std::sort(rel.begin(), rel.end());
    MESSAGE(name(test), ": ", rel.size(), " hits, relative t error of double vs long double: median ",
            rel[rel.size() / 2], ", max ", rel.back(), "; float t not the rounded long-double t: ", rounded_off);
    CHECK(rel[rel.size() / 2] < 1e-15);
    CHECK(rel.back() < 1e-13);
  }
}

TEST_CASE("reference: commit refuses a SIMD ISA and robust = false, and leaves the Accel as it was") {
  const Soup soup = random_soup(100, 5);
  Accel accel = soup.accel(Options{TriangleTest::watertight, Isa::scalar});
  const Ray ray = ordinary_rays(1, 9)[0];
  const Hit before = accel.intersect(ray);
  for (Isa isa : simd_isas()) {
    CAPTURE(std::string(volley::to_string(isa)));
    CHECK_THROWS_WITH_AS(accel.commit(Options{TriangleTest::watertight, isa, true, true}),
                         doctest::Contains("reference_double"), volley::Error);
  }
  CHECK_THROWS_WITH_AS(accel.commit(Options{TriangleTest::watertight, Isa::scalar, false, true}),
                       doctest::Contains("robust"), volley::Error);
  CHECK(agree(accel.intersect(ray), before));
  CHECK(!accel.info().reference_double);
}

TEST_CASE("reference: volley trace --reference and info --reference, end to end") {
  namespace fs = std::filesystem;
  using volley::test::run;
  const std::string scene = std::string(VOLLEY_SOURCE_DIR) + "/scenes/cornell.json";
  const fs::path dir = fs::temp_directory_path() / "volley_reference_test";
  fs::create_directories(dir);
  const std::string rays = (dir / "primary.vray").string();
  REQUIRE(run("rays " + scene + " --workload primary --width 32 --height 24 -o " + rays).status == 0);

  std::map<std::string, std::string> hits;
  for (const std::string flags : {"", " --reference", " --reference --isa scalar", " --fast-slabs"}) {
    CAPTURE(flags);
    const volley::test::Run r = run("trace " + scene + " --rays " + rays + " --reps 1" + flags);
    REQUIRE(r.status == 0);
    std::smatch m;
    REQUIRE(std::regex_search(r.output, m, std::regex(R"(hits=(\d+) robust=(\d) reference=(\d))")));
    const bool reference = flags.find("--reference") != std::string::npos;
    CHECK(m[2] == (flags.find("--fast-slabs") != std::string::npos ? "0" : "1"));
    CHECK(m[3] == (reference ? "1" : "0"));
    if (reference) CHECK(r.output.find("isa=scalar") != std::string::npos);
    hits[flags] = m[1];
  }
  // A closed box seen from inside: every primary ray hits, in every configuration.
  CHECK(hits[""] == hits[" --reference"]);
  CHECK(hits[""] == hits[" --fast-slabs"]);

  const volley::test::Run info = run("info " + scene + " --reference");
  CHECK(info.status == 0);
  CHECK(info.output.find("double triangle tests") != std::string::npos);

  const volley::test::Run simd = run("trace " + scene + " --rays " + rays + " --reference --isa avx2");
  CHECK(simd.status != 0);
  CHECK(simd.output.find("--reference") != std::string::npos);
  CHECK(run("trace " + scene + " --rays " + rays + " --reference --fast-slabs").status != 0);
  CHECK(run("render --help").output.find("--fast-slabs") != std::string::npos);
  CHECK(run("render --help").output.find("--reference") != std::string::npos);
}
