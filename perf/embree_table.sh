#!/bin/bash
# volley against Embree on the same rays, one thread: the table of perf/reports/embree.md, as
# markdown rows. Run on a quiet machine. Environment: B (build folder, default
# build/release), R (repetitions, default 9), SCENES (default ../shared/scenes),
# RAYS (where the ray files go, default /tmp/volley_embree_rays).
set -euo pipefail
cd "$(dirname "$0")/.."
B=${B:-build/release}; R=${R:-9}; SCENES=${SCENES:-../shared/scenes}; RAYS=${RAYS:-/tmp/volley_embree_rays}
mkdir -p "$RAYS"
# "scene workload mode embree volley ratio agreement" from a vs_embree line.
row() { grep "^vs_embree" | sed -E 's/.*mode=([a-z0-9_]+).*embree_Mrays\/s=([0-9.]+) volley_Mrays\/s=([0-9.]+) ratio=([0-9.]+) agree=([0-9.]+).*/\1 | \2 | \3 | \4 | \5 |/'; }
echo "| scene | rays | mode | Embree Mrays/s | volley Mrays/s | volley / Embree | agreement |"
echo "|---|---|---|---|---|---|---|"
for s in bench/embree/bunny.json scenes/sponza.json bench/embree/conference.json bench/embree/kitchen.json; do
  n=$(basename "$s" .json)
  for w in primary shadow diffuse; do
    [ -f "$RAYS/${n}_$w.vray" ] || "$B/volley" rays "$s" --scenes "$SCENES" --workload $w -o "$RAYS/${n}_$w.vray" >/dev/null
  done
  "$B/volley_vs_embree" "$s" --scenes "$SCENES" --rays "$RAYS/${n}_primary.vray" --modes packet,single --reps "$R" 2>&1 | row | sed "s/^/| $n | primary | /"
  "$B/volley_vs_embree" "$s" --scenes "$SCENES" --rays "$RAYS/${n}_shadow.vray" --modes occluded1,occluded16 --reps "$R" 2>&1 | row | sed "s/^/| $n | shadow | /"
  "$B/volley_vs_embree" "$s" --scenes "$SCENES" --rays "$RAYS/${n}_diffuse.vray" --modes single --reps "$R" 2>&1 | row | sed "s/^/| $n | diffuse | /"
done
