#!/usr/bin/env python3
"""ctest perf.gbench_compare: the stored results are Google Benchmark JSON.

- Google Benchmark's own compare.py (Debian libbenchmark-tools; it needs scipy) runs
  `compare.py benchmarks BASELINE BASELINE` on every committed baseline, and
  `compare.py benchmarks BASELINE NEW` on a fresh volley_bench result;
- perf/compare accepts that fresh, native Google Benchmark file;
- what perf/run writes by default (perf/results/, perf/history/) is git-ignored, so
  `make bench` and `make perf` leave the tree clean;
- on a machine without a timing baseline (VOLLEY_PERF_MACHINE names one), `perf/run
  --compare baseline` says so in one line and gives no timing verdicts.

Skipped (77) in part when compare.py or scipy is missing.

Usage: check_gbench_compare.py VOLLEY_BENCH
"""
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from perf_test_util import PERF, SKIP, fail

COMPARE_PY = Path("/usr/share/benchmark/compare.py")
FRESH_FILTER = "^triangle/(moller|watertight)/(scalar|sse4.2)/(1x1|1xblock)/aimed$"


def python_with_scipy() -> str:
    for exe in (sys.executable, "/usr/bin/python3"):
        if Path(exe).is_file() and subprocess.run([exe, "-c", "import scipy"], capture_output=True).returncode == 0:
            return exe
    return ""


def compare_py(python: str, base: Path, new: Path) -> str:
    r = subprocess.run([python, str(COMPARE_PY), "benchmarks", str(base), str(new)], capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"compare.py benchmarks {base} {new} exited with {r.returncode}:\n{r.stderr[-2000:]}")
    return r.stdout


def check_ignored() -> None:
    inside = subprocess.run(["git", "rev-parse", "--is-inside-work-tree"], cwd=PERF, capture_output=True, text=True)
    if inside.returncode != 0:
        print("not a git checkout: the ignore rules are not checked")
        return
    for path in ("perf/results/0123abc.json", "perf/history/some-machine.csv"):
        r = subprocess.run(["git", "check-ignore", "-q", path], cwd=PERF.parent)
        if r.returncode != 0:
            fail(f"{path} is not git-ignored: perf/run would leave the tree modified")
    print("ok: perf/results/ and perf/history/ are git-ignored")


def check_no_baseline(bench: str, tmp: Path) -> None:
    env = dict(os.environ, VOLLEY_PERF_MACHINE="a machine without a baseline")
    r = subprocess.run([sys.executable, str(PERF / "run"), "--quick", "--quiet", "--no-history", "--bench", bench,
                        "--filter", FRESH_FILTER, "--out", str(tmp / "other.json"), "--compare", "baseline"],
                       env=env, capture_output=True, text=True)
    lines = [line for line in r.stdout.splitlines() if line.strip()]
    if r.returncode != 0 or len(lines) != 1 or "no timing baseline for this machine" not in lines[0]:
        fail(f"perf/run --compare baseline on a machine without one (exit {r.returncode}):\n{r.stdout}{r.stderr}")
    print(f"ok: {lines[0]}")


def main() -> int:
    bench = sys.argv[1]
    check_ignored()
    baselines = sorted(p for p in (PERF / "baselines").rglob("*.json") if p.name != "noise.json")
    if not baselines:
        fail("no committed baseline")
    with tempfile.TemporaryDirectory(prefix="perf-gbench-") as tmp:
        fresh = Path(tmp) / "fresh.json"
        r = subprocess.run([bench, f"--benchmark_filter={FRESH_FILTER}", "--benchmark_repetitions=3",
                            "--benchmark_min_time=0.01", f"--benchmark_out={fresh}", "--benchmark_out_format=json"],
                           capture_output=True, text=True)
        if r.returncode != 0 or not fresh.is_file():
            fail(f"volley_bench exited with {r.returncode}: {r.stderr[-1000:]}")
        r = subprocess.run([sys.executable, str(PERF / "compare"), str(baselines[0]), str(fresh), "--no-noise"],
                           capture_output=True, text=True)
        print(r.stdout[-600:])
        if r.returncode not in (0, 1):
            fail(f"perf/compare could not read a native Google Benchmark file (exit {r.returncode}): {r.stderr}")
        check_no_baseline(bench, Path(tmp))
        python = python_with_scipy()
        if not COMPARE_PY.is_file() or not python:
            print(f"skipped in part: {COMPARE_PY} or scipy not installed (Debian libbenchmark-tools python3-scipy)")
            return SKIP
        for base in baselines:
            out = compare_py(python, base, base)
            print(f"ok: compare.py reads {base.relative_to(PERF)} ({out.count(chr(10))} lines)")
        timing = [b for b in baselines if b.name == "timing.json"]
        for base in timing[:1]:
            out = compare_py(python, base, fresh)
            if "triangle/moller/sse4.2/1xblock/aimed" not in out:
                fail(f"compare.py {base} fresh.json lists no common benchmark:\n{out[-1000:]}")
            print(f"ok: compare.py compares {base.relative_to(PERF)} with a fresh result")
    return 0


if __name__ == "__main__":
    sys.exit(main())
