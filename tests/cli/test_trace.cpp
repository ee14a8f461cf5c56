// `volley trace` end to end on `volley rays` files: every trace mode giving the same
// answers; the parseable summary line; the query and structure options; bad input refused
// with a message that names it. The workloads themselves: test_workloads.cpp.
#include <doctest/doctest.h>

#include "cli/cli_run.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include "io/ray_file.h"

namespace fs = std::filesystem;
using namespace volley;
using namespace volley::test;

TEST_CASE("trace: every mode and thread count gives the same answers, and the line parses") {
  const fs::path primary = temp_path("trace_primary.vray"), shadow = temp_path("trace_shadow.vray");
  REQUIRE(run("rays " + kCornell + " --workload primary --width 40 --height 30 -o " + primary.string()).status == 0);
  REQUIRE(run("rays " + kCornell + " --workload shadow --width 40 --height 30 -o " + shadow.string()).status == 0);

  for (const bool occluded : {false, true}) {
    const fs::path& rays = occluded ? shadow : primary;
    const std::size_t count = io::read_rays(rays).size();
    std::vector<Hit> reference;
    for (const std::string mode :
         {"single", "packet --packet 16", "packet --packet 8", "packet --packet 4", "stream", "batch"}) {
      for (const int threads : {1, 2}) {
        CAPTURE(mode);
        CAPTURE(threads);
        CAPTURE(occluded);
        const fs::path hits = temp_path("trace.vhit");
        fs::remove(hits);
        const Run r = run("trace " + kCornell + " --rays " + rays.string() + " --mode " + mode + " --threads " +
                          std::to_string(threads) + " --reps 2 -o " + hits.string() + (occluded ? " --occluded" : ""));
        REQUIRE(r.status == 0);
        auto kv = trace_line(r.output);
        CHECK(kv["scene"] == kCornell);
        CHECK(kv["rays"] == std::to_string(count));
        CHECK(kv["mode"] == mode.substr(0, mode.find(' ')));
        CHECK(kv["packet"] == (kv["mode"] == "packet" ? mode.substr(mode.rfind(' ') + 1) : "0"));
        CHECK(kv["test"] == "watertight");
        CHECK(kv["threads"] == std::to_string(threads));
        CHECK(kv["occluded"] == (occluded ? "1" : "0"));
        CHECK(kv["reps"] == "2");
        CHECK(std::stod(kv["best_s"]) <= std::stod(kv["median_s"]));
        CHECK(std::stod(kv["Mrays/s"]) > 0.0);
        for (const char* key : {"isa", "hits"}) CHECK(kv.count(key) == 1);

        const std::vector<Hit> answers = io::read_hits(hits);
        REQUIRE(answers.size() == count);
        std::size_t hit_count = 0;
        for (const Hit& h : answers) {
          hit_count += h.hit();
          if (occluded) CHECK((h.t == 0.0f) == h.hit());
        }
        CHECK(kv["hits"] == std::to_string(hit_count));
        if (reference.empty()) {
          reference = answers;
          CHECK(hit_count > 0);
          continue;
        }
        std::size_t differ = 0;
        for (std::size_t i = 0; i < count; ++i)
          differ += answers[i].prim != reference[i].prim ||
                    std::abs(answers[i].t - reference[i].t) > 1e-6f * std::abs(reference[i].t);
        CHECK(differ == 0);
      }
    }
  }
}

TEST_CASE("trace --count on the stream API and --normals: the same answers as single rays, bad pairs refused") {
  const std::string& scene = kCornell;
  const fs::path rays = temp_path("count_modes.vray");
  REQUIRE(run("rays " + scene + " --workload diffuse --width 40 --height 30 -o " + rays.string()).status == 0);
  const fs::path single = temp_path("count_single.vcnt");
  REQUIRE(run("trace " + scene + " --rays " + rays.string() + " --count --reps 1 -o " + single.string()).status == 0);
  for (const std::string mode : {"stream", "batch"}) {
    for (const int threads : {1, 2}) {
      CAPTURE(mode);
      CAPTURE(threads);
      const fs::path counts = temp_path("count_" + mode + ".vcnt");
      const Run r = run("trace " + scene + " --rays " + rays.string() + " --count --reps 1 --mode " + mode + " --threads " +
                        std::to_string(threads) + " -o " + counts.string());
      REQUIRE(r.status == 0);
      CHECK(trace_line(r.output)["query"] == "count");
      CHECK(bytes_of(counts) == bytes_of(single));
    }
  }
  // --normals: timed beside the hits, which stay the same; the line says so.
  const fs::path plain = temp_path("normals_off.vhit"), with = temp_path("normals_on.vhit");
  Run r = run("trace " + scene + " --rays " + rays.string() + " --mode stream --reps 1 -o " + plain.string());
  REQUIRE(r.status == 0);
  CHECK(trace_line(r.output)["normals"] == "0");
  r = run("trace " + scene + " --rays " + rays.string() + " --mode stream --reps 1 --normals -o " + with.string());
  REQUIRE(r.status == 0);
  CHECK(trace_line(r.output)["normals"] == "1");
  CHECK(bytes_of(plain) == bytes_of(with));

  r = run("trace " + scene + " --rays " + rays.string() + " --count --mode packet");
  CHECK(r.status == 2);  // a usage error
  CHECK(has(r.output, "--count has no packet form"));
  r = run("trace " + scene + " --rays " + rays.string() + " --all --mode stream");
  CHECK(r.status == 2);  // a usage error
  CHECK(has(r.output, "--all traces single rays"));
  r = run("trace " + scene + " --rays " + rays.string() + " --count --mask 1 --mode batch");
  CHECK(r.status == 2);  // a usage error
  CHECK(has(r.output, "--count with --mask traces single rays"));
  CHECK(run("trace " + scene + " --rays " + rays.string() + " --normals --occluded").status != 0);
  CHECK(run("trace " + scene + " --rays " + rays.string() + " --normals --count").status != 0);
}

TEST_CASE("trace --stats: the walk's visits per ray, refused where the walk cannot count") {
  const fs::path primary = temp_path("stats_primary.vray");
  REQUIRE(run("rays " + kCornell + " --workload primary --width 20 --height 20 -o " + primary.string()).status == 0);
  for (const char* query : {"", " --occluded"}) {
    CAPTURE(query);
    const Run r = run("trace " + kCornell + " --rays " + primary.string() + " --reps 1 --stats" + query);
    REQUIRE(r.status == 0);
    std::smatch m;
    REQUIRE(std::regex_search(r.output, m, std::regex(R"(walk: nodes/ray=([0-9.]+) leaves/ray=([0-9.]+) triangles/ray=([0-9.]+))")));
    CHECK(std::stod(m[1]) > 0.0);
    CHECK(std::stod(m[2]) > 0.0);
    CHECK(std::stod(m[3]) >= std::stod(m[2]));  // a leaf holds a triangle at least
  }
  const Run scalar = run("trace " + kCornell + " --rays " + primary.string() + " --reps 1 --stats --isa scalar");
  CHECK(scalar.status == 1);
  CHECK(has(scalar.output, "walk_counts: only for"));
  const Run crossing = run("trace " + kCornell + " --rays " + primary.string() + " --reps 1 --stats --count");
  CHECK(crossing.status == 2);  // a usage error
  CHECK(has(crossing.output, "--stats counts the closest-hit or occlusion walk"));
}

TEST_CASE("trace and rays: bad input gives a clear message and a non-zero exit") {
  const fs::path rays = temp_path("ok.vray");
  REQUIRE(run("rays " + kCornell + " --workload primary --width 8 --height 8 -o " + rays.string()).status == 0);

  Run r = run("trace " + kCornell + " --rays /nonexistent/rays.vray");
  CHECK(r.status != 0);
  CHECK(has(r.output, "/nonexistent/rays.vray: file not found"));

  const fs::path text = temp_file("text.vray", "this is not a ray file");
  r = run("trace " + kCornell + " --rays " + text.string());
  CHECK(r.status != 0);
  CHECK(has(r.output, "text.vray: not a ray file"));

  const fs::path hits = temp_path("some.vhit");
  REQUIRE(run("trace " + kCornell + " --rays " + rays.string() + " --reps 1 -o " + hits.string()).status == 0);
  r = run("trace " + kCornell + " --rays " + hits.string());
  CHECK(r.status != 0);
  CHECK(has(r.output, "this is a hit file"));

  const std::string good = bytes_of(rays);
  const fs::path cut = temp_file("cut.vray", good.substr(0, good.size() - 7));
  r = run("trace " + kCornell + " --rays " + cut.string());
  CHECK(r.status != 0);
  CHECK(has(r.output, "cut.vray: truncated"));

  CHECK(run("trace " + kCornell + " --rays " + rays.string() + " --mode warp").status != 0);
  CHECK(run("trace " + kCornell + " --rays " + rays.string() + " --mode packet --packet 32").status != 0);
  CHECK(run("trace " + kCornell + " --rays " + rays.string() + " --reps 0").status != 0);
  CHECK(run("trace " + kCornell).status != 0);  // --rays is required
  r = run("trace /nonexistent/scene.json --rays " + rays.string());
  CHECK(r.status != 0);
  CHECK(has(r.output, "/nonexistent/scene.json"));

  CHECK(run("rays " + kCornell + " --workload bounce -o " + temp_path("x.vray").string()).status != 0);
  CHECK(run("rays " + kCornell + " --workload primary").status != 0);  // -o is required
  // A scene with a camera but no light has no shadow workload.
  const fs::path dark = temp_file("dark.json", R"({"camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0]},
    "objects": [{"type": "triangles", "vertices": [[-1,-1,0],[1,-1,0],[0,1,0]], "indices": [[0,1,2]]}]})");
  r = run("rays " + dark.string() + " --workload shadow -o " + temp_path("dark.vray").string());
  CHECK(r.status != 0);
  CHECK(has(r.output, "no light"));
}

TEST_CASE("trace --quality high: the same hit and crossing files as medium, info names it, a bad name is refused") {
  const std::string& scene = kCornell;
  const fs::path rays = temp_path("quality.vray");
  REQUIRE(run("rays " + scene + " --workload diffuse --width 40 --height 30 -o " + rays.string()).status == 0);
  for (const std::string query : {"", " --occluded", " --count"}) {
    CAPTURE(query);
    const fs::path medium = temp_path("medium.out"), high = temp_path("high.out");
    REQUIRE(run("trace " + scene + " --rays " + rays.string() + query + " --reps 1 -o " + medium.string()).status == 0);
    REQUIRE(run("trace " + scene + " --rays " + rays.string() + query + " --reps 1 --quality high -o " +
                high.string()).status == 0);
    CHECK(bytes_of(medium) == bytes_of(high));
  }
  Run r = run("info " + scene + " --quality high");
  REQUIRE(r.status == 0);
  CHECK(has(r.output, "high quality"));
  CHECK(has(r.output, "triangle references in the leaves"));
  r = run("trace " + scene + " --rays " + rays.string() + " --quality low");
  CHECK(r.status != 0);
  CHECK(r.status < 128);
  CHECK(has(r.output, "--quality"));
}

TEST_CASE("trace --save / --load: the loaded structure gives the same hit file, a wrong file is named") {
  const fs::path rays = temp_path("saveload.vray"), saved = temp_path("cornell.vacc");
  const fs::path built_hits = temp_path("built.vhit"), loaded_hits = temp_path("loaded.vhit");
  REQUIRE(run("rays " + kCornell + " --workload primary --width 40 --height 30 -o " + rays.string()).status == 0);
  Run r = run("trace " + kCornell + " --rays " + rays.string() + " --reps 1 --save " + saved.string() + " -o " +
              built_hits.string());
  REQUIRE(r.status == 0);
  CHECK(has(r.output, "saved the structure to " + saved.string()));
  CHECK(has(r.output, "BVH built in"));
  r = run("trace " + kCornell + " --rays " + rays.string() + " --reps 1 --load " + saved.string() + " -o " +
          loaded_hits.string());
  REQUIRE(r.status == 0);
  CHECK(has(r.output, "BVH loaded in"));
  CHECK(bytes_of(built_hits) == bytes_of(loaded_hits));

  // Saved from another scene: the counts differ, and the message says so.
  r = run("trace " + std::string(VOLLEY_SOURCE_DIR) + "/scenes/polygons.json --rays " + rays.string() + " --load " +
          saved.string());
  CHECK(r.status != 0);
  CHECK(r.status < 128);
  CHECK(has(r.output, "it was saved from another scene"));
  // Not a structure file, and a corrupted one.
  r = run("trace " + kCornell + " --rays " + rays.string() + " --load " + rays.string());
  CHECK(r.status != 0);
  CHECK(has(r.output, "not a volley structure file"));
  std::string bytes = bytes_of(saved);
  bytes[bytes.size() / 2] ^= 1;
  const fs::path corrupted = temp_file("corrupted.vacc", bytes);
  r = run("trace " + kCornell + " --rays " + rays.string() + " --load " + corrupted.string());
  CHECK(r.status != 0);
  CHECK(has(r.output, "corrupted.vacc: checksum mismatch"));
  CHECK(run("trace " + kCornell + " --rays " + rays.string() + " --load /nonexistent/x.vacc").status != 0);
}

TEST_CASE("trace --mask: rays see the objects whose \"mask\" shares a bit with theirs") {
  const fs::path scene = temp_file("masked.json", R"({"camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0], "fov": 60},
    "objects": [
      {"type": "triangles", "name": "front", "mask": 1, "vertices": [[-1,-1,1],[1,-1,1],[0,1,1]], "indices": [[0,1,2]]},
      {"type": "triangles", "name": "back", "mask": 2, "vertices": [[-2,-2,0],[2,-2,0],[0,2,0]], "indices": [[0,1,2]]},
      {"type": "polygon", "name": "hidden", "mask": 0, "vertices": [[-3,-3,2],[3,-3,2],[3,3,2],[-3,3,2]]}]})");
  const fs::path rays = temp_path("masked.vray");
  REQUIRE(run("rays " + scene.string() + " --workload primary --width 32 --height 32 -o " + rays.string()).status == 0);
  std::map<std::string, std::size_t> hits;
  for (const std::string mode : {"single", "packet", "stream"})
    for (const std::string mask : {"", "1", "2", "4", "3"}) {
      const Run r = run("trace " + scene.string() + " --rays " + rays.string() + " --reps 1 --mode " + mode +
                        (mask.empty() ? "" : " --mask " + mask));
      REQUIRE(r.status == 0);
      auto kv = trace_line(r.output);
      CHECK(kv["mask"] == (mask.empty() ? "none" : mask));
      const std::size_t n = std::stoul(kv["hits"]);
      if (mode != "single") CHECK(n == hits[mask]);  // every mode the same
      hits[mask] = n;
    }
  // The hidden polygon (mask 0) covers everything and is never hit; "back" covers "front".
  CHECK(hits["1"] > 0);
  CHECK(hits["1"] < hits["2"]);
  CHECK(hits["2"] == hits[""]);
  CHECK(hits["3"] == hits[""]);
  CHECK(hits["4"] == 0);
  const Run info = run("info " + scene.string());
  CHECK(has(info.output, "2 distinct object masks"));
  CHECK(run("trace " + scene.string() + " --rays " + rays.string() + " --mask 4294967296").status != 0);
  const fs::path bad = temp_file("badmask.json", R"({"objects": [{"type": "triangles", "mask": -1,
    "vertices": [[0,0,0],[1,0,0],[0,1,0]], "indices": [[0,1,2]]}]})");
  const Run r = run("info " + bad.string());
  CHECK(r.status != 0);
  CHECK(has(r.output, "mask"));
}

TEST_CASE("instance objects: the same hits as the object placed by hand, bad \"of\" names the problem") {
  // A square of two triangles, hidden itself (mask 0), placed twice; and the same two
  // placements written out as plain objects.
  const std::string square = R"("vertices": [[-1,-1,0],[1,-1,0],[1,1,0],[-1,1,0]], "indices": [[0,1,2],[0,2,3]])";
  const std::string place1 = R"({"translate": [0.5, 0, -1]})";
  const std::string place2 = R"({"scale": [-2, 1, 1], "rotate": {"axis": [0, 0, 1], "degrees": 30}, "translate": [0, 0.5, -3]})";
  const std::string camera = R"("camera": {"eye": [0, 0, 5], "look_at": [0, 0, 0], "fov": 60})";
  const fs::path instanced = temp_file("instanced.json", "{" + camera + R"(, "objects": [
      {"type": "triangles", "name": "sq", "mask": 0, )" + square + R"(},
      {"type": "instance", "of": "sq", "transform": )" + place1 + R"(},
      {"type": "instance", "of": "sq", "transform": )" + place2 + "}]}");
  const fs::path flat = temp_file("flat.json", "{" + camera + R"(, "objects": [
      {"type": "triangles", "name": "sq", "mask": 0, )" + square + R"(},
      {"type": "triangles", "transform": )" + place1 + ", " + square + R"(},
      {"type": "triangles", "transform": )" + place2 + ", " + square + "}]}");
  const fs::path rays = temp_path("instanced.vray");
  REQUIRE(run("rays " + flat.string() + " --workload primary --width 48 --height 48 -o " + rays.string()).status == 0);
  const fs::path a = temp_path("instanced.vhit"), b = temp_path("flat.vhit");
  for (const std::string mode : {"single", "packet", "stream"}) {
    CAPTURE(mode);
    REQUIRE(run("trace " + instanced.string() + " --rays " + rays.string() + " --reps 1 --mode " + mode + " -o " +
                a.string()).status == 0);
    REQUIRE(run("trace " + flat.string() + " --rays " + rays.string() + " --reps 1 -o " + b.string()).status == 0);
    const std::vector<Hit> through = io::read_hits(a), placed = io::read_hits(b);
    REQUIRE(through.size() == placed.size());
    std::size_t hits = 0, differ = 0;
    for (std::size_t i = 0; i < through.size(); ++i) {
      hits += through[i].hit();
      differ += through[i].hit() != placed[i].hit() ||
                (through[i].hit() && (through[i].inst != placed[i].geom || through[i].geom != 0 ||
                                      std::abs(through[i].t - placed[i].t) > 1e-5f * placed[i].t));
    }
    CHECK(hits > through.size() / 10);
    CHECK(differ == 0);
  }
  const Run info = run("info " + instanced.string());
  CHECK(has(info.output, "instances   2 (4 triangles through them"));
  // A render through instances works (shading reads the instance's transform).
  CHECK(run("render " + instanced.string() + " --width 32 --height 32 -o " + temp_path("instanced.png").string())
            .status == 0);

  const fs::path bad = temp_file("badof.json", R"({"objects": [
      {"type": "polygon", "name": "p", "vertices": [[0,0,0],[1,0,0],[0,1,0]]},
      {"type": "instance", "of": "p"}]})");
  Run r = run("info " + bad.string());
  CHECK(r.status != 0);
  CHECK(r.status < 128);
  CHECK(has(r.output, "objects[1].of: no mesh or triangles object named \"p\""));
  const fs::path singular = temp_file("singular.json", R"({"objects": [
      {"type": "triangles", "name": "t", "vertices": [[0,0,0],[1,0,0],[0,1,0]]},
      {"type": "instance", "of": "t", "transform": {"scale": [1, 1, 0]}}]})");
  r = run("info " + singular.string());
  CHECK(r.status != 0);
  const fs::path saved = temp_path("instanced.vacc");
  r = run("trace " + instanced.string() + " --rays " + rays.string() + " --reps 1 --save " + saved.string());
  CHECK(r.status != 0);
  CHECK(has(r.output, "instances, which are not saved"));
}
