#!/usr/bin/env python3
"""ctest perf.synthetic_regression: a deliberate slowdown is caught, a rerun is not.

VOLLEY_BENCH_SLOWDOWN=F makes the benchmark code (never the library) do F times the
kernel work per iteration while counting the same items (bench/bench_common.h). On one
triangle kernel:

  timing:  6 repetitions unslowed, 6 with F = 2 -> perf/compare must call it `slower`
           and exit 1 (a regression beyond the 10% threshold, p < 0.05); the reverse
           comparison must call it `faster` and exit 0.
  icount:  two callgrind runs of the same build -> perf/compare must find the counts
           `same` and exit 0; with F = 1.25 -> `slower` and exit 1.

F = 2 for timing keeps the verdict robust on a loaded 2-core machine (the measured
spread there is 5-15%); the instruction counts need no margin. The icount half is
skipped without valgrind.

Usage: check_synthetic_regression.py VOLLEY_BENCH
"""
import json
import os
import sys
import tempfile
from pathlib import Path

from perf_test_util import compare, fail, have_valgrind, load, run_perf

KERNEL = "triangle/moller/sse4.2/1xblock/aimed"  # SSE4.2 is the x86-64-v2 baseline: always registered
FILTER = f"^{KERNEL}$"


def run(args, out: Path, slowdown: str = "") -> None:
    env = dict(os.environ)
    env.pop("VOLLEY_BENCH_SLOWDOWN", None)
    if slowdown:
        env["VOLLEY_BENCH_SLOWDOWN"] = slowdown
    r = run_perf(args + ["--out", str(out)], env=env)
    if r.returncode != 0 or not out.is_file():
        fail(f"perf/run failed (exit status {r.returncode})")
    errors = [b["error"] for b in load(out)["benchmarks"].values() if b.get("error")]
    if errors:
        fail(f"benchmark error: {errors}")


def merge(parts, out: Path) -> None:
    """One result with the repetitions of all `parts` (same benchmarks, same build)."""
    merged = load(parts[0])
    for part in parts[1:]:
        for name, b in load(part)["benchmarks"].items():
            m = merged["benchmarks"][name]
            for key in ("values", "cpu_time_ns", "real_time_ns", "iterations"):
                m[key] = m[key] + b[key]
    out.write_text(json.dumps(merged))


def main() -> int:
    bench = sys.argv[1]
    with tempfile.TemporaryDirectory(prefix="perf-synthetic-") as tmpdir:
        tmp = Path(tmpdir)
        # Base and slowed runs alternate, two repetitions at a time, and are merged into six
        # each: a slow spell of the shared machine then lands on both sides (run one after
        # the other, a spell during the base runs once made the 2x slowdown look faster).
        timing = ["--bench", bench, "--filter", FILTER, "--reps", "2", "--min-time", "0.05", "--warmup", "0.02"]
        for r in range(3):
            run(timing, tmp / f"base{r}.json")
            run(timing, tmp / f"slow{r}.json", slowdown="2")
        merge([tmp / f"base{r}.json" for r in range(3)], tmp / "base.json")
        merge([tmp / f"slow{r}.json" for r in range(3)], tmp / "slow.json")
        status, verdicts = compare(tmp / "base.json", tmp / "slow.json", "--no-noise")
        if status != 1 or verdicts.get(KERNEL) != "slower regression":
            fail("timing: the 2x slowdown was not reported as a regression")
        status, verdicts = compare(tmp / "slow.json", tmp / "base.json", "--no-noise")
        if status != 0 or verdicts.get(KERNEL) != "faster":
            fail("timing: removing the slowdown was not reported as faster")
        print("ok: timing compare caught the synthetic slowdown")

        if not have_valgrind():
            print("icount half skipped: valgrind is not installed")
            return 0
        icount = ["--callgrind", "--bench", bench, "--benchmarks", KERNEL]
        run(icount, tmp / "a.icount.json")
        run(icount, tmp / "b.icount.json")
        run(icount, tmp / "slow.icount.json", slowdown="1.25")
        status, verdicts = compare(tmp / "a.icount.json", tmp / "b.icount.json")
        if status != 0 or verdicts.get(KERNEL) != "same":
            fail("icount: two runs of the same build were not reported as the same")
        a, b = (load(tmp / f)["benchmarks"][KERNEL]["instructions"] for f in ("a.icount.json", "b.icount.json"))
        if a != b:
            fail(f"icount: two runs of the same build counted {a} and {b} instructions")
        status, verdicts = compare(tmp / "a.icount.json", tmp / "slow.icount.json")
        if status != 1 or verdicts.get(KERNEL) != "slower regression":
            fail("icount: the 1.25x slowdown was not reported as a regression")
        print("ok: instruction-count compare caught the synthetic slowdown and passed the rerun")
    return 0


if __name__ == "__main__":
    sys.exit(main())
