#!/usr/bin/env bash
# Runs every fuzz target for SECONDS seconds each, one after the other, from the committed
# seed corpus (fuzz/corpus/TARGET, read only) into a working corpus beside the build
# (BUILD/corpus/TARGET). A crash, a leak, a sanitizer report, a timeout (10 s per input)
# or more than 2 GB of memory stops that target with its input saved as
# BUILD/artifacts/TARGET-crash-..., and the script exits non-zero after the others ran.
# Usage: fuzz/run_all.sh BUILD SECONDS [TARGET ...]
set -uo pipefail
build=${1:?usage: fuzz/run_all.sh BUILD SECONDS [TARGET ...]}
seconds=${2:?usage: fuzz/run_all.sh BUILD SECONDS [TARGET ...]}
shift 2
here=$(cd "$(dirname "$0")" && pwd)
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(fuzz_obj fuzz_ply fuzz_scene_json fuzz_ray_file fuzz_capi fuzz_accel_file)
mkdir -p "$build/artifacts"
failed=()
for t in "${targets[@]}"; do
  mkdir -p "$build/corpus/$t"
  echo "== $t: ${seconds} s"
  # Leak checks stay on; the loaders' inputs are small, so 2 GB is a runaway allocation.
  if ! "$build/fuzz/$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=2048 \
       -print_final_stats=1 -artifact_prefix="$build/artifacts/$t-" \
       "$build/corpus/$t" "$here/corpus/$t" 2>"$build/$t.log"; then
    failed+=("$t")
    tail -40 "$build/$t.log"
  fi
  grep -E "^stat::number_of_executed_units|^stat::peak_rss_mb|^INFO: seed corpus|^#[0-9]+.*DONE" "$build/$t.log" || true
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: findings in ${failed[*]} (inputs in $build/artifacts/; reproduce with $build/fuzz/TARGET FILE)"
  exit 1
fi
echo "fuzz: ${#targets[@]} targets, ${seconds} s each, no findings"
