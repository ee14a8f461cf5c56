# volley: the commands a newcomer needs. Each target installs missing Debian packages,
# then configures and builds with the CMake presets (Release in build/release).
PRESET ?= release
BUILD  := build/$(PRESET)
JOBS   ?= $(shell nproc)

# Required to build; the optional ones enable the Embree side-by-side, plots and
# instruction-count benchmarks.
DEPS     := cmake g++ make pkg-config libxsimd-dev libbenchmark-dev libglm-dev libstb-dev \
            doctest-dev libtinyobjloader-dev nlohmann-json3-dev libtbb-dev libcli11-dev
OPTIONAL := libembree-dev gnuplot-nox valgrind
SUDO     := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: deps build test demo bench clean

deps:
	@missing=$$(for p in $(DEPS) $(OPTIONAL); do dpkg -s $$p >/dev/null 2>&1 || echo $$p; done); \
	if [ -n "$$missing" ]; then \
	  echo "installing Debian packages:" $$missing; \
	  $(SUDO) apt-get update -qq && DEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y -qq $$missing; \
	fi

build: deps
	cmake --preset $(PRESET)
	cmake --build --preset $(PRESET) -j $(JOBS)

test: build
	ctest --preset $(PRESET) -j $(JOBS)

demo: build
	$(BUILD)/volley render scenes/cornell.json -o out/cornell.png

bench: build
	$(BUILD)/volley_bench --benchmark_out=out/bench.json --benchmark_out_format=json

clean:
	rm -rf build out
