#!/bin/bash
# Multi-core scaling: BVH build, rendering and tracing a ray file at 1, 2, 4, ... threads,
# as markdown rows for perf/reports/scaling.md. Build threads are set by CPU affinity (taskset: the
# oneTBB builder uses the cores it may run on), render and trace threads by --threads.
# Each figure is the best of R runs. Environment: B (folder with the volley binary, default
# build/release), SCENES (default ../shared/scenes), RAYS (ray files, default
# /tmp/volley_embree_rays, made when missing), THREADS (default 1 2 4 ... up to nproc), R
# (default 3), SPP (render samples per pixel, default 8), PARTS (any of build render trace
# stream, default all four; stream: the multi-threaded stream, `volley trace --mode batch`,
# the library spreading one call's rays over the threads).
set -euo pipefail
cd "$(dirname "$0")/.."
B=${B:-build/release}; SCENES=${SCENES:-../shared/scenes}; RAYS=${RAYS:-/tmp/volley_embree_rays}
R=${R:-3}; SPP=${SPP:-8}; PARTS=${PARTS:-build render trace stream}
cores=$(nproc)
if [ -z "${THREADS:-}" ]; then
  THREADS=""; for ((t = 1; t <= cores; t *= 2)); do THREADS="$THREADS $t"; done
  [ $((t / 2)) -eq "$cores" ] || THREADS="$THREADS $cores"
fi
mkdir -p "$RAYS" out
best_min() { sort -g | head -1; }
best_max() { sort -g | tail -1; }

# "s" of `volley info`'s build line for scene $1 on the first $2 cores, best of R.
build_s() {
  for _ in $(seq "$R"); do
    taskset -c "0-$(($2 - 1))" "$B/volley" info "$1" --scenes "$SCENES" | sed -nE 's/^build +([0-9.]+) s.*/\1/p'
  done | best_min
}
# Seconds of a render of scene $1 on $2 threads (its summary line), best of R.
render_s() {
  for _ in $(seq "$R"); do
    "$B/volley" render "$1" --scenes "$SCENES" --spp "$SPP" --threads "$2" -o out/scaling.png 2>&1 |
      sed -nE 's/.* rays in ([0-9.]+) s,.*/\1/p'
  done | best_min
}
# Mrays/s of tracing scene $1 with ray file $2 and options $3 on $4 threads, best of R
# repetitions inside one run.
trace_mrays() {
  # shellcheck disable=SC2086  # $3 is a list of options
  "$B/volley" trace "$1" --scenes "$SCENES" --rays "$2" --threads "$4" --reps "$R" $3 2>&1 |
    sed -nE 's/^trace: .*Mrays\/s=([0-9.]+).*/\1/p'
}

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
echo
echo "| what | threads | result | speedup over 1 thread | per thread |"
echo "|---|---|---|---|---|"
row() {  # label threads value unit base higher_is_better
  awk -v l="$1" -v t="$2" -v v="$3" -v u="$4" -v b="$5" -v h="$6" 'BEGIN {
    s = h ? v / b : b / v; printf "| %s | %d | %s %s | %.2f | %.2f |\n", l, t, v, u, s, s / t }'
}
# One row per thread count: label $1, unit $2, $3 = 1 when higher is better, then a
# command that prints the value given the thread count as its last argument.
sweep() {
  local label=$1 unit=$2 higher=$3 base="" t v
  shift 3
  for t in $THREADS; do
    v=$("$@" "$t")
    base=${base:-$v}
    row "$label" "$t" "$v" "$unit" "$base" "$higher"
  done
}
part() { [[ " $PARTS " == *" $1 "* ]]; }
# Trace rows: "scene workload mode [options]" per line of $1, scenes from bench/embree or scenes/.
trace_sweeps() {
  local n w mode extra scene
  while read -r n w mode extra; do
    scene=bench/embree/$n.json; [ -f "$scene" ] || scene=scenes/$n.json
    [ -f "$RAYS/${n}_$w.vray" ] || "$B/volley" rays "$scene" --scenes "$SCENES" --workload "$w" -o "$RAYS/${n}_$w.vray" >/dev/null
    sweep "trace $n $w ($mode${extra:+ $extra})" Mrays/s 1 trace_mrays "$scene" "$RAYS/${n}_$w.vray" "--mode $mode ${extra:-}"
  done <<< "$1"
}
part build && for scene in bench/embree/kitchen.json bench/embree/conference.json; do
  sweep "build $(basename "$scene" .json)" s 0 build_s "$scene"
done
part render && for scene in scenes/sponza.json bench/embree/conference.json; do
  sweep "render $(basename "$scene" .json), $SPP spp" s 0 render_s "$scene"
done
part trace && trace_sweeps "kitchen diffuse single
kitchen shadow single --occluded
conference primary packet"
part stream && trace_sweeps "kitchen diffuse batch
kitchen shadow batch --occluded
sponza diffuse batch
sponza shadow batch --occluded
conference diffuse batch
bunny diffuse batch
instances diffuse batch"
