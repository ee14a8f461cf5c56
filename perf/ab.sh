#!/bin/bash
# A/B of two volley executables on one ray file: ABBA pairs of `volley trace` runs (best of
# REPS repetitions each, one thread), then the best rate of each side, the ratio of the
# bests and the median of the pairs' ratios (B / A: above 1, B is faster).
#
#   perf/ab.sh A B SCENE RAYS ["TRACE OPTIONS"] [PAIRS]
#   perf/ab.sh /tmp/before build/release/volley bench/embree/kitchen.json \
#       /tmp/volley_embree_rays/kitchen_shadow.vray "--occluded --mode stream" 6
#
# ICOUNT=1 counts instead of timing: one callgrind pass of each executable, the
# instructions executed inside the traced calls (the CLI's timed tracer; no build, no load),
# and their ratio B / A. Deterministic, so it shows a change's work where this VM's
# timing noise hides it; it does not see latencies, misses or mispredictions.
#
# Refuses two byte-identical executables: the CLI's CMake target is `volley_cli` (its
# output is named `volley`); `cmake --build ... --target volley` builds the library alone
# and leaves the executable as it was, which once turned a session's A/Bs into
# measurements of the VM's noise (perf/reports/rays.md, session 27). Environment: REPS (default
# 20), SCENES (default ../shared/scenes), ICOUNT. On a shared VM, six pairs or more:
# identical binaries there gave medians of pairs from 0.86 to 1.08.
set -euo pipefail
if [ $# -lt 4 ]; then
  sed -n '2,/^set -euo/p' "$0" | sed '$d' | sed 's/^# \{0,1\}//'
  exit 2
fi
OPTIONS=${5:-} PAIRS=${6:-6} REPS=${REPS:-20}
for exe in "$1" "$2"; do
  [[ -f "$exe" && -x "$exe" ]] || { echo "ab.sh: $exe is not an executable" >&2; exit 2; }
done
for file in "$3" "$4"; do
  [ -f "$file" ] || { echo "ab.sh: $file: no such file" >&2; exit 2; }
done
[[ "$PAIRS" =~ ^[1-9][0-9]*$ ]] || { echo "ab.sh: PAIRS must be a positive integer, not '$PAIRS'" >&2; exit 2; }
# Paths taken here, the runs made from the repository root (where ../shared/scenes is).
A=$(realpath "$1") B=$(realpath "$2") SCENE=$(realpath "$3") RAYS=$(realpath "$4")
cd "$(dirname "$0")/.."
SCENES=$(realpath -m "${SCENES:-../shared/scenes}")
if cmp -s "$A" "$B"; then
  echo "ab.sh: $A and $B are the same executable (rebuild with --target volley_cli)" >&2
  exit 2
fi
if [ "${ICOUNT:-0}" = 1 ]; then
  command -v valgrind > /dev/null || { echo "ab.sh: ICOUNT=1 needs valgrind (apt-get install valgrind)" >&2; exit 2; }
  # The traced calls are the std::function tracers that cmd_trace.cpp's make_tracer returns;
  # --trace-children follows an executable that is a script exec'ing volley.
  count() {
    local out
    # shellcheck disable=SC2086  # OPTIONS is a list of options
    out=$(valgrind --tool=callgrind --callgrind-out-file=/dev/null --trace-children=yes \
          --toggle-collect='std::_Function_handler*make_tracer*' \
          "$1" trace "$SCENE" --scenes "$SCENES" --rays "$RAYS" $OPTIONS --reps 1 --threads 1 2>&1) || true
    sed -nE 's/^==[0-9]+== Collected : ([1-9][0-9]*)$/\1/p' <<< "$out" | tail -n 1 | grep . || { echo "$out" >&2; return 1; }
  }
  if ! a=$(count "$A") || ! b=$(count "$B"); then
    echo "ab.sh: a callgrind run counted nothing (its output above)" >&2
    exit 1
  fi
  echo "$(basename "$SCENE") $(basename "$RAYS") $OPTIONS: instructions A $a B $b, B/A $(python3 -c "print(f'{$b / $a:.4f}')")"
  exit 0
fi
# The rate of one run; the run's own output (warnings, errors) shown only when it has none.
rate() {
  local out
  # shellcheck disable=SC2086  # OPTIONS is a list of options
  out=$("$1" trace "$SCENE" --scenes "$SCENES" --rays "$RAYS" $OPTIONS --reps "$REPS" --threads 1 2>&1) || true
  sed -nE 's/^trace: .*Mrays\/s=([0-9.]+).*/\1/p' <<< "$out" | grep . || { echo "$out" >&2; return 1; }
}
as="" bs=""
for ((i = 0; i < PAIRS; ++i)); do
  if ((i % 2 == 0)); then
    a=$(rate "$A") && b=$(rate "$B")
  else
    b=$(rate "$B") && a=$(rate "$A")
  fi || { echo "ab.sh: a trace run printed no rate (its output above)" >&2; exit 1; }
  as="$as $a" bs="$bs $b"
done
python3 - "$as" "$bs" "$(basename "$SCENE") $(basename "$RAYS") $OPTIONS" <<'EOF'
import statistics, sys
a = [float(x) for x in sys.argv[1].split()]
b = [float(x) for x in sys.argv[2].split()]
pairs = [y / x for x, y in zip(a, b)]
print(f"{sys.argv[3]}: A {max(a):.2f} B {max(b):.2f} Mrays/s, B/A best {max(b) / max(a):.3f}, "
      f"median of {len(pairs)} pairs {statistics.median(pairs):.3f}")
EOF
