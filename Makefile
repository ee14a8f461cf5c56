# volley: the commands a newcomer needs. Each target installs missing Debian packages,
# then configures and builds with the CMake presets (Release in build/release).
PRESET ?= release
BUILD  := build/$(PRESET)
JOBS   ?= $(shell nproc)

# What `make demo` needs: the library and the volley command. `make test` (and bench,
# perf) also need the test, benchmark and Python packages; the optional ones enable the
# Embree side-by-side, plots, instruction-count benchmarks, the perf/ scripts, Google
# Benchmark's compare.py (libbenchmark-tools, python3-scipy) and the Dask example
# (python3-distributed).
DEMO_DEPS := cmake g++ make pkg-config libxsimd-dev libglm-dev libstb-dev libtinyobjloader-dev \
             nlohmann-json3-dev libtbb-dev libcli11-dev
DEPS      := $(DEMO_DEPS) libbenchmark-dev doctest-dev python3-dev python3-numpy pybind11-dev python3-pytest
OPTIONAL  := libembree-dev gnuplot-nox valgrind python3 python3-distributed libbenchmark-tools python3-scipy
# The sanitizer builds and the fuzzers use clang with its runtimes and libFuzzer.
SANITIZER_DEPS := clang libclang-rt-14-dev libfuzzer-14-dev
# Warnings are errors in CI (CI=true), so that a new one fails the run.
WERROR   ?= $(if $(CI),ON,OFF)
# Every part on (make test) or only the library and the command (make demo); the library's
# objects are the same in both, so one build tree serves both.
ALL_PARTS  := -DVOLLEY_WERROR=$(WERROR) -DVOLLEY_BUILD_TESTS=ON -DVOLLEY_BUILD_BENCH=ON -DVOLLEY_PYTHON=ON
DEMO_PARTS := -DVOLLEY_WERROR=$(WERROR) -DVOLLEY_BUILD_TESTS=OFF -DVOLLEY_BUILD_BENCH=OFF -DVOLLEY_PYTHON=OFF
SUDO     := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: deps deps-demo deps-sanitizers build test test-asan test-tsan fuzz demo bench perf perf-icount perf-baseline perf-icount-baseline perf-steps perf-plot clean

# Installs the Debian packages of $(1) that are missing.
define install_missing
	@missing=$$(for p in $(1); do dpkg -s $$p >/dev/null 2>&1 || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:" $$missing; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $$missing; \
	fi
endef

deps:
	$(call install_missing,$(DEPS) $(OPTIONAL))

deps-demo:
	$(call install_missing,$(DEMO_DEPS))

deps-sanitizers: deps
	$(call install_missing,$(SANITIZER_DEPS))

build: deps
	cmake --preset $(PRESET) $(ALL_PARTS)
	cmake --build --preset $(PRESET) -j $(JOBS)

test: build
	ctest --preset $(PRESET) -j $(JOBS)

# The whole ctest suite under AddressSanitizer + UndefinedBehaviorSanitizer (build/asan,
# which also holds the fuzz targets) or ThreadSanitizer (build/tsan), clang -O1. README
# "Testing".
test-asan test-tsan: test-%: deps-sanitizers
	cmake --preset $* -DVOLLEY_WERROR=$(WERROR)
	cmake --build --preset $* -j $(JOBS)
	ctest --preset $* -j $(JOBS)

# Each libFuzzer target for FUZZ_SECONDS seconds from its committed seed corpus
# (README "Testing"), built in the ASan tree (build/asan, whose libraries carry libFuzzer's
# coverage: no library is built twice); a crash leaves its input in build/asan/artifacts/
# and fails.
FUZZ_SECONDS ?= 60
fuzz: deps-sanitizers
	cmake --preset asan -DVOLLEY_WERROR=$(WERROR)
	cmake --build --preset fuzz -j $(JOBS)
	fuzz/run_all.sh build/asan $(FUZZ_SECONDS)

# The library and the volley command only (no tests, benchmarks or Python), then a render.
demo: deps-demo
	cmake --preset $(PRESET) $(DEMO_PARTS)
	cmake --build --preset $(PRESET) -j $(JOBS) --target volley_cli
	$(BUILD)/volley render scenes/cornell.json -o out/cornell.png

# Benchmarks and regression tracking (perf/README.md). Results (Google Benchmark JSON)
# go to perf/results/ and each machine's history to perf/history/, both git-ignored, so
# these targets leave `git status` clean.
#   bench: every suite once, short (1 repetition), against this machine's baseline (no
#          verdicts from one repetition), then the instruction counts of every ISA path.
#   perf:  the full timing run (5 repetitions) with verdicts, then the instruction counts;
#          fails on a tracked regression.
#   perf-icount: instruction counts under callgrind, deterministic; fails on a regression.
#   perf-baseline: records this machine's timing baseline and its noise (perf/baselines/
#          MACHINE/); perf-icount-baseline: the instruction counts of every ISA path.
#   perf-steps: where this machine's series stepped; perf-plot: history.png and .html.
ICOUNT_ISAS := avx2 sse4.2 scalar
define each_icount_path
	@if ! command -v valgrind >/dev/null; then \
	  echo "valgrind is not installed: instruction counts not compared (Debian package valgrind)"; \
	else status=0; for isa in $(ICOUNT_ISAS); do \
	  perf/run --callgrind --isa $$isa --build-dir $(BUILD) $(1) || status=1; done; exit $$status; fi
endef

bench: build
	perf/run --quick --build-dir $(BUILD) --compare baseline
	$(call each_icount_path,--compare baseline)

perf: build
	perf/run --build-dir $(BUILD) --compare baseline
	$(call each_icount_path,--compare baseline)

perf-icount: build
	$(call each_icount_path,--compare baseline)

perf-baseline: build
	perf/run --build-dir $(BUILD) --record-baseline
	perf/noise --build-dir $(BUILD)

perf-icount-baseline: build
	$(call each_icount_path,--record-baseline)

perf-steps:
	perf/steps

perf-plot:
	perf/plot

clean:
	rm -rf build out
