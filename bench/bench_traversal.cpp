// Rays per second through the public Accel API (src/volley/accel.h): BVH traversal plus
// the leaf kernels, per scene x ISA x query form x workload, one thread.
//
// Scenes (bench/scenes/*.json): teapot (small; the one perf/run --callgrind uses), bunny
// (close-up), conference (camera inside the room), 256 x 256 pixels.
// Workloads (render/workloads.h, the same rays `volley rays` writes):
//   primary: one camera ray per pixel in 4x4 pixel blocks (coherent), closest hit;
//   shadow:  from the primary hits to the light (coherent-ish), occlusion (any hit);
//   diffuse: cosine-distributed bounces at the primary hits (incoherent), closest hit.
// Forms, each taking AoS rays and writing AoS answers as `volley trace` does:
//   single: Accel::intersect(Ray) / occluded(Ray) per ray;
//   packet: 16 consecutive rays loaded into a RayPacket<16>, Accel::intersect / occluded
//           of the packet (the conversion is inside the timed loop);
//   stream: Accel::intersect(const Ray*, n, Hit*) / occluded(...) over the whole workload.
// Triangle test: watertight (the default). Items processed = rays. Names:
// traversal/<scene>/<isa>/<form>/<workload>; the label is the ISA; the counter hit_rate
// (fraction of rays that hit / are occluded) is a deterministic check of the answers.
// The scenes and their rays are built once per process, outside the timed loops.
//
// Robust against fast slab tests (Options::robust, issue #5): traversal_slabs/<scene>/<isa>/
// <form>/primary/<robust|fast>, bunny and conference, AVX2 and AVX-512, the same rays and
// scene both ways; run with --benchmark_enable_random_interleaving and repetitions so that
// the two of a pair alternate in one process (perf/reports/robust.md).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <exception>
#include <map>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include <tbb/global_control.h>

#include "bench_common.h"
#include "render/scene.h"
#include "render/workloads.h"
#include "volley/accel.h"
#include "volley/packet.h"

namespace volley::bench {
namespace {

constexpr int kImage = 256;            // pixels per side: 65536 primary rays
constexpr std::uint64_t kSeed = 1;     // diffuse directions
constexpr int kPacket = 16;            // rays per packet

enum class Form { single, packet, stream };

const char* to_string(Form f) { return f == Form::single ? "single" : f == Form::packet ? "packet" : "stream"; }

/// A committed scene per (scene, ISA), and the workloads per scene (shared by all ISAs:
/// every ISA gives the oracle's answers, so the secondary rays do not depend on it).
/// Both are made on this thread alone: no oneTBB worker exists to run (and be counted
/// by callgrind) beside the timed loop, and the structure cannot depend on scheduling.
const render::Scene& scene_for(const std::string& name, Isa isa, bool robust = true) {
  static std::map<std::tuple<std::string, Isa, bool>, std::unique_ptr<render::Scene>> cache;
  auto& slot = cache[{name, isa, robust}];
  if (!slot) {
    const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
    slot = std::make_unique<render::Scene>(scene_desc(name), kImage, kImage,
                                           Options{TriangleTest::watertight, isa, robust});
  }
  return *slot;
}

const std::vector<Ray>& rays_for(const std::string& name, Isa isa, render::Workload workload) {
  static std::map<std::pair<std::string, render::Workload>, std::vector<Ray>> cache;
  const auto key = std::make_pair(name, workload);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, render::make_workload(scene_for(name, isa), workload, kSeed, 1)).first;
  return it->second;
}

/// Traces rays[begin, end) in the given form; returns how many hit (or are occluded).
std::size_t trace(const Accel& accel, const std::vector<Ray>& rays, std::size_t begin, std::size_t end, Form form,
                  bool occlusion, std::vector<Hit>& hits, std::vector<std::uint8_t>& blocked) {
  std::size_t count = 0;
  switch (form) {
    case Form::single:
      for (std::size_t i = begin; i < end; ++i) count += occlusion ? accel.occluded(rays[i]) : accel.intersect(rays[i]).hit();
      break;
    case Form::packet: {
      RayPacket<kPacket> packet;
      HitPacket<kPacket> answers;
      for (std::size_t b = begin; b < end; b += kPacket) {
        const int n = static_cast<int>(std::min<std::size_t>(kPacket, end - b));
        load(packet, rays.data() + b, n);
        if (occlusion) {
          count += static_cast<std::size_t>(std::popcount(accel.occluded(packet)));
        } else {
          reset(answers);
          accel.intersect(packet, answers);
          for (int i = 0; i < n; ++i) count += answers.prim[i] != kInvalidPrim;
        }
      }
      break;
    }
    case Form::stream:
      if (occlusion) {
        accel.occluded(rays.data() + begin, end - begin, blocked.data(), 1);
        for (std::size_t i = 0; i < end - begin; ++i) count += blocked[i];
      } else {
        accel.intersect(rays.data() + begin, end - begin, hits.data(), 1);
        for (std::size_t i = 0; i < end - begin; ++i) count += hits[i].hit();
      }
      break;
  }
  return count;
}

void traverse(benchmark::State& state, const std::string& scene, Isa isa, Form form, render::Workload workload,
              bool robust = true) {
  state.SetLabel(std::string(volley::to_string(isa)));
  const render::Scene* s = nullptr;
  const std::vector<Ray>* rays = nullptr;
  try {
    s = &scene_for(scene, isa, robust);
    rays = &rays_for(scene, isa, workload);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  const bool occlusion = workload == render::Workload::shadow;
  const std::size_t n = rays->size();
  // The synthetic slowdown (perf tests only) traces the first `extra` rays once more.
  const std::size_t extra = std::min(n, slowdown_extra(n));
  std::vector<Hit> hits(n);
  std::vector<std::uint8_t> blocked(n);
  std::size_t hit_count = 0;
  for (auto _ : state) {
    hit_count += trace(s->accel(), *rays, 0, n, form, occlusion, hits, blocked);
    if (extra) benchmark::DoNotOptimize(trace(s->accel(), *rays, 0, extra, form, occlusion, hits, blocked));
    benchmark::DoNotOptimize(hit_count);
  }
  const auto traced = static_cast<double>(state.iterations()) * static_cast<double>(n);
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(n));
  state.counters["hit_rate"] = traced > 0 ? static_cast<double>(hit_count) / traced : 0.0;
}

const bool registered = [] {
  for (const char* scene : {"teapot", "bunny", "conference"}) {
    note_scene(scene);
    for (Isa isa : {Isa::scalar, Isa::sse42, Isa::avx2, Isa::avx512}) {
      if (!bench_isa(isa)) continue;
      for (render::Workload workload : {render::Workload::primary, render::Workload::shadow, render::Workload::diffuse})
        for (Form form : {Form::single, Form::packet, Form::stream}) {
          const std::string name = std::string("traversal/") + scene + "/" + std::string(volley::to_string(isa)) + "/" +
                                   to_string(form) + "/" + std::string(render::to_string(workload));
          benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& st) { traverse(st, scene, isa, form, workload); })
              ->Unit(benchmark::kMicrosecond);
        }
    }
  }
  // The robust / fast pairs (primary rays).
  for (const char* scene : {"bunny", "conference"})
    for (Isa isa : {Isa::avx2, Isa::avx512}) {
      if (!bench_isa(isa)) continue;
      for (Form form : {Form::single, Form::packet, Form::stream})
        for (bool robust : {true, false}) {
          const std::string name = std::string("traversal_slabs/") + scene + "/" +
                                   std::string(volley::to_string(isa)) + "/" + to_string(form) + "/primary/" +
                                   (robust ? "robust" : "fast");
          benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& st) {
            traverse(st, scene, isa, form, render::Workload::primary, robust);
          })->Unit(benchmark::kMicrosecond);
        }
    }
  return true;
}();

}  // namespace
}  // namespace volley::bench
