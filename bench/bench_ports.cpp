// What this machine's vector units can issue per cycle: the real ceiling of the triangle
// kernels (bench_triangle_kernels.cpp, perf/reports/kernels.md). A Möller block test is about 37
// vector operations (20 multiplies and FMAs, 4 adds, 6 compares, 5 logic, 2 mask moves),
// so its ceiling is 37 over the operations per cycle of the ports they share, not 20 over
// the FMA rate alone.
//
// machine/ports/<width>/<op>: twelve independent chains of one operation (more than latency
// x ports on every x86 we know), so the loop runs at the issue rate. Counter ops_per_cycle:
// operations per cycle, the cycle measured first by one dependent chain of FMAs, whose
// latency is 4 cycles on every AVX2 and AVX-512 core since Skylake and Zen 1 (counter ghz).
// The mix (half FMAs, half compares) shows whether the two share ports: if compares issue
// at 1 per cycle and FMAs at 2, a mix at 2 per cycle says they do.
#include <benchmark/benchmark.h>
#include <immintrin.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <string>

#include "simd/isa/dispatch.h"

namespace {

constexpr int kChains = 12;
constexpr double kFmaLatency = 4.0;  // cycles, AVX2 / AVX-512 FMA on Skylake+ and Zen 1+
constexpr long kIters = 4096;        // loop trips per benchmark iteration

/// The vector type and operations of one width, as target-attributed functions (baseline
/// file: no per-ISA object, nothing inlined across widths).
#define VOLLEY_PORTS(NAME, TARGET, V, M, SET1, FMA, ADD, AND, CMP)                              \
  struct NAME {                                                                                 \
    [[gnu::target(TARGET), gnu::noinline]] static float chain(long n) {                         \
      V a = SET1(0.5f);                                                                         \
      const V b = SET1(0.999f);                                                                 \
      for (long i = 0; i < n; ++i) {                                                            \
        a = FMA(a, b, b);                                                                       \
        asm volatile("" : "+v"(a));                                                             \
      }                                                                                         \
      alignas(64) float out[sizeof(V) / 4];                                                     \
      __builtin_memcpy(out, &a, sizeof(V));                                                     \
      return out[0];                                                                            \
    }                                                                                           \
    /* Op: 0 fma, 1 add, 2 and, 3 compare, 4 fma + compare (half each) */                       \
    template <int Op>                                                                           \
    [[gnu::target(TARGET), gnu::noinline]] static unsigned run(long n) {                        \
      V x[kChains];                                                                             \
      _Pragma("GCC unroll 12") for (int c = 0; c < kChains; ++c) x[c] = SET1(0.5f + 0.01f * c); \
      const V y = SET1(0.25f), z = SET1(0.75f);                                                 \
      M m[kMasks];                                                                              \
      for (int k = 0; k < kMasks; ++k) m[k] = all_lanes(M{});                                   \
      for (long i = 0; i < n; ++i) {                                                            \
        _Pragma("GCC unroll 12") for (int c = 0; c < kChains; ++c) {                            \
          if constexpr (Op == 0) x[c] = FMA(x[c], y, z);                                        \
          if constexpr (Op == 1) x[c] = ADD(x[c], y);                                           \
          if constexpr (Op == 2) x[c] = AND(x[c], z);                                           \
          if constexpr (Op == 3) CMP(m[c % kMasks], x[c], y);                                   \
          if constexpr (Op == 4) {                                                              \
            if (c & 1)                                                                          \
              CMP(m[c % kMasks], x[c], y);                                                      \
            else                                                                                \
              x[c] = FMA(x[c], y, z);                                                           \
          }                                                                                     \
          asm volatile("" : "+v"(x[c]));                                                        \
        }                                                                                       \
      }                                                                                         \
      unsigned acc = 0;                                                                         \
      for (int k = 0; k < kMasks; ++k) acc += mask_bits(m[k]);                                  \
      return acc;                                                                               \
    }                                                                                           \
  };

// Compares as the kernels chain them: AVX-512 into a mask register under the previous mask
// (and_cmp, `vcmpps k{k}`), AVX2 into a vector ANDed with the previous one. Six masks, so
// the chains' latency does not limit the rate.
constexpr int kMasks = 6;
[[gnu::target("avx512f")]] inline __mmask16 all_lanes(__mmask16) { return 0xffff; }
[[gnu::target("avx2")]] inline __m256 all_lanes(__m256) { return _mm256_castsi256_ps(_mm256_set1_epi32(-1)); }
[[gnu::target("avx512f")]] inline unsigned mask_bits(__mmask16 m) { return m; }
[[gnu::target("avx2")]] inline unsigned mask_bits(__m256 m) { return static_cast<unsigned>(_mm256_movemask_ps(m)); }
#define VOLLEY_CMP512(m, a, b) (m) = _mm512_mask_cmp_ps_mask(m, a, b, _CMP_LT_OQ)
#define VOLLEY_CMP256(m, a, b) (m) = _mm256_and_ps(m, _mm256_cmp_ps(a, b, _CMP_LT_OQ))
VOLLEY_PORTS(Zmm, "avx512f,avx512dq", __m512, __mmask16, _mm512_set1_ps, _mm512_fmadd_ps, _mm512_add_ps, _mm512_and_ps,
             VOLLEY_CMP512)
VOLLEY_PORTS(Ymm, "avx2,fma", __m256, __m256, _mm256_set1_ps, _mm256_fmadd_ps, _mm256_add_ps, _mm256_and_ps,
             VOLLEY_CMP256)

/// Seconds per cycle: a dependent FMA chain's time per FMA over its latency.
template <class P>
double cycle_seconds() {
  constexpr long kChainLength = 1 << 20;
  double best = 1e300;
  for (int rep = 0; rep < 3; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(P::chain(kChainLength));
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best / (kChainLength * kFmaLatency);
}

/// Operation `op` of width P: items = operations; counters ops_per_cycle and ghz.
template <class P, int Op>
void issue(benchmark::State& state) {
  const double cycle = cycle_seconds<P>();
  unsigned sink = 0;
  double seconds = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    sink += P::template run<Op>(kIters);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  benchmark::DoNotOptimize(sink);
  const double ops = static_cast<double>(state.iterations()) * kIters * kChains;
  state.SetItemsProcessed(static_cast<std::int64_t>(ops));
  state.counters["ops_per_cycle"] = seconds > 0 ? ops / (seconds / cycle) : 0.0;
  state.counters["ghz"] = 1e-9 / cycle;
}

const char* const kOps[] = {"fma", "add", "and", "compare", "fma+compare"};

template <class P>
void register_width(const std::string& width) {
  const auto add = [&](int op, void (*fn)(benchmark::State&)) {
    benchmark::RegisterBenchmark(("machine/ports/" + width + "/" + kOps[op]).c_str(), [=](benchmark::State& s) {
      fn(s);
      s.SetLabel(width);
    });
  };
  add(0, issue<P, 0>), add(1, issue<P, 1>), add(2, issue<P, 2>), add(3, issue<P, 3>), add(4, issue<P, 4>);
}

const bool registered = [] {
  if (volley::simd::cpu_has(volley::Isa::avx2)) register_width<Ymm>("ymm");
  if (volley::simd::cpu_has(volley::Isa::avx512)) register_width<Zmm>("zmm");
  return true;
}();

}  // namespace
