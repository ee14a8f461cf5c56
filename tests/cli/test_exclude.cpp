// `volley rays --origins --no-offset` and `volley trace --exclude` end to end: secondary rays
// that start on the hit points themselves, traced with the primitive each leaves excluded,
// never meet it again (without the exclusion many do), in every mode that has the form,
// with the same answers in each; bad pairs refused with a message that names them.
#include <doctest/doctest.h>

#include "cli/cli_run.h"

#include <filesystem>
#include <string>
#include <vector>

#include "io/ray_file.h"

namespace fs = std::filesystem;
using namespace volley;
using test::has;
using test::kCornell;
using test::Run;
using test::run;
using test::temp_path;
using test::trace_line;

TEST_CASE("trace --exclude: rays from hit points pass over the triangle they leave, in every form") {
  const fs::path rays = temp_path("exclude_diffuse.vray"), origins = temp_path("exclude_origins.vhit");
  const Run made = run("rays " + kCornell + " --workload diffuse --no-offset --width 48 --height 36 -o " +
                       rays.string() + " --origins " + origins.string());
  REQUIRE(made.status == 0);
  CHECK(has(made.output, origins.string()));
  const std::vector<Hit> from = io::read_hits(origins);
  REQUIRE(from.size() == io::read_rays(rays).size());
  REQUIRE(from.size() > 500);

  const fs::path plain = temp_path("exclude_plain.vhit");
  REQUIRE(run("trace " + kCornell + " --rays " + rays.string() + " --reps 1 -o " + plain.string()).status == 0);
  std::size_t self_hits = 0;
  for (std::size_t i = 0; const Hit& h : io::read_hits(plain)) {
    self_hits += h.prim == from[i].prim && h.geom == from[i].geom;
    ++i;
  }
  CHECK(self_hits > from.size() / 20);  // without the exclusion, rays on the surface meet it again

  std::string reference;
  for (const std::string mode : {"single", "stream", "batch"})
    for (const bool occluded : {false, true}) {
      CAPTURE(mode);
      CAPTURE(occluded);
      const fs::path out = temp_path("exclude_" + mode + (occluded ? "_occ" : "") + ".vhit");
      const Run r = run("trace " + kCornell + " --rays " + rays.string() + " --exclude " + origins.string() +
                        " --mode " + mode + " --threads 2 --reps 1 -o " + out.string() + (occluded ? " --occluded" : ""));
      REQUIRE(r.status == 0);
      CHECK(trace_line(r.output)["exclude"] == origins.string());
      const std::vector<Hit> hits = io::read_hits(out);
      REQUIRE(hits.size() == from.size());
      if (occluded) continue;
      for (std::size_t i = 0; i < hits.size(); ++i)
        if (hits[i].prim == from[i].prim && hits[i].geom == from[i].geom) FAIL_CHECK("ray " << i << " met its own triangle");
      if (reference.empty()) reference = test::bytes_of(out);
      CHECK(test::bytes_of(out) == reference);
    }
  CHECK(trace_line(run("trace " + kCornell + " --rays " + rays.string() + " --reps 1").output)["exclude"] == "none");
}

TEST_CASE("trace --exclude: the wrong count, a packet mode or a crossing query is refused by name") {
  const fs::path rays = temp_path("exclude_primary.vray"), origins = temp_path("exclude_primary.vhit");
  REQUIRE(run("rays " + kCornell + " --workload primary --width 16 --height 16 -o " + rays.string() + " --origins " +
              origins.string())
              .status == 0);
  const fs::path other = temp_path("exclude_other.vray");
  REQUIRE(run("rays " + kCornell + " --workload primary --width 8 --height 8 -o " + other.string()).status == 0);
  const Run wrong = run("trace " + kCornell + " --rays " + other.string() + " --exclude " + origins.string());
  CHECK(wrong.status == 2);
  CHECK(has(wrong.output, "256 hits for 64 rays"));
  for (const std::string extra : {" --mode packet", " --count", " --stats"}) {
    const Run r = run("trace " + kCornell + " --rays " + rays.string() + " --exclude " + origins.string() + extra);
    CAPTURE(extra);
    CHECK(r.status == 2);
    CHECK(has(r.output, "--exclude"));
  }
  // Primary rays leave no surface: their origins are misses, and exclude nothing.
  const Run ok = run("trace " + kCornell + " --rays " + rays.string() + " --exclude " + origins.string() + " --reps 1");
  CHECK(ok.status == 0);
  CHECK(trace_line(ok.output)["hits"] == trace_line(run("trace " + kCornell + " --rays " + rays.string() +
                                                         " --reps 1").output)["hits"]);
}
