// volley_bench entry point: Google Benchmark's main for every suite in bench/.
#include <benchmark/benchmark.h>

BENCHMARK_MAIN();
