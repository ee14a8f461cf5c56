// The conventions every subcommand shares (README "Exit status"): 2 and `volley: error:`
// for a usage error, 1 for a runtime error, --threads 0 for all cores, PNG output only.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>

#include "cli/cli_run.h"

namespace fs = std::filesystem;
using namespace volley::test;

TEST_CASE("cli conventions: argument errors exit with 2 and the volley: error: prefix") {
  const char* usage_errors[] = {
      "",                                       // no subcommand
      "render",                                 // the scene is required
      "render scenes/cornell.json --spp 0",     // out of range
      "render scenes/cornell.json --isa mmx",   // not a choice
      "render scenes/cornell.json --no-such",   // unknown option
      "trace scenes/cornell.json --threads -1", // negative thread count
      "frobnicate",                             // unknown subcommand
  };
  for (const char* args : usage_errors) {
    CAPTURE(args);
    const Run r = run(args);
    CHECK(r.status == 2);
    CHECK(has(r.output, "volley: error: "));
    CHECK(has(r.output, "--help"));
  }
}

TEST_CASE("cli conventions: options that do not go together are a usage error") {
  const fs::path rays = temp_path("conventions.vray");
  REQUIRE(run("rays " + kCornell + " --workload primary --width 8 --height 8 -o " + rays.string()).status == 0);
  const Run r = run("trace " + kCornell + " --rays " + rays.string() + " --all --mode packet");
  CHECK(r.status == 2);
  CHECK(has(r.output, "volley: error: --all traces single rays"));
  const Run ref = run("trace " + kCornell + " --rays " + rays.string() + " --reference --isa sse4.2");
  CHECK(ref.status == 2);
  CHECK(has(ref.output, "volley: error: --reference"));
}

TEST_CASE("cli conventions: runtime errors exit with 1") {
  const Run missing = run("render /nonexistent/scene.json");
  CHECK(missing.status == 1);
  CHECK(has(missing.output, "volley: error: /nonexistent/scene.json: file not found"));
  const Run dir = run("render " + fs::temp_directory_path().string());
  CHECK(dir.status == 1);
  CHECK(has(dir.output, "is a directory, expected a scene file (.json) or a mesh (.obj, .ply)"));
  CHECK(!has(dir.output, "unknown scene file type"));
}

TEST_CASE("cli conventions: render writes PNG only and refuses another extension before rendering") {
  for (const char* name : {"x.jpg", "x.jpeg", "x", "x.png.tmp"}) {
    const fs::path out = temp_path(name);
    fs::remove(out);
    CAPTURE(name);
    const Run r = run("render " + kCornell + " --width 8 --height 8 -o " + out.string());
    CHECK(r.status == 2);
    CHECK(has(r.output, "PNG"));
    CHECK(!fs::exists(out));
  }
  const fs::path upper = temp_path("upper.PNG");
  CHECK(run("render " + kCornell + " --width 8 --height 8 -o " + upper.string()).status == 0);
  CHECK(fs::exists(upper));
}

TEST_CASE("cli conventions: --threads 0 means all cores in every subcommand, as in the APIs") {
  const fs::path png = temp_path("threads0.png"), rays = temp_path("threads0.vray");
  const Run render = run("render " + kCornell + " --width 8 --height 8 --threads 0 -o " + png.string());
  CHECK(render.status == 0);
  REQUIRE(run("rays " + kCornell + " --workload primary --width 8 --height 8 --threads 0 -o " + rays.string()).status ==
          0);
  const Run trace = run("trace " + kCornell + " --rays " + rays.string() + " --threads 0 --reps 1");
  CHECK(trace.status == 0);
  const Run help = run("trace --help");
  CHECK(has(help.output, "0 (the default) for all cores"));
}
