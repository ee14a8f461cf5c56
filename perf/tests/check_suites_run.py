#!/usr/bin/env python3
"""ctest perf.suites_run: every volley_bench suite builds and runs. One iteration of every
registered benchmark through perf/run --smoke (no timing verdict): the result must hold
the four suites (triangle kernels, traversal, build, render), each benchmark with a
positive figure and no error.

Usage: check_suites_run.py VOLLEY_BENCH
"""
import sys
import tempfile
from pathlib import Path

from perf_test_util import SKIP, fail, load, run_perf

SUITES = ("triangle/", "traversal/", "build/", "render/")


def main() -> int:
    bench = sys.argv[1]
    with tempfile.TemporaryDirectory(prefix="perf-suites-") as tmp:
        out = Path(tmp) / "smoke.json"
        r = run_perf(["--smoke", "--bench", bench, "--out", str(out)])
        if not out.is_file():
            fail(f"perf/run --smoke wrote no result (exit status {r.returncode})")
        result = load(out)
    benchmarks = result["benchmarks"]
    errors = {n: b["error"] for n, b in benchmarks.items() if b.get("error")}
    for n, e in errors.items():
        print(f"error: {n}: {e}")
    for suite in SUITES:
        names = [n for n in benchmarks if n.startswith(suite)]
        print(f"{suite:<11} {len(names):4d} benchmarks")
        if not names:
            fail(f"no {suite}* benchmark ran")
    bad = [n for n, b in benchmarks.items() if not b.get("error") and not (b["values"] and b["values"][0] > 0)]
    if bad:
        fail(f"{len(bad)} benchmarks have no positive figure: {bad[:5]}")
    # Without the shared meshes (../shared/scenes, VOLLEY_SCENES) the scenes that use them
    # cannot load (a scene file names a missing "shared mesh"; the load and refit suites
    # name the mesh path itself): everything else must still run, and the test reports
    # itself skipped.
    def needs_meshes(e: str) -> bool:
        return "not found" in e and ("shared mesh" in e or "/shared/scenes/" in e)

    no_meshes = all(needs_meshes(e) for e in errors.values())
    if errors and not no_meshes:
        fail(f"{len(errors)} benchmarks reported an error")
    missing = [k for k, v in result["context"].get("scenes", {}).items() if v.get("missing")]
    if errors:
        print(f"skipped in part: {len(errors)} benchmarks need the shared meshes, not found ({missing[:3]} ...)")
        return SKIP
    if missing:
        fail(f"scene files recorded as missing: {missing}")
    if not result["context"].get("compiler_version"):
        fail("the context has no compiler version")
    print(f"ok: {len(benchmarks)} benchmarks ran once each")
    return 0


if __name__ == "__main__":
    sys.exit(main())
