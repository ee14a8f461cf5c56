#!/usr/bin/env bash
# The answers of every query configuration as digests, one line each, so that a
# refactoring can show its answers are byte for byte the same: run before and after, then
# diff the two outputs. For each scene x workload, `volley rays` writes one ray file
# (W x H pixels), then `volley trace -o` answers it in every mode (single, packet 4/8/16,
# stream) x test x ISA this CPU has (and the scalar oracle and the double reference), closest
# hit and occlusion; each line is the configuration and the sha256 of its .vhit.
# Usage: perf/answers_digest.sh [BUILD_DIR] > answers.txt   (env: SCENES, W, H; EXTRA: flags
# added to every trace, e.g. EXTRA="--quality high" to compare build qualities)
set -euo pipefail
build=${1:-build/release}
volley="$build/volley"
scenes_dir=${VOLLEY_SCENES:-../shared/scenes}
scenes=${SCENES:-"scenes/cornell.json scenes/polygons.json $scenes_dir/stanford-bunny.obj $scenes_dir/sponza_dabrovic.obj $scenes_dir/conference.obj"}
w=${W:-64}
h=${H:-48}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
flags=$(grep -m1 '^flags' /proc/cpuinfo)
isas="scalar"
for pair in sse4_2:sse4.2 avx2:avx2 avx512bw:avx512; do
  case " $flags " in *" ${pair%%:*} "*) isas="$isas ${pair##*:}" ;; esac
done
for scene in $scenes; do
  [ -f "$scene" ] || { echo "# $scene: not found, skipped" >&2; continue; }
  for workload in primary shadow diffuse; do
    rays="$work/rays.vray"
    "$volley" rays "$scene" --workload "$workload" --width "$w" --height "$h" -o "$rays" >/dev/null
    for test in plane moller watertight; do
      configs=()
      for isa in $isas; do configs+=("--isa $isa"); done
      configs+=("--reference")
      for config in "${configs[@]}"; do
        for mode in "single" "packet --packet 4" "packet --packet 8" "packet --packet 16" "stream"; do
          for query in "" "--occluded"; do
            # shellcheck disable=SC2086
            "$volley" trace "$scene" --rays "$rays" --test "$test" $config --mode $mode $query --reps 1 --threads 1 ${EXTRA:-} \
              -o "$work/hits.vhit" >/dev/null
            echo "$(basename "$scene") $workload $test ${config// /=} ${mode// /=} ${query:-closest} $(sha256sum < "$work/hits.vhit" | cut -c1-16)"
          done
        done
      done
    done
  done
done
