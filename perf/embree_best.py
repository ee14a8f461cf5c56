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
"""
import json
import os
import re
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


def main():
    only = set(filter(None, os.environ.get("ONLY", "").split(",")))
    os.makedirs(RAYS, exist_ok=True)
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
