// `volley points`, `volley query` and `volley trace --count / --all` end to end: the files
// they write hold the answers the API gives, the summary lines parse, and bad input is
// refused with a message that names it.
#include <doctest/doctest.h>

#include "cli/cli_run.h"

#include <cmath>
#include <string>
#include <vector>

#include "io/query_files.h"
#include "io/ray_file.h"
#include "volley/accel.h"

namespace fs = std::filesystem;
using namespace volley;
using test::has;
using test::Run;
using test::run;
using test::temp_file;
using test::temp_path;
using test::trace_line;

namespace {

// A closed box [0, 2]^3 (12 triangles) seen from the front.
const std::string kBox = R"({"camera": {"eye": [1, 1, 8], "look_at": [1, 1, 1], "fov": 40},
  "objects": [{"type": "triangles",
    "vertices": [[0,0,0],[2,0,0],[2,2,0],[0,2,0],[0,0,2],[2,0,2],[2,2,2],[0,2,2]],
    "indices": [[0,2,1],[0,3,2],[4,5,6],[4,6,7],[0,1,5],[0,5,4],[1,2,6],[1,6,5],[2,3,7],[2,7,6],[3,0,4],[3,4,7]]}]})";

}  // namespace

TEST_CASE("cli query: points, then contains, distances and closest points written as the API answers them") {
  const fs::path scene = temp_file("box.json", kBox);
  const fs::path pts = temp_path("box.vpts");
  Run r = run("points " + scene.string() + " -n 500 --near 0.3 --seed 4 -o " + pts.string());
  REQUIRE(r.status == 0);
  const std::vector<float> xyz = io::read_points(pts);
  REQUIRE(xyz.size() == 1500);
  std::size_t inside_box = 0;
  for (std::size_t i = 0; i < 500; ++i) {
    bool in = true;
    for (int a = 0; a < 3; ++a) in = in && xyz[3 * i + a] > 0.0f && xyz[3 * i + a] < 2.0f;
    inside_box += in;
  }
  const fs::path occ = temp_path("box.vocc"), dst = temp_path("box.vdst"), sdf = temp_path("box.sdf.vdst"),
                 clp = temp_path("box.vclp");
  r = run("query " + scene.string() + " --points " + pts.string() + " --op contains --threads 2 --reps 1 -o " + occ.string());
  REQUIRE(r.status == 0);
  CHECK(!has(r.output, "warning"));  // closed and consistently oriented
  auto kv = trace_line(r.output, "query");
  CHECK(kv["op"] == "contains");
  CHECK(kv["points"] == "500");
  CHECK(std::stoul(kv["inside"]) == inside_box);
  const std::vector<std::uint8_t> inside = io::read_occupancy(occ);
  REQUIRE(inside.size() == 500);
  REQUIRE(run("query " + scene.string() + " --points " + pts.string() + " --op distance --reps 1 -o " + dst.string()).status == 0);
  REQUIRE(run("query " + scene.string() + " --points " + pts.string() + " --op signed-distance --reps 1 -o " + sdf.string()).status == 0);
  r = run("query " + scene.string() + " --points " + pts.string() + " --op closest --max-distance 0.5 --reps 1 -o " + clp.string());
  REQUIRE(r.status == 0);
  const std::vector<float> d = io::read_distances(dst), sd = io::read_distances(sdf);
  const std::vector<io::ClosestRecord> c = io::read_closest(clp);
  REQUIRE(d.size() == 500);
  REQUIRE(c.size() == 500);
  for (std::size_t i = 0; i < 500; ++i) {
    // Distance to the box surface, by hand.
    const float* p = &xyz[3 * i];
    float out2 = 0.0f, in = INFINITY;
    for (int a = 0; a < 3; ++a) {
      const float e = std::max({0.0f - p[a], p[a] - 2.0f, 0.0f});
      out2 += e * e;
      in = std::min({in, p[a], 2.0f - p[a]});
    }
    const float want = inside[i] ? in : std::sqrt(out2);
    CHECK(std::abs(d[i] - want) <= 1e-5f);
    CHECK(sd[i] == (inside[i] ? -d[i] : d[i]));
    if (d[i] < 0.5f) {
      CHECK(c[i].geometry == 0);
      CHECK(c[i].primitive < 12);
    } else {
      CHECK(c[i].primitive == kInvalidPrim);
      CHECK(std::isinf(c[i].x));
    }
  }
}

TEST_CASE("cli trace --count / --all: crossings per ray and hit lists, one per crossing") {
  const fs::path scene = temp_file("box2.json", kBox);
  // Rays straight through the box along z at half-integer x, y: through its vertices, edges
  // and face diagonals. Inside ones cross twice; others graze and cross an even number.
  std::vector<Ray> rays;
  for (int i = 0; i <= 4; ++i)
    for (int j = 0; j <= 4; ++j) rays.push_back(Ray{{0.5f * i, 0.5f * j, -1.0f}, 0.0f, {0, 0, 1}, INFINITY});
  const fs::path vray = temp_path("box2.vray"), cnt = temp_path("box2.vcnt"), all = temp_path("box2.vall");
  io::write_rays(vray, rays);
  Run r = run("trace " + scene.string() + " --rays " + vray.string() + " --count --reps 1 -o " + cnt.string());
  REQUIRE(r.status == 0);
  CHECK(trace_line(r.output)["query"] == "count");
  REQUIRE(run("trace " + scene.string() + " --rays " + vray.string() + " --all --reps 1 --threads 2 -o " + all.string()).status == 0);
  const std::vector<std::uint32_t> counts = io::read_counts(cnt);
  const HitLists lists = io::read_hit_lists(all);
  REQUIRE(counts.size() == rays.size());
  REQUIRE(lists.offsets.size() == rays.size() + 1);
  for (std::size_t k = 0; k < rays.size(); ++k) {
    const int i = int(k) / 5, j = int(k) % 5;
    const bool interior = i > 0 && i < 4 && j > 0 && j < 4;
    INFO("ray " << k);
    if (interior) CHECK(counts[k] == 2);
    else CHECK(counts[k] % 2 == 0);
    REQUIRE(lists.offsets[k + 1] - lists.offsets[k] == counts[k]);
    if (interior) {
      CHECK(lists.hits[lists.offsets[k]].t == 1.0f);
      CHECK(lists.hits[lists.offsets[k] + 1].t == 3.0f);
    }
  }
}

TEST_CASE("cli query: bad input names the file or option") {
  const fs::path scene = temp_file("box3.json", kBox);
  const fs::path rays = temp_file("not_points.vpts", "VRAY\x01\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00");
  Run r = run("query " + scene.string() + " --points " + rays.string() + " --op contains");
  CHECK(r.status == 1);
  CHECK(has(r.output, "not_points.vpts"));
  CHECK(has(r.output, "VPTS"));
  const fs::path pts = temp_path("box3.vpts");
  REQUIRE(run("points " + scene.string() + " -n 10 -o " + pts.string()).status == 0);
  r = run("query " + scene.string() + " --points " + pts.string() + " --op volume");
  CHECK(r.status != 0);
  CHECK(r.status < 128);
  CHECK(has(r.output, "--op"));
  r = run("query " + scene.string() + " --points " + pts.string() + " --op closest --test plane");
  CHECK(r.status == 1);
  CHECK(has(r.output, "plane test"));
  r = run("trace " + scene.string() + " --rays " + pts.string() + " --count");
  CHECK(r.status == 1);
  CHECK(has(r.output, "VRAY"));
  // An open surface: contains warns that its answer is one ray's parity.
  const fs::path open = temp_file("open.json", R"({"objects": [{"type": "triangles",
    "vertices": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,2]]}]})");
  r = run("query " + open.string() + " --points " + pts.string() + " --op contains --reps 1");
  CHECK(r.status == 0);
  CHECK(has(r.output, "warning"));
  CHECK(has(r.output, "not a closed"));
}
