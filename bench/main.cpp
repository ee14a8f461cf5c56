// volley_bench entry point: Google Benchmark's main for every suite in bench/, plus
// `--scenes DIR` (the shared benchmark meshes; sets VOLLEY_SCENES, see bench_common.h).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <cstring>
#include <string>

int main(int argc, char** argv) {
  // Take --scenes DIR / --scenes=DIR out of argv before Google Benchmark sees it.
  int kept = 1;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--scenes") == 0 && i + 1 < argc) {
      setenv("VOLLEY_SCENES", argv[++i], 1);
    } else if (std::strncmp(argv[i], "--scenes=", 9) == 0) {
      setenv("VOLLEY_SCENES", argv[i] + 9, 1);
    } else {
      argv[kept++] = argv[i];
    }
  }
  argc = kept;
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
