#!/usr/bin/env python3
"""ctest perf.icount_vs_baseline: the instruction counts of a few triangle kernels against
the committed baseline of their ISA path (perf/baselines/icount/ISA.json), through perf/run --callgrind and
perf/compare with the checked-in thresholds. Deterministic, so it may fail a build: a
kernel that now executes more than 1% more instructions than the baseline is a
regression (update the baseline with the change if it is deliberate: perf/README.md).

Skipped (exit 77) without valgrind, without AVX2, or when the baseline was recorded with
another compiler or other flags (instruction counts are only comparable within one
toolchain).

Usage: check_icount_baseline.py VOLLEY_BENCH
"""
import sys
import tempfile
from pathlib import Path

from perf_test_util import PERF, SKIP, compare, have_valgrind, load, run_perf

PATHS = {"avx2": ["triangle/moller/avx2/1xblock/aimed", "triangle/watertight/avx2/16xblock/aimed"],
         "sse4.2": ["triangle/watertight/sse4.2/16xblock/aimed"],
         "scalar": ["triangle/watertight/scalar/1x1/aimed"]}


def main() -> int:
    bench = sys.argv[1]
    if not have_valgrind():
        print("skipped: valgrind is not installed (Debian package valgrind)")
        return SKIP
    statuses = []
    for isa, kernels in PATHS.items():
        print(f"--- ISA path {isa}")
        statuses.append(check_path(bench, isa, kernels))
    if 1 in statuses:
        return 1
    return SKIP if all(s == SKIP for s in statuses) else 0


def check_path(bench: str, isa: str, kernels: list[str]) -> int:
    baseline_file = PERF / "baselines" / "icount" / f"{isa}.json"
    baseline = load(baseline_file)
    missing = [k for k in kernels if k not in baseline["benchmarks"]]
    if missing:
        print(f"FAIL: the baseline lacks {missing}")
        return 1
    with tempfile.TemporaryDirectory(prefix="perf-icount-") as tmp:
        out = Path(tmp) / "icount.json"
        r = run_perf(["--callgrind", "--isa", isa, "--bench", bench, "--benchmarks", ",".join(kernels),
                      "--out", str(out)])
        if not out.is_file():
            print(f"FAIL: perf/run --callgrind wrote no result (exit status {r.returncode})")
            return 1
        new = load(out)
        errors = {n: b["error"] for n, b in new["benchmarks"].items() if b.get("error")}
        if errors and all("no such benchmark" in e for e in errors.values()):
            print(f"skipped: the {isa} kernels are not registered on this CPU")
            return SKIP
        if errors:
            print(f"FAIL: {errors}")
            return 1
        b, n = baseline["context"], new["context"]
        for key in ("compiler_version", "flags", "cmake_cxx_flags"):
            if b.get(key) != n.get(key):
                print(f"skipped: baseline {key} {b.get(key)!r} differs from this build's {n.get(key)!r}")
                return SKIP
        status, verdicts = compare(baseline_file, out, "--filter", "^(" + "|".join(kernels) + ")$")
    if len(verdicts) != len(kernels):
        print(f"FAIL: compared {sorted(verdicts)}, expected {kernels}")
        return 1
    return 0 if status == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
