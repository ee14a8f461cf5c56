#!/usr/bin/python3
"""volley's best against Embree's best on the same rays, one thread (issue #22's measure).

For every scene and workload, `volley_vs_embree` runs every mode of the workload (1-wide,
16-wide and stream calls; closest hit for primary and diffuse rays, occlusion for shadow
rays) twice: Embree and volley both built at medium quality, then both at high quality
(volley's high adds spatial splits, as Embree's does), alternating the two engines
repetition by repetition (FTZ/DAZ on for both). Embree's best is the fastest of its six
rows, volley's the fastest of its six (mode and quality named); the ratio is volley best /
Embree best. Beside it, what volley's single-ray walk visits per ray at the quality of its
best (`volley trace --stats`).

Prints a markdown table with the CPU model. Environment: B (build folder, default
build/release), R (repetitions, default 5), SCENES (default ../shared/scenes), RAYS (where
the ray files go, default /tmp/volley_embree_rays), ONLY (comma-separated scene names).

ICOUNT=1 counts instead of timing: `volley_vs_embree` once under callgrind per scene and
workload (both engines at medium quality, one untimed warm-up and one timed pass each),
and for every mode the instructions per ray inside each engine's entry (Embree's rtc
call; volley's Accel call), their ratio volley / Embree. Deterministic: a shared machine's
pace, which moves the timed table by 10-20% between runs, does not enter; latencies,
misses and mispredictions do not either. Needs valgrind; some 30-60 s per scene and
workload under callgrind (kitchen and Sponza longest).
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
B = os.environ.get("B", "build/release")
R = os.environ.get("R", "5")
SCENES_DIR = os.environ.get("SCENES", "../shared/scenes")
RAYS = os.environ.get("RAYS", "/tmp/volley_embree_rays")
SCENES = [
    ("bunny", "bench/embree/bunny.json"),
    ("dragon_100k", os.path.join(SCENES_DIR, "dragon_100k.obj")),
    ("sponza", "scenes/sponza.json"),
    ("conference", "bench/embree/conference.json"),
    ("kitchen", "bench/embree/kitchen.json"),
]
MODES = {"primary": "single,packet,stream", "shadow": "occluded1,occluded16,occluded_stream",
         "diffuse": "single,packet,stream"}


def run(args):
    done = subprocess.run(args, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if done.returncode != 0:
        sys.exit(f"embree_best: {' '.join(args)} failed ({done.returncode}):\n{done.stdout}")
    return done.stdout


def cpu_model():
    for line in open("/proc/cpuinfo"):
        if line.startswith("model name"):
            return line.split(":", 1)[1].strip()
    return "unknown CPU"


# volley's entry for each mode of volley_vs_embree (Embree's is the C call the result names).
VOLLEY_ENTRY = {
    "single": "volley::Accel::intersect(volley::Ray const&) const",
    "packet": "void volley::Accel::intersect<16>(volley::RayPacket<16> const&, volley::HitPacket<16>&) const",
    "stream": "volley::Accel::intersect(volley::Ray const*, unsigned long, volley::Hit*, int) const",
    "occluded1": "volley::Accel::occluded(volley::Ray const&) const",
    "occluded16": "unsigned int volley::Accel::occluded<16>(volley::RayPacket<16> const&) const",
    "occluded_stream": "volley::Accel::occluded(volley::Ray const*, unsigned long, unsigned char*, int) const",
}


def inclusive_costs(annotated):
    """{function: inclusive instructions} from `callgrind_annotate --inclusive=yes` output
    (lines 'COUNT (PERCENT)  FILE:FUNCTION [OBJECT]'); a function listed twice keeps its first."""
    costs = {}
    for line in annotated.splitlines():
        m = re.match(r"\s*([\d,]+) \([^)]*\)\s+[^:\s]*:(.*?)(?: \[[^\]]*\])?$", line)
        if m:
            costs.setdefault(m[2].strip(), int(m[1].replace(",", "")))
    return costs


def entry_cost(costs, name):
    """The cost of function `name`: a C function's bare name, a C++ one's whole signature."""
    if name in costs:
        return costs[name]
    sys.exit(f"embree_best: no callgrind cost for {name}")


def count(name, scene, workload, rays):
    """One row of the ICOUNT table: per mode, Embree's and volley's instructions per ray."""
    with tempfile.TemporaryDirectory() as tmp:
        out, json_out = os.path.join(tmp, "callgrind.out"), os.path.join(tmp, "result.json")
        run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", f"{B}/volley_vs_embree", scene,
             "--scenes", SCENES_DIR, "--rays", rays, "--modes", MODES[workload], "--reps", "1", "--json", json_out])
        result = json.load(open(json_out))
        costs = inclusive_costs(run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", out]))
    passes = 2 * result["ray_count"]  # the warm-up and the timed pass
    cells = []
    for m in result["modes"]:
        embree = entry_cost(costs, m["embree_call"]) / passes
        volley = entry_cost(costs, VOLLEY_ENTRY[m["mode"]]) / passes
        cells.append(f"{embree:.0f} / {volley:.0f} ({volley / embree:.3f})")
    print(f"| {name} | {workload} | " + " | ".join(cells) + " |", flush=True)


def main():
    only = set(filter(None, os.environ.get("ONLY", "").split(",")))
    os.makedirs(RAYS, exist_ok=True)
    icount = os.environ.get("ICOUNT", "0") == "1"
    if icount and not (shutil.which("valgrind") and shutil.which("callgrind_annotate")):
        sys.exit("embree_best: ICOUNT=1 needs valgrind and callgrind_annotate (apt-get install valgrind)")
    if icount:
        print(f"CPU: {cpu_model()}; instructions per ray under callgrind, medium quality; "
              "Embree / volley (volley / Embree)\n")
        print("| scene | rays | 1-wide | 16-wide | stream |")
        print("|---|---|---|---|---|")
    else:
        print(f"CPU: {cpu_model()}, {os.cpu_count()} cores; one thread; R = {R} repetitions per engine, mode and quality\n")
        print("| scene | rays | Embree best Mrays/s (call, quality) | volley best Mrays/s (mode, quality) | volley / Embree |"
              " nodes/ray | leaves/ray | triangles/ray | agreement | volley medium / high |")
        print("|---|---|---|---|---|---|---|---|---|---|")
    for name, scene in SCENES:
        if only and name not in only:
            continue
        for workload in ("primary", "shadow", "diffuse"):
            rays = os.path.join(RAYS, f"{name}_{workload}.vray")
            if not os.path.exists(rays):
                run([f"{B}/volley", "rays", scene, "--scenes", SCENES_DIR, "--workload", workload, "-o", rays])
            if icount:
                count(name, scene, workload, rays)
                continue
            embree, volley, agreement = (0.0, ""), (0.0, ""), 1.0
            volley_at = {}  # volley's best per quality
            for quality in ("medium", "high"):
                with tempfile.NamedTemporaryFile(suffix=".json") as out:
                    run([f"{B}/volley_vs_embree", scene, "--scenes", SCENES_DIR, "--rays", rays, "--modes",
                         MODES[workload], "--reps", R, "--quality", quality, "--volley-quality", quality,
                         "--json", out.name])
                    result = json.load(open(out.name))
                for m in result["modes"]:
                    embree = max(embree, (m["embree_mrays"], f"{m['embree_call']}, {quality}"))
                    volley = max(volley, (m["volley_mrays"], f"{m['mode']}, {quality}"))
                    volley_at[quality] = max(volley_at.get(quality, 0.0), m["volley_mrays"])
                    agreement = min(agreement, m["agreement"])
            stats = run([f"{B}/volley", "trace", scene, "--scenes", SCENES_DIR, "--rays", rays, "--reps", "1",
                         "--threads", "1", "--stats", "--quality", volley[1].split(", ")[1]] +
                        (["--occluded"] if workload == "shadow" else []))
            walk = re.search(r"nodes/ray=([0-9.]+) leaves/ray=([0-9.]+) triangles/ray=([0-9.]+)", stats)
            print(f"| {name} | {workload} | {embree[0]:.2f} ({embree[1]}) | {volley[0]:.2f} ({volley[1]}) | "
                  f"{volley[0] / embree[0]:.2f} | {float(walk[1]):.2f} | {float(walk[2]):.2f} | "
                  f"{float(walk[3]):.1f} | {agreement:.6f} | {volley_at['medium']:.2f} / {volley_at['high']:.2f} |",
                  flush=True)


if __name__ == "__main__":
    main()
