#!/bin/bash
# Multi-core scaling: BVH build, rendering and tracing a ray file at 1, 2, 4, ... threads,
# as markdown rows for perf/scaling.md. Build threads are set by CPU affinity (taskset: the
# oneTBB builder uses the cores it may run on), render and trace threads by --threads.
# Each figure is the best of R runs. Environment: B (folder with the volley binary, default
# build/release), SCENES (default ../shared/scenes), RAYS (ray files, default
# /tmp/volley_embree_rays, made when missing), THREADS (default 1 2 4 ... up to nproc), R
# (default 3), SPP (render samples per pixel, default 8).
set -euo pipefail
cd "$(dirname "$0")/.."
B=${B:-build/release}; SCENES=${SCENES:-../shared/scenes}; RAYS=${RAYS:-/tmp/volley_embree_rays}
R=${R:-3}; SPP=${SPP:-8}
cores=$(nproc)
if [ -z "${THREADS:-}" ]; then
  THREADS=""; for ((t = 1; t <= cores; t *= 2)); do THREADS="$THREADS $t"; done
  [ $((t / 2)) -eq "$cores" ] || THREADS="$THREADS $cores"
fi
mkdir -p "$RAYS" out
best_min() { sort -g | head -1; }
best_max() { sort -g | tail -1; }

# "s" of `volley info`'s build line, best of R, on the first $1 cores.
build_s() {
  for _ in $(seq "$R"); do
    taskset -c "0-$(($1 - 1))" "$B/volley" info "$2" --scenes "$SCENES" | sed -nE 's/^build +([0-9.]+) s.*/\1/p'
  done | best_min
}
# Seconds of a render (its summary line), best of R.
render_s() {
  for _ in $(seq "$R"); do
    "$B/volley" render "$2" --scenes "$SCENES" --spp "$SPP" --threads "$1" -o out/scaling.png 2>&1 |
      sed -nE 's/.* rays in ([0-9.]+) s,.*/\1/p'
  done | best_min
}
# Mrays/s of tracing a ray file, best of R repetitions inside one run.
trace_mrays() {
  "$B/volley" trace "$2" --scenes "$SCENES" --rays "$3" --threads "$1" --reps "$R" $4 2>&1 |
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
for scene in bench/embree/kitchen.json bench/embree/conference.json; do
  base=""
  for t in $THREADS; do
    v=$(build_s "$t" "$scene"); base=${base:-$v}
    row "build $(basename "$scene" .json)" "$t" "$v" s "$base" 0
  done
done
for scene in scenes/sponza.json bench/embree/conference.json; do
  base=""
  for t in $THREADS; do
    v=$(render_s "$t" "$scene"); base=${base:-$v}
    row "render $(basename "$scene" .json), $SPP spp" "$t" "$v" s "$base" 0
  done
done
for spec in "kitchen diffuse single" "kitchen shadow single --occluded" "conference primary packet"; do
  read -r n w mode extra <<< "$spec"
  scene=bench/embree/$n.json
  [ -f "$RAYS/${n}_$w.vray" ] || "$B/volley" rays "$scene" --scenes "$SCENES" --workload "$w" -o "$RAYS/${n}_$w.vray" >/dev/null
  base=""
  for t in $THREADS; do
    v=$(trace_mrays "$t" "$scene" "$RAYS/${n}_$w.vray" "--mode $mode ${extra:-}"); base=${base:-$v}
    row "trace $n $w ($mode)" "$t" "$v" Mrays/s "$base" 1
  done
done
