// volley_vs_embree: volley and Embree 3 side by side on the same triangles and the same
// rays, one thread, alternating A/B repetitions, both rates and their ratio per mode.
//
//   volley_vs_embree SCENE (--rays RAYS.vray | --workload primary|shadow|diffuse)
//                    [--modes single,packet,stream,occluded1,occluded16,occluded_stream]
//                    [--reps N] [--quality medium|high] [--volley-quality medium|high] [--robust] [--coherent]
//                    [--test ...] [--isa ...] [--json OUT.json] [--embree-config STR] [--no-ftz]
//
// Both engines get the scene's merged triangle mesh (triangle i = prim id i; scenes with
// polygons are refused: Embree has no planar-polygon primitive). Every timed pass takes
// AoS rays (the .vray records) and writes AoS answers, as `volley trace` does: each
// engine converts into its own packet layout inside the timed loop. Repetition r runs
// Embree first when r is even, volley first when r is odd, so drift (other processes,
// frequency) falls on both, after one untimed warm-up pass each; best-of and median are
// reported, the ratio from the bests.
// Flush-to-zero / denormals-are-zero are on for both (Embree's requirement) unless --no-ftz.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <xmmintrin.h>

#include "embree_scene.h"
#include "embree_scene_of.h"
#include "count_modes.h"
#include "query_modes.h"
#include "io/load_error.h"
#include "io/ray_file.h"
#include "io/scene_loader.h"
#include "render/scene.h"
#include "render/workloads.h"
#include "volley/accel.h"
#include "volley/packet.h"

namespace volley::bench {
namespace {


struct Args {
  std::string scene;
  std::string rays;
  std::string workload;
  int width = 0, height = 0;
  long long seed = -1;
  std::string modes = "single,packet,stream,occluded1,occluded16,occluded_stream";
  int reps = 10;
  std::string quality = "medium";
  std::string volley_quality = "medium";
  bool robust = false;
  bool coherent = false;
  std::string test = "watertight";
  std::string isa = "auto";
  std::string scenes;
  std::string json;
  std::string embree_config;
  bool no_ftz = false;
  int show_differences = 0;
};

struct Result {
  const Mode* mode = nullptr;
  std::vector<double> embree_s, volley_s;
  Answers embree_answers, volley_answers;
  double agreement = 0.0;       ///< same hit/miss (or blocked/free) answer
  double prim_agreement = 0.0;  ///< same prim among rays both engines hit
  std::size_t embree_hits = 0, volley_hits = 0;
};


double timed(const std::function<void(const std::vector<Ray>&, Answers&)>& pass, const std::vector<Ray>& rays,
             Answers& out) {
  const auto start = std::chrono::steady_clock::now();
  pass(rays, out);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

double best(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::min_element(v.begin(), v.end()); }

double mrays(std::size_t rays, double seconds) { return seconds > 0.0 ? double(rays) / seconds * 1e-6 : 0.0; }

void compare(Result& r) {
  const std::size_t n = r.mode->counting    ? r.volley_answers.counts.size()
                        : r.mode->occlusion ? r.volley_answers.blocked.size()
                                            : r.volley_answers.hits.size();
  std::size_t same = 0, both = 0, same_prim = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (r.mode->counting) {
      same += r.embree_answers.counts[i] == r.volley_answers.counts[i];
      r.embree_hits += r.embree_answers.counts[i];
      r.volley_hits += r.volley_answers.counts[i];
    } else if (r.mode->occlusion) {
      const bool e = r.embree_answers.blocked[i] != 0, v = r.volley_answers.blocked[i] != 0;
      same += e == v;
      r.embree_hits += e;
      r.volley_hits += v;
    } else {
      const Hit& e = r.embree_answers.hits[i];
      const Hit& v = r.volley_answers.hits[i];
      same += e.hit() == v.hit();
      r.embree_hits += e.hit();
      r.volley_hits += v.hit();
      if (e.hit() && v.hit()) {
        ++both;
        same_prim += e.prim == v.prim;
      }
    }
  }
  r.agreement = n ? double(same) / double(n) : 1.0;
  r.prim_agreement = both ? double(same_prim) / double(both) : 1.0;
}

// Prints up to `limit` rays whose answers differ, with each engine's closest hit (for
// occlusion modes too: it shows where the blocker is) and its smallest barycentric, so
// edge cases (min barycentric near 0) are told apart from real disagreements.
void show_differences(const Result& r, const std::vector<Ray>& rays, const Accel& accel, const EmbreeScene& embree,
                      int limit) {
  int shown = 0;
  for (std::size_t i = 0; i < rays.size() && shown < limit; ++i) {
    bool differ;
    if (r.mode->occlusion) {
      differ = r.embree_answers.blocked[i] != r.volley_answers.blocked[i];
    } else {
      const Hit &e = r.embree_answers.hits[i], &v = r.volley_answers.hits[i];
      differ = e.hit() != v.hit() || e.prim != v.prim;
    }
    if (!differ) continue;
    ++shown;
    const Ray& ray = rays[i];
    std::printf("  %s ray %zu: org (%.9g %.9g %.9g) dir (%.9g %.9g %.9g) t [%.9g, %.9g)\n", r.mode->name.c_str(), i,
                ray.org[0], ray.org[1], ray.org[2], ray.dir[0], ray.dir[1], ray.dir[2], ray.tmin, ray.tmax);
    if (r.mode->occlusion)
      std::printf("    blocked: volley %d, embree %d\n", r.volley_answers.blocked[i], r.embree_answers.blocked[i]);
    for (const auto& [name, h] : {std::pair{"volley", accel.intersect(ray)}, std::pair{"embree", embree.intersect(ray)}}) {
      if (h.hit())
        std::printf("    %s closest: prim %u t %.9g u %.9g v %.9g (min barycentric %.3g)\n", name, h.prim, h.t, h.u, h.v,
                    std::min({h.u, h.v, 1.0f - h.u - h.v}));
      else
        std::printf("    %s closest: miss\n", name);
    }
    // What lies just behind the origin: for a secondary ray, the surface it leaves.
    const Ray back{{ray.org[0], ray.org[1], ray.org[2]}, 0.0f, {-ray.dir[0], -ray.dir[1], -ray.dir[2]},
                   std::numeric_limits<float>::infinity()};
    const Hit b = accel.intersect(back);
    if (b.hit()) std::printf("    behind the origin (volley): prim %u at t %.9g\n", b.prim, b.t);
  }
}

std::string json_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out;
}

// --scenes, else $VOLLEY_SCENES, else ../shared/scenes beside the source tree.
std::filesystem::path shared_scenes(const std::string& flag) {
  if (!flag.empty()) return flag;
  if (const char* env = std::getenv("VOLLEY_SCENES"); env && *env) return env;
  return VOLLEY_SHARED_SCENES;
}

int run(const Args& a) {
  const io::SceneDesc desc = io::load_scene(a.scene, shared_scenes(a.scenes));
  if (!desc.polygons.empty())
    throw std::runtime_error(a.scene + ": the scene has " + std::to_string(desc.polygons.size()) +
                             " polygons; Embree gets triangles only, so the comparison needs a triangle-only scene");
  Options options;
  options.test = *parse_triangle_test(a.test);
  options.isa = *parse_isa(a.isa);
  options.quality = *parse_build_quality(a.volley_quality);
  const int width = a.width ? a.width : desc.settings.width;
  const int height = a.height ? a.height : desc.settings.height;
  // The scene's Accel holds exactly the mesh triangles (no polygons), prim id = index.
  const render::Scene scene(desc, width, height, options);
  const Accel& accel = scene.accel();
  const AccelInfo info = accel.info();

  std::vector<Ray> rays;
  std::string source;
  if (!a.rays.empty()) {
    rays = io::read_rays(a.rays);
    source = a.rays;
  } else {
    const std::uint64_t seed = a.seed >= 0 ? std::uint64_t(a.seed) : desc.settings.seed;
    rays = render::make_workload(scene, *render::parse_workload(a.workload), seed);
    source = a.workload + " " + std::to_string(width) + "x" + std::to_string(height);
  }

  EmbreeConfig config;
  config.quality = a.quality == "high" ? RTC_BUILD_QUALITY_HIGH : RTC_BUILD_QUALITY_MEDIUM;
  config.robust = a.robust;
  config.device_config = a.embree_config;
  config.context_filter = a.modes.find("count") != std::string::npos || a.modes.find("all") != std::string::npos;
  const EmbreeScene embree = embree_scene_of(desc, a.scene, config);

  // Flush-to-zero and denormals-are-zero, as Embree asks of every thread that traces
  // (its verbose output warns of a "severe performance impact" otherwise); both engines
  // run under the same MXCSR. MXCSR bit 15 = FTZ, bit 6 = DAZ.
  if (!a.no_ftz) _mm_setcsr(_mm_getcsr() | 0x8040u);

  std::vector<Mode> modes = all_modes(embree, accel, a.coherent);
  add_count_modes(modes, embree, accel, a.coherent);
  std::vector<Result> results;
  std::stringstream wanted(a.modes);
  for (std::string name; std::getline(wanted, name, ',');) {
    const auto m = std::find_if(modes.begin(), modes.end(), [&](const Mode& x) { return x.name == name; });
    if (m == modes.end()) throw std::runtime_error("unknown mode '" + name + "'");
    Result r;
    r.mode = &*m;
    for (Answers* ans : {&r.embree_answers, &r.volley_answers}) {
      if (m->counting) ans->counts.assign(rays.size(), 0);
      else if (m->occlusion) ans->blocked.assign(rays.size(), 0);
      else ans->hits.assign(rays.size(), Hit{});
    }
    results.push_back(std::move(r));
  }

  std::printf("scene %s: %zu triangles, %zu instances (%zu triangles through them); rays %s: %zu; 1 thread, %d "
              "alternating reps, FTZ/DAZ %s\n",
              a.scene.c_str(), info.triangles, info.instances, info.instanced_triangles, source.c_str(), rays.size(),
              a.reps, a.no_ftz ? "off" : "on");
  std::printf("embree %d.%d.%d: build quality %s, scene flags %s, context %s, built in %.3f s\n", RTC_VERSION_MAJOR,
              RTC_VERSION_MINOR, RTC_VERSION_PATCH, to_string(config.quality), config.robust ? "ROBUST" : "NONE",
              a.coherent ? "COHERENT" : "INCOHERENT", embree.build_seconds());
  std::printf("volley: test %s, isa %s, build quality %s, %.1f bytes/triangle, SAH cost %.2f, built in %.3f s\n",
              std::string(to_string(info.test)).c_str(), std::string(to_string(info.isa)).c_str(),
              std::string(to_string(info.quality)).c_str(),
              double(info.bytes) / double(std::max<std::size_t>(1, info.triangles)), info.sah_cost,
              info.build_seconds);

  // One untimed pass each first: page faults and cold caches are nobody's rate.
  for (Result& r : results) {
    r.mode->embree(rays, r.embree_answers);
    r.mode->volley(rays, r.volley_answers);
  }
  for (int rep = 0; rep < a.reps; ++rep) {
    for (Result& r : results) {
      if (rep % 2 == 0) {
        r.embree_s.push_back(timed(r.mode->embree, rays, r.embree_answers));
        r.volley_s.push_back(timed(r.mode->volley, rays, r.volley_answers));
      } else {
        r.volley_s.push_back(timed(r.mode->volley, rays, r.volley_answers));
        r.embree_s.push_back(timed(r.mode->embree, rays, r.embree_answers));
      }
    }
  }

  std::printf("%-16s %-15s %10s %10s   %-26s %10s %10s   %7s  %s\n", "mode", "embree", "Mrays/s", "(median)",
              "volley", "Mrays/s", "(median)", "v/e", "agreement");
  for (Result& r : results) {
    compare(r);
    const double e = mrays(rays.size(), best(r.embree_s)), v = mrays(rays.size(), best(r.volley_s));
    std::printf("%-16s %-15s %10.2f %10.2f   %-26s %10.2f %10.2f   %6.3fx  %.4f%% %s", r.mode->name.c_str(),
                r.mode->embree_call.c_str(), e, mrays(rays.size(), median(r.embree_s)), r.mode->volley_call.c_str(), v,
                mrays(rays.size(), median(r.volley_s)), e > 0 ? v / e : 0.0, 100.0 * r.agreement,
                r.mode->counting ? "same count" : r.mode->occlusion ? "blocked/free" : "hit/miss");
    if (!r.mode->occlusion && !r.mode->counting) std::printf(", prim %.4f%%", 100.0 * r.prim_agreement);
    std::printf("\n");
  }
  if (a.show_differences > 0)
    for (const Result& r : results) show_differences(r, rays, accel, embree, a.show_differences);
  for (const Result& r : results)
    std::printf("vs_embree: scene=%s rays=%zu mode=%s test=%s isa=%s embree_Mrays/s=%.3f volley_Mrays/s=%.3f "
                "ratio=%.4f agree=%.6f embree_hits=%zu volley_hits=%zu\n",
                a.scene.c_str(), rays.size(), r.mode->name.c_str(), std::string(to_string(info.test)).c_str(),
                std::string(to_string(info.isa)).c_str(), mrays(rays.size(), best(r.embree_s)),
                mrays(rays.size(), best(r.volley_s)),
                best(r.volley_s) > 0 ? best(r.embree_s) / best(r.volley_s) : 0.0, r.agreement, r.embree_hits,
                r.volley_hits);

  if (!a.json.empty()) {
    std::ofstream out(a.json);
    if (!out) throw std::runtime_error(a.json + ": cannot write");
    out << "{\n  \"scene\": \"" << json_escape(a.scene) << "\",\n  \"rays\": \"" << json_escape(source)
        << "\",\n  \"ray_count\": " << rays.size() << ",\n  \"threads\": 1,\n  \"reps\": " << a.reps
        << ",\n  \"embree\": {\"version\": \"" << RTC_VERSION_STRING << "\", \"quality\": \"" << to_string(config.quality)
        << "\", \"robust\": " << (config.robust ? "true" : "false") << ", \"build_s\": " << embree.build_seconds()
        << "},\n  \"volley\": {\"test\": \"" << to_string(info.test) << "\", \"isa\": \"" << to_string(info.isa)
        << "\", \"quality\": \"" << to_string(info.quality) << "\", \"build_s\": " << info.build_seconds << "},\n  \"modes\": [\n";
    for (std::size_t i = 0; i < results.size(); ++i) {
      const Result& r = results[i];
      out << "    {\"mode\": \"" << r.mode->name << "\", \"embree_call\": \"" << r.mode->embree_call
          << "\", \"embree_best_s\": " << best(r.embree_s) << ", \"embree_median_s\": " << median(r.embree_s)
          << ", \"volley_best_s\": " << best(r.volley_s) << ", \"volley_median_s\": " << median(r.volley_s)
          << ", \"embree_mrays\": " << mrays(rays.size(), best(r.embree_s))
          << ", \"volley_mrays\": " << mrays(rays.size(), best(r.volley_s))
          << ", \"ratio\": " << (best(r.volley_s) > 0 ? best(r.embree_s) / best(r.volley_s) : 0.0)
          << ", \"agreement\": " << r.agreement << "}" << (i + 1 < results.size() ? "," : "") << "\n";
    }
    out << "  ]\n}\n";
    std::printf("json -> %s\n", a.json.c_str());
  }
  return 0;
}

}  // namespace
}  // namespace volley::bench

int main(int argc, char** argv) {
  volley::bench::Args a;
  CLI::App app{
      "volley_vs_embree: volley and Embree 3 on the same triangles and rays, one thread,\n"
      "alternating repetitions; prints both rates and volley/embree per mode. Examples:\n"
      "  volley_vs_embree ../shared/scenes/sponza_dabrovic.obj --workload primary --modes packet\n"
      "  volley_vs_embree scene.obj --rays shadow.vray --modes occluded1,occluded16 --json out.json"};
  app.add_option("scene", a.scene, "Scene file (.json) or mesh (.obj, .ply); triangles only")->required();
  auto* rays = app.add_option("--rays", a.rays, "Ray file (.vray) to trace");
  auto* workload = app.add_option("--workload", a.workload, "Make the rays instead: primary, shadow or diffuse")
                       ->check(CLI::IsMember({"primary", "shadow", "diffuse"}));
  rays->excludes(workload);
  app.add_option("--width", a.width, "Image width for --workload (default: the scene's)")->check(CLI::Range(2, 16384));
  app.add_option("--height", a.height, "Image height for --workload (default: the scene's)")->check(CLI::Range(2, 16384));
  app.add_option("--seed", a.seed, "Seed for --workload diffuse (default: the scene's)")->check(CLI::NonNegativeNumber);
  app.add_option("--modes", a.modes,
                 "Comma-separated: single (rtcIntersect1), packet (rtcIntersect16), stream (rtcIntersect1M), "
                 "occluded1, occluded16, occluded_stream; count1, count16, all1 (every hit: Embree through an intersection\n"
                 "filter that records and rejects each hit; its scene then has the context-filter flag)")
      ->capture_default_str();
  app.add_option("--reps", a.reps, "Repetitions per engine and mode (alternating)")->check(CLI::Range(1, 100000))->capture_default_str();
  app.add_option("--quality", a.quality, "Embree build quality")->check(CLI::IsMember({"medium", "high"}))->capture_default_str();
  app.add_flag("--robust", a.robust, "Embree scene flag ROBUST (default NONE)");
  app.add_flag("--coherent", a.coherent, "Embree intersect context flag COHERENT (default INCOHERENT)");
  app.add_option("--volley-quality", a.volley_quality, "volley's build quality (Options::quality)")
      ->check(CLI::IsMember({"medium", "high"}))
      ->capture_default_str();
  app.add_option("--test", a.test, "volley's triangle test")->check(CLI::IsMember({"plane", "moller", "watertight"}))->capture_default_str();
  app.add_option("--isa", a.isa, "volley's ISA")->check(CLI::IsMember({"auto", "scalar", "sse4.2", "avx2", "avx512"}))->capture_default_str();
  app.add_option("--scenes", a.scenes, "Folder of shared meshes for ${scenes}/ paths");
  app.add_option("--json", a.json, "Also write the results as JSON");
  app.add_option("--show-differences", a.show_differences, "Print up to N rays per mode whose answers differ")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--no-ftz", a.no_ftz, "Leave flush-to-zero / denormals-are-zero off (Embree wants them on)");
  app.add_option("--embree-config", a.embree_config, "rtcNewDevice configuration, e.g. \"verbose=1\" or \"isa=avx2\"");
  try {
    app.parse(argc, argv);
    if (a.rays.empty() && a.workload.empty()) throw CLI::RequiredError("--rays or --workload");
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }
  try {
    return volley::bench::run(a);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "volley_vs_embree: error: %s\n", e.what());
  }
  return 1;
}
