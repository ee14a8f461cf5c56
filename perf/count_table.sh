#!/bin/bash
# volley's counting (count_intersections, intersect_all) against Embree's filter-function
# counting on the same rays, one thread: the table of perf/reports/queries.md, as markdown rows.
# Embree at its best: the faster of build quality medium and high and of rtcIntersect1 and
# rtcIntersect16; volley at its best of the single-ray and batch forms. Run on a quiet
# machine. Environment as perf/embree_table.sh: B, R, SCENES, RAYS.
set -euo pipefail
cd "$(dirname "$0")/.."
B=${B:-build/release}; R=${R:-9}; SCENES=${SCENES:-../shared/scenes}; RAYS=${RAYS:-/tmp/volley_embree_rays}
mkdir -p "$RAYS"
echo "| scene | rays | Embree best Mrays/s (call, quality) | volley best Mrays/s (call) | volley / Embree | same count | volley all hits Mrays/s |"
echo "|---|---|---|---|---|---|---|"
for s in bench/embree/bunny.json bench/embree/conference.json bench/embree/kitchen.json; do
  n=$(basename "$s" .json)
  for w in primary shadow diffuse; do
    [ -f "$RAYS/${n}_$w.vray" ] || "$B/volley" rays "$s" --scenes "$SCENES" --workload $w -o "$RAYS/${n}_$w.vray" >/dev/null
    out=""
    for q in medium high; do
      out+=$("$B/volley_vs_embree" "$s" --scenes "$SCENES" --rays "$RAYS/${n}_$w.vray" --modes count1,count16,all1 \
               --reps "$R" --quality $q 2>&1 | grep "^vs_embree" | sed "s/^/quality=$q /")$'\n'
    done
    # The best of each side over modes and qualities (the ratio of bests: both sides at their best).
    echo "$out" | awk -v scene="$n" -v rays="$w" '
      /vs_embree/ {
        for (i = 1; i <= NF; i++) { split($i, kv, "="); f[kv[1]] = kv[2] }
        if (f["mode"] == "all1") { if (f["volley_Mrays/s"] > all) all = f["volley_Mrays/s"]; next }
        if (f["embree_Mrays/s"] > e) { e = f["embree_Mrays/s"]; ec = (f["mode"] == "count1" ? "1" : "16") ", " f["quality"] }
        if (f["volley_Mrays/s"] > v) { v = f["volley_Mrays/s"]; vc = (f["mode"] == "count1" ? "single" : "batch") }
        agree = f["agree"]
      }
      END { printf "| %s | %s | %.2f (%s) | %.2f (%s) | %.2fx | %.4f%% | %.2f |\n", scene, rays, e, ec, v, vc, v / e, 100 * agree, all }'
  done
done
