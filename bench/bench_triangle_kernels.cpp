// Ray-triangle tests per second of the SIMD kernels (simd/triangle/block_kernels.h) and the scalar
// oracle (src/core/triangle_*.h), per test x ISA x form x workload, L1-resident data.
//
// A "leaf" is 16 triangles (1 block at AVX-512, 2 at AVX2, 4 at SSE4.2), so every ISA does
// the same work per call. Workloads:
//   aimed:  rays from random origins aimed at a random point of a random triangle of the leaf
//           (barycentrics in [-0.1, 1.1]): about one hit per ray and leaf, the closest-hit case
//           of a BVH leaf the ray really reaches;
//   random: rays through the leaf's bounding box in random directions: mostly misses.
// Forms:
//   1xblock:    one ray against the leaf's blocks (closest hit), RayBlockKernels::intersect;
//   1xblock_any: the same, any hit (occluded);
//   1x64:       one ray against four consecutive leaves in one call (64 triangles; closest
//               hit): the call's fixed cost spread over four times the tests;
//   16x1:       a coherent packet of 16 rays against one triangle at a time,
//               PacketKernels<.., 16>::intersect_triangle over the leaf's triangles
//               (packets prepared once beforehand, as a traversal would);
//   16xblock:   the same packet against the leaf's blocks, PacketKernels<.., 16>::intersect.
// Items processed = ray-triangle tests (rays x 16). Names: triangle/<test>/<isa>/<form>/<workload>;
// the label is the ISA. The scalar oracle ("scalar") precomputes what its blocks would hold
// (PlaneTriangle, WoopRay per ray) and loops over the 16 triangles; moller in the variant
// Isa::scalar runs (unfused: std::fma is a libm call in the x86-64-v2 baseline).
#include <benchmark/benchmark.h>

#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include "bench_common.h"
#include "core/triangle.h"
#include "simd/testing/prepare_ray.h"
#include "simd/aligned.h"
#include "simd/isa/arch.h"
#include "simd/triangle/block_build.h"
#include "simd/triangle/block_kernels.h"
#include "simd/isa/dispatch.h"
#include "simd/rays/prepared_packet.h"
#include "simd/rays/prepared_ray.h"
#include "simd/rays/ray_packet.h"

namespace {

using volley::Hit;
using volley::Ray;
using volley::TriangleTest;
using V3 = volley::core::Vec3<float>;

constexpr int kLeaf = 16;       // triangles per leaf
constexpr int kLeaves = 8;      // leaves in the working set (<= 7 KB of blocks)
constexpr int kRaysPerLeaf = 64;
constexpr float kInf = std::numeric_limits<float>::infinity();

/// Triangles of the leaves (9 floats each) and the rays aimed at each leaf.
struct Workload {
  std::vector<float> xyz;                 // kLeaves * kLeaf triangles
  std::vector<std::uint32_t> ids;
  std::vector<std::vector<Ray>> rays;     // per leaf
};

Workload make_workload(bool aimed) {
  std::mt19937 rng(1234);
  const auto uni = [&](float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); };
  Workload w;
  w.rays.resize(kLeaves);
  for (int leaf = 0; leaf < kLeaves; ++leaf) {
    // A patch of surface: triangles around a wavy sheet in [-1, 1]^2, like a BVH leaf.
    const std::size_t first = w.ids.size();
    for (int t = 0; t < kLeaf; ++t) {
      const V3 c(uni(-1, 1), uni(-1, 1), uni(-0.2f, 0.2f));
      for (int k = 0; k < 3; ++k) {
        const V3 p = c + V3(uni(-0.4f, 0.4f), uni(-0.4f, 0.4f), uni(-0.1f, 0.1f));
        w.xyz.insert(w.xyz.end(), {p.x, p.y, p.z});
      }
      w.ids.push_back(static_cast<std::uint32_t>(w.ids.size()));
    }
    for (int r = 0; r < kRaysPerLeaf; ++r) {
      const V3 org(uni(-3, 3), uni(-3, 3), uni(2, 4) * (r % 2 ? 1.0f : -1.0f));
      V3 target;
      if (aimed) {
        const float* p = w.xyz.data() + 9 * (first + static_cast<std::size_t>(rng() % kLeaf));
        const float bu = uni(-0.1f, 1.1f), bv = uni(-0.1f, 1.1f - bu);
        for (int c = 0; c < 3; ++c) target[c] = p[c] + bu * (p[3 + c] - p[c]) + bv * (p[6 + c] - p[c]);
      } else {
        target = V3(uni(-1.4f, 1.4f), uni(-1.4f, 1.4f), uni(-0.3f, 0.3f));
      }
      const V3 d = target - org;
      w.rays[leaf].push_back(Ray{{org.x, org.y, org.z}, 0.0f, {d.x, d.y, d.z}, kInf});
    }
  }
  return w;
}

/// Leaves visited per iteration: kLeaves, more under the synthetic slowdown of the perf
/// tests (VOLLEY_BENCH_SLOWDOWN, bench_common.h), which revisits leaves without counting
/// them as items.
int leaf_passes() { return kLeaves + static_cast<int>(volley::bench::slowdown_extra(kLeaves)); }

const Workload& workload(bool aimed) {
  static const Workload a = make_workload(true), r = make_workload(false);
  return aimed ? a : r;
}

/// Coherent packets: 16 rays of one leaf sharing the origin of the first.
std::vector<volley::simd::RayPacket<16>> packets_of(const Workload& w, int leaf) {
  std::vector<volley::simd::RayPacket<16>> out;
  const auto& rays = w.rays[leaf];
  for (std::size_t first = 0; first + 16 <= rays.size(); first += 16) {
    Ray group[16];
    for (int i = 0; i < 16; ++i) {
      Ray r = rays[first + i];
      const V3 target(r.org[0] + r.dir[0], r.org[1] + r.dir[1], r.org[2] + r.dir[2]);
      for (int c = 0; c < 3; ++c) r.org[c] = rays[first].org[c];
      const V3 d = target - V3(r.org[0], r.org[1], r.org[2]);
      r.dir[0] = d.x, r.dir[1] = d.y, r.dir[2] = d.z;
      group[i] = r;
    }
    volley::simd::RayPacket<16> p;
    volley::simd::load(p, group, 16);
    out.push_back(p);
  }
  return out;
}

// ---- SIMD kernels ---------------------------------------------------------------------

template <class Arch, TriangleTest Test>
struct Leaves {
  static constexpr int W = volley::simd::kLanes<Arch>;
  static constexpr int kBlocks = kLeaf / W;
  using Block = volley::simd::BlockFor<Test, W>;
  volley::simd::AlignedVector<Block> blocks;
  explicit Leaves(const Workload& w) : blocks(kLeaves * kBlocks) {
    for (int leaf = 0; leaf < kLeaves; ++leaf)
      volley::simd::pack_blocks<Test, W>(w.xyz.data() + 9 * kLeaf * leaf, w.ids.data() + kLeaf * leaf, kLeaf,
                                         blocks.data() + kBlocks * leaf);
  }
  const Block* leaf(int i) const { return blocks.data() + kBlocks * i; }
};

/// One ray against `Group` consecutive leaves per call (Group = 1: the 16-triangle leaf;
/// 4: a 64-triangle run, which spreads the call's fixed cost over four times the tests).
template <class Arch, TriangleTest Test, bool AnyHit, int Group = 1>
void single_ray(benchmark::State& state, bool aimed) {
  static_assert(kLeaves % Group == 0);
  const Workload& w = workload(aimed);
  const Leaves<Arch, Test> leaves(w);
  std::vector<std::vector<volley::simd::PreparedRay>> prepared(kLeaves);
  for (int l = 0; l < kLeaves; ++l)
    for (const Ray& r : w.rays[l]) prepared[l].push_back(volley::simd::prepare_ray(r, Test == TriangleTest::watertight));
  std::size_t hits = 0;
  const int passes = leaf_passes();
  for (auto _ : state) {
    for (int pass = 0; pass < passes; ++pass) {
      const int l = (pass * Group) % kLeaves;
      const auto* blocks = leaves.leaf(l);
      constexpr std::uint32_t count = Group * Leaves<Arch, Test>::kBlocks;
      for (const auto& pr : prepared[l]) {
        if constexpr (AnyHit) {
          hits += volley::simd::RayBlockKernels<Arch, Test>::occluded(pr, blocks, count);
        } else {
          Hit h;
          volley::simd::RayBlockKernels<Arch, Test>::intersect(pr, blocks, count, h);
          hits += h.hit();
        }
      }
    }
    benchmark::DoNotOptimize(hits);
  }
  state.SetItemsProcessed(state.iterations() * kLeaves * kRaysPerLeaf * kLeaf * Group);
  state.counters["hit_rate"] = double(hits) / double(state.iterations() * passes * kRaysPerLeaf);
}

template <class Arch, TriangleTest Test, bool PerTriangle>
void packet(benchmark::State& state, bool aimed) {
  constexpr int W = volley::simd::kLanes<Arch>;
  const Workload& w = workload(aimed);
  const Leaves<Arch, Test> leaves(w);
  // Packets are prepared once (the Woop shear per lane for watertight), as a traversal would.
  std::vector<volley::simd::AlignedVector<volley::simd::PreparedPacket<16>>> packets(kLeaves);
  for (int l = 0; l < kLeaves; ++l)
    for (const auto& p : packets_of(w, l)) {
      packets[l].emplace_back();
      volley::simd::PacketKernels<Arch, Test, 16>::prepare(p, packets[l].back());
    }
  std::size_t hits = 0;
  const int passes = leaf_passes();
  for (auto _ : state) {
    for (int pass = 0; pass < passes; ++pass) {
      const int l = pass % kLeaves;
      const auto* blocks = leaves.leaf(l);
      for (const auto& p : packets[l]) {
        volley::simd::HitPacket<16> h;
        volley::simd::reset(h);
        if constexpr (PerTriangle) {
          for (int b = 0; b < Leaves<Arch, Test>::kBlocks; ++b)
            for (int j = 0; j < W; ++j) volley::simd::PacketKernels<Arch, Test, 16>::intersect_triangle(p, blocks[b], j, h);
        } else {
          volley::simd::PacketKernels<Arch, Test, 16>::intersect(p, blocks, Leaves<Arch, Test>::kBlocks, h);
        }
        hits += h.prim[0] != volley::kInvalidPrim;
      }
    }
    benchmark::DoNotOptimize(hits);
  }
  state.SetItemsProcessed(state.iterations() * kLeaves * kRaysPerLeaf * kLeaf);
}

// ---- scalar oracle --------------------------------------------------------------------

template <TriangleTest Test>
void scalar(benchmark::State& state, bool aimed) {
  const Workload& w = workload(aimed);
  std::vector<V3> verts;
  for (std::size_t i = 0; i < w.xyz.size(); i += 3) verts.emplace_back(w.xyz[i], w.xyz[i + 1], w.xyz[i + 2]);
  std::vector<volley::core::PlaneTriangle<float>> planes;
  for (std::size_t t = 0; t < w.ids.size(); ++t)
    planes.push_back(volley::core::PlaneTriangle<float>::from(verts[3 * t], verts[3 * t + 1], verts[3 * t + 2]));
  std::vector<std::vector<volley::core::RayT<float>>> rays(kLeaves);
  std::vector<std::vector<volley::core::WoopRay<float>>> woop(kLeaves);
  for (int l = 0; l < kLeaves; ++l)
    for (const Ray& r : w.rays[l]) {
      rays[l].push_back({V3(r.org[0], r.org[1], r.org[2]), r.tmin, V3(r.dir[0], r.dir[1], r.dir[2]), r.tmax});
      woop[l].push_back(volley::core::make_woop_ray(rays[l].back().dir));
    }
  std::size_t hits = 0;
  const int passes = leaf_passes();
  for (auto _ : state) {
    for (int pass = 0; pass < passes; ++pass) {
      const int l = pass % kLeaves;
      for (std::size_t r = 0; r < rays[l].size(); ++r) {
        volley::core::RayT<float> ray = rays[l][r];
        volley::core::TriHit<float> h{};
        bool any = false;
        for (int t = l * kLeaf; t < (l + 1) * kLeaf; ++t) {
          bool hit = false;
          if constexpr (Test == TriangleTest::moller)
            hit = volley::core::intersect_moller<float, volley::core::moller_fused_for(volley::Isa::scalar)>(
                ray, verts[3 * t], verts[3 * t + 1], verts[3 * t + 2], h);
          else if constexpr (Test == TriangleTest::plane)
            hit = volley::core::intersect_plane(ray, planes[t], h);
          else
            hit = volley::core::intersect_watertight(ray, woop[l][r], verts[3 * t], verts[3 * t + 1], verts[3 * t + 2], h);
          if (hit) ray.tmax = h.t, any = true;
        }
        hits += any;
      }
    }
    benchmark::DoNotOptimize(hits);
  }
  state.SetItemsProcessed(state.iterations() * kLeaves * kRaysPerLeaf * kLeaf);
  state.counters["hit_rate"] = double(hits) / double(state.iterations() * passes * kRaysPerLeaf);
}

// ---- registration ---------------------------------------------------------------------

std::string test_name(TriangleTest t) { return std::string(volley::to_string(t)); }

/// Arch's benchmarks, labelled with its ISA ("avx512ymm": AVX-512 on 8 lanes, the single-ray
/// leaf kernels of the AVX-512 wide BVH).
template <class Arch, TriangleTest Test>
void register_isa() {
  const std::string isa = std::is_same_v<Arch, volley::simd::Avx512Ymm>
                              ? std::string("avx512ymm")
                              : std::string(volley::to_string(volley::simd::kIsaOf<Arch>));
  if (!volley::simd::cpu_has(volley::simd::kIsaOf<Arch>)) return;
  for (bool aimed : {true, false}) {
    const std::string suffix = std::string("/") + (aimed ? "aimed" : "random");
    const std::string base = "triangle/" + test_name(Test) + "/" + isa + "/";
    benchmark::RegisterBenchmark((base + "1xblock" + suffix).c_str(),
                                 [=](benchmark::State& s) { single_ray<Arch, Test, false>(s, aimed); s.SetLabel(isa); });
    benchmark::RegisterBenchmark((base + "1x64" + suffix).c_str(),
                                 [=](benchmark::State& s) { single_ray<Arch, Test, false, 4>(s, aimed); s.SetLabel(isa); });
    benchmark::RegisterBenchmark((base + "1xblock_any" + suffix).c_str(),
                                 [=](benchmark::State& s) { single_ray<Arch, Test, true>(s, aimed); s.SetLabel(isa); });
    benchmark::RegisterBenchmark((base + "16x1" + suffix).c_str(),
                                 [=](benchmark::State& s) { packet<Arch, Test, true>(s, aimed); s.SetLabel(isa); });
    benchmark::RegisterBenchmark((base + "16xblock" + suffix).c_str(),
                                 [=](benchmark::State& s) { packet<Arch, Test, false>(s, aimed); s.SetLabel(isa); });
  }
}

template <TriangleTest Test>
void register_test() {
  for (bool aimed : {true, false})
    benchmark::RegisterBenchmark(("triangle/" + test_name(Test) + "/scalar/1x1/" + (aimed ? "aimed" : "random")).c_str(),
                                 [=](benchmark::State& s) { scalar<Test>(s, aimed); s.SetLabel("scalar"); });
  register_isa<volley::simd::Sse42, Test>();
  register_isa<volley::simd::Avx2, Test>();
  register_isa<volley::simd::Avx512, Test>();
  register_isa<volley::simd::Avx512Ymm, Test>();
}

const bool registered = [] {
  register_test<TriangleTest::moller>();
  register_test<TriangleTest::plane>();
  register_test<TriangleTest::watertight>();
  return true;
}();

}  // namespace
