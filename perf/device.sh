#!/bin/bash
# Thread scaling on a lent device machine (16 cores; Ubuntu, no Debian packages, no
# network). Two steps:
#
#   bash perf/device.sh pack     # here: fill .dev/ (git-ignored) with what travels
#   bash perf/device.sh run      # there, in the repository root (the device tool's run,
#                                # carry [".dev"]): the multi-threaded stream and the
#                                # Python package's nthreads, at 1, 2, 4, 8, 16 threads
#   bash perf/device.sh smt      # there: the CPU topology, and the stream rows that scale
#                                # least at 8 threads on 8 cores against 8 on 4 (siblings)
#   bash perf/device.sh sixteen  # there: 1 and 16 threads alternating, PAIRS times, for
#                                # batch and stream mode on every scene's diffuse and shadow
#                                # rays (the one-thread rate of a shared host drifts, so the
#                                # ratio is taken within pairs), then 2, 4 and 8 threads once
#
# What travels (about 55 MiB): the CLI and the Python extension built here, the Debian
# libraries they load, Debian's python3.11 with its standard library and NumPy (the
# extension is built for 3.11; the device's Python is another), and the benchmark meshes
# gzipped (the kitchen's OBJ alone is over the 64 MiB a call may carry). Results go to
# $OUT (the device tool's folder that comes back), or out/device without one.
set -euo pipefail
cd "$(dirname "$0")/.."
B=${B:-build/release}; SCENES=${SCENES:-../shared/scenes}
MESHES="kitchen_partial.obj conference.obj sponza_dabrovic.obj stanford-bunny.obj bun_zipper.ply"

pack() {
  grep -qx '/.dev/' .git/info/exclude 2>/dev/null || echo '/.dev/' >> .git/info/exclude
  rm -rf .dev && mkdir -p .dev/bin .dev/lib .dev/scenes .dev/py/bin .dev/py/lib .dev/py/site
  cp "$B/volley" .dev/bin/
  for l in libtbb.so.12 libtinyobjloader.so.2rc10 libstb.so.0 libblas.so.3; do cp -L "/lib/x86_64-linux-gnu/$l" .dev/lib/; done
  for m in $MESHES; do gzip -c "$SCENES/$m" > ".dev/scenes/$m.gz"; done
  cp /usr/bin/python3.11 .dev/py/bin/
  tar -C /usr/lib -cf - --exclude=test --exclude=idlelib --exclude=tkinter --exclude=lib2to3 --exclude=ensurepip \
    --exclude=__pycache__ --exclude='config-3.11*' --exclude=turtledemo python3.11 | tar -C .dev/py/lib -xf -
  tar -C /usr/lib/python3/dist-packages -cf - --exclude=__pycache__ --exclude=tests numpy | tar -C .dev/py/site -xf -
  cp -r "$B/python/volley" .dev/py/site/
  tar -C .dev -cJf .dev/py.tar.xz py && rm -rf .dev/py
  du -sh .dev
}

# Where `run` and `smt` work on the device machine.
out=${OUT:-out/device} scenes=/tmp/volley_scenes rays=/tmp/volley_device_rays

# Unpacks what pack made into the folders above (once per machine).
unpack() {
  mkdir -p "$out" "$scenes" "$rays" build/device
  cp .dev/bin/volley build/device/
  export LD_LIBRARY_PATH=$PWD/.dev/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}
  for m in $MESHES; do [ -f "$scenes/$m" ] || gzip -dc ".dev/scenes/$m.gz" > "$scenes/$m"; done
  [ -d /tmp/py ] || tar -C /tmp -xJf .dev/py.tar.xz
}

# The scene file of a benchmark name (bench/embree/NAME.json or scenes/NAME.json).
scene_of() { if [ -f "bench/embree/$1.json" ]; then echo "bench/embree/$1.json"; else echo "scenes/$1.json"; fi; }

# The ray file of scene $1, workload $2, made when missing: larger than the defaults
# (1280x960), so that 16 threads get milliseconds of work.
ray_file() {
  local f=$rays/$1_$2.vray
  [ -f "$f" ] || build/device/volley rays "$(scene_of "$1")" --scenes "$scenes" --workload "$2" --width 1280 \
    --height 960 -o "$f" >/dev/null
  echo "$f"
}

# Mrays/s of a trace (mode MODE, default batch) of scene $1, workload $2 on CPUs $3 with
# $4 threads, best of $5 repetitions; further arguments go to `volley trace`.
batch_rate() {
  local n=$1 w=$2 cpus=$3 threads=$4 reps=$5
  shift 5
  taskset -c "$cpus" build/device/volley trace "$(scene_of "$n")" --scenes "$scenes" --rays "$(ray_file "$n" "$w")" \
    --mode "${MODE:-batch}" --threads "$threads" --reps "$reps" "$@" | sed -nE 's/^trace: .*Mrays\/s=([0-9.]+).*/\1/p'
}

# Whether the logical CPUs are SMT siblings (the figures of `run` at 16 threads on a
# machine of 8 cores with two threads each could not reach 16x for compute-bound rays),
# and how fast one thread is on each CPU.
smt() {
  unpack
  { lscpu | grep -E "^(Model name|CPU\(s\)|Thread|Core|Socket|NUMA node\(s\)|L2|L3)"
    for c in /sys/devices/system/cpu/cpu[0-9]*; do
      echo "$(basename "$c"): siblings $(cat "$c/topology/thread_siblings_list" 2>/dev/null), core $(cat "$c/topology/core_id" 2>/dev/null)"
    done
    # One CPU per core, and the first 8 CPUs (siblings where there are any).
    local per_core first8 all n w extra spec t cpus sum cpu rate
    per_core=$(for c in /sys/devices/system/cpu/cpu[0-9]*; do cut -d, -f1 < "$c/topology/thread_siblings_list" | cut -d- -f1; done | sort -un | head -8 | paste -sd,)
    first8=$(seq -s, 0 7)
    all=0-$(($(nproc) - 1))
    echo "one CPU per core: $per_core; first eight: $first8"
    while read -r n w extra; do
      for spec in "1 0" "8 $per_core" "8 $first8" "$(nproc) $all"; do
        read -r t cpus <<< "$spec"
        # shellcheck disable=SC2086  # $extra is a list of options
        echo "$n $w, $t threads on CPUs $cpus: $(batch_rate "$n" "$w" "$cpus" "$t" 7 $extra) Mrays/s"
      done
    done <<< "bunny diffuse
sponza shadow --occluded
kitchen diffuse"
    # One thread pinned to each CPU in turn, then all threads three times: on a host whose
    # cores differ in speed, the ideal n-thread rate is the sum of the n one-thread rates.
    while read -r n w extra; do
      sum=0
      printf '%s %s, one thread on each CPU:' "$n" "$w"
      for cpu in $(seq 0 $(($(nproc) - 1))); do
        # shellcheck disable=SC2086
        rate=$(batch_rate "$n" "$w" "$cpu" 1 5 $extra)
        printf ' %s' "$rate"
        sum=$(awk -v a="$sum" -v b="$rate" 'BEGIN { print a + b }')
      done
      printf '; sum %s Mrays/s\n%s %s, %s threads:' "$sum" "$n" "$w" "$(nproc)"
      # shellcheck disable=SC2086
      for _ in 1 2 3; do printf ' %s' "$(batch_rate "$n" "$w" "$all" "$(nproc)" 7 $extra)"; done
      echo " Mrays/s"
    done <<< "bunny diffuse
sponza shadow --occluded"
  } 2>&1 | tee "$out/smt.md"
}

run() {
  unpack
  local n w
  for n in kitchen conference sponza bunny instances; do
    for w in diffuse shadow; do ray_file "$n" "$w" >/dev/null; done
  done
  B=build/device SCENES=$scenes RAYS=$rays PARTS=stream R=${R:-5} THREADS=${THREADS:-1 2 4 8 16} \
    bash perf/scaling.sh 2>&1 | tee "$out/stream_scaling.md"
  env -i PATH=/usr/bin:/bin LD_LIBRARY_PATH="$LD_LIBRARY_PATH" PYTHONHOME=/tmp/py PYTHONPATH=/tmp/py/site \
    /tmp/py/bin/python3.11 perf/python_overhead.py "$scenes/stanford-bunny.obj" --volley build/device/volley \
    --workload diffuse --threads "$(echo "${THREADS:-1 2 4 8 16}" | tr ' ' ,)" --reps 5 --rounds 2 2>&1 | tee "$out/python_scaling.md"
}

# The speedup of 16 threads over one, from one and sixteen threads alternating: each row
# prints every sample, the best over the best and the median of the paired ratios.
sixteen() {
  unpack
  local all n w extra mode one many ratios
  all=0-$(($(nproc) - 1))
  {
    lscpu | grep -E "^(Model name|CPU\(s\)|Thread|Core|Socket|L2|L3)"
    echo
    echo "| rays | mode | 1 thread (samples) | 16 threads (samples) | best / best | median of pairs | 2, 4, 8 threads |"
    echo "|---|---|---|---|---|---|---|"
    while read -r n w extra; do
      for mode in batch stream; do
        export MODE=$mode
        one=() many=() ratios=()
        for _ in $(seq "${PAIRS:-3}"); do
          # shellcheck disable=SC2086  # $extra is a list of options
          one+=("$(batch_rate "$n" "$w" "$all" 1 7 $extra)")
          # shellcheck disable=SC2086
          many+=("$(batch_rate "$n" "$w" "$all" "$(nproc)" 7 $extra)")
          ratios+=("$(awk -v a="${one[-1]}" -v b="${many[-1]}" 'BEGIN { printf "%.2f", b / a }')")
        done
        # shellcheck disable=SC2086
        echo "| $n $w | $mode | ${one[*]} | ${many[*]} | $(printf '%s\n' "${many[@]}" | sort -g | tail -1 | awk -v a="$(printf '%s\n' "${one[@]}" | sort -g | tail -1)" '{ printf "%.1fx", $1 / a }') | $(printf '%s\n' "${ratios[@]}" | sort -g | awk '{ v[NR] = $1 } END { printf "%.1fx", v[int((NR + 1) / 2)] }') | $(for t in 2 4 8; do batch_rate "$n" "$w" "$all" "$t" 5 $extra; done | paste -sd' ') |"
      done
    done <<< "kitchen diffuse
kitchen shadow --occluded
sponza diffuse
sponza shadow --occluded
conference diffuse
conference shadow --occluded
bunny diffuse
bunny shadow --occluded"
  } 2>&1 | tee "$out/sixteen.md"
}

case "${1:-}" in
  pack) pack ;;
  run) run ;;
  smt) smt ;;
  sixteen) sixteen ;;
  *) echo "usage: bash perf/device.sh pack|run|smt|sixteen (see the comments at its top)" >&2; exit 2 ;;
esac
