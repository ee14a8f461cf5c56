"""Shared code of perf/run, perf/compare and perf/plot: the result file format, the
thresholds file, the Mann-Whitney U test and the history file. Plain python3 (3.9+),
standard library only. perf/README.md describes the formats.
"""
from __future__ import annotations

import csv
import fnmatch
import json
import math
import os
import re
import sys
from dataclasses import dataclass
from pathlib import Path

PERF_DIR = Path(__file__).resolve().parent
ROOT = PERF_DIR.parent
RESULTS_DIR = PERF_DIR / "results"
BASELINES_DIR = PERF_DIR / "baselines"
HISTORY = PERF_DIR / "history.csv"
THRESHOLDS = PERF_DIR / "thresholds"

SCHEMA = "volley-perf-result/1"
HISTORY_FIELDS = ["date", "commit", "dirty", "label", "kind", "benchmark", "isa", "value", "unit",
                  "reps", "cv", "host", "cpu"]

# ---- result files ---------------------------------------------------------------------
#
# {
#   "schema": "volley-perf-result/1",
#   "kind": "timing" | "icount",
#   "context": {...},                      # commit, dirty, compiler, flags, ISA, CPU, scenes
#   "benchmarks": {
#     NAME: {"label": ISA, "metric": "items_per_second" | "cpu_time_ns" | "instructions",
#            "higher_is_better": bool,
#            "values": [one per repetition],   # the compared figure
#            "unit": "items/s" | "ns" | "instr/iteration",
#            "counters": {NAME: number},       # the benchmark's user counters (mean)
#            ... kind-specific detail (times, iterations, instructions per item) ...,
#            "error": "message" only when the benchmark was skipped}
#   },
#   "accuracy": {GROUP: {METRIC: number or string}}   # optional; any change is reported
# }


def load_result(path: Path) -> dict:
    with open(path) as f:
        data = json.load(f)
    if data.get("schema") != SCHEMA:
        raise ValueError(f"{path}: not a volley perf result (schema {data.get('schema')!r}, expected {SCHEMA})")
    return data


def save_json(path: Path, data: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    with open(tmp, "w") as f:
        json.dump(data, f, indent=1, sort_keys=False)
        f.write("\n")
    os.replace(tmp, path)


def resolve_result(arg: str) -> Path:
    """A result named on the command line: a path; a name in perf/results/,
    perf/baselines/ or perf/ (with or without .json: `baselines/timing`); or, in
    perf/results/, a prefix of a file name (a commit) or a run's label (`before` finds
    `<commit>[-dirty]-before.json`). Several matches: the newest, with a note."""
    p = Path(arg)
    if p.is_file():
        return p
    for folder in (RESULTS_DIR, BASELINES_DIR, PERF_DIR):
        for candidate in (folder / arg, folder / (arg + ".json")):
            if candidate.is_file():
                return candidate
    matches = set()
    if RESULTS_DIR.is_dir():
        matches = set(RESULTS_DIR.glob(arg + "*.json")) | set(RESULTS_DIR.glob(f"*-{arg}.json"))
    if not matches:
        raise FileNotFoundError(f"no result {arg!r} (a file, a name in {RESULTS_DIR} or {BASELINES_DIR}, "
                                "a commit prefix or a label)")
    newest = max(matches, key=lambda m: m.stat().st_mtime)
    if len(matches) > 1:
        print(f"note: {arg!r} matches {len(matches)} results, using the newest: {newest.name}", file=sys.stderr)
    return newest


def median(values: list[float]) -> float:
    v = sorted(values)
    n = len(v)
    if n == 0:
        return math.nan
    return v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2])


def cv(values: list[float]) -> float:
    """Coefficient of variation (sample standard deviation / mean); 0 for one value."""
    if len(values) < 2:
        return 0.0
    m = sum(values) / len(values)
    var = sum((x - m) ** 2 for x in values) / (len(values) - 1)
    return math.sqrt(var) / m if m else 0.0


# ---- Mann-Whitney U -------------------------------------------------------------------


def _exact_u_cdf(n1: int, n2: int) -> list[float]:
    """P(U <= u) for u = 0 .. n1*n2 under H0 (no ties): counts of the U statistic by the
    recurrence f(m, n, u) = f(m-1, n, u-n) + f(m, n-1, u) (Mann & Whitney 1947)."""
    # table[n][u] for the current m, built up from m = 0.
    maxu = n1 * n2
    prev = [[1] + [0] * maxu for _ in range(n2 + 1)]  # m = 0: U = 0 only
    for m in range(1, n1 + 1):
        cur = [[0] * (maxu + 1) for _ in range(n2 + 1)]
        cur[0][0] = 1  # n = 0: U = 0 only
        for n in range(1, n2 + 1):
            for u in range(maxu + 1):
                c = cur[n - 1][u]
                if u - n >= 0:
                    c += prev[n][u - n]
                cur[n][u] = c
        prev = cur
    counts = prev[n2]
    total = float(sum(counts))
    cdf, acc = [], 0
    for c in counts:
        acc += c
        cdf.append(acc / total)
    return cdf


def mann_whitney_u(x: list[float], y: list[float]) -> tuple[float, float] | None:
    """Two-sided Mann-Whitney U test of x against y. Returns (U of x, p-value), or None
    when either sample has fewer than 2 values. Follows scipy.stats.mannwhitneyu's
    default (method 'auto'), which Google Benchmark's compare.py calls: the exact
    distribution when there are no ties and a sample is smaller than 8, otherwise the
    normal approximation with tie correction and continuity correction."""
    n1, n2 = len(x), len(y)
    if n1 < 2 or n2 < 2:
        return None
    u1 = 0.0
    for a in x:
        for b in y:
            u1 += 1.0 if a > b else 0.5 if a == b else 0.0
    combined = sorted(x + y)
    has_ties = len(set(combined)) < len(combined)
    if not has_ties and min(n1, n2) < 8:
        cdf = _exact_u_cdf(n1, n2)
        u = int(round(u1))
        # P(U >= u) = 1 - P(U <= u - 1); the distribution is symmetric about n1 n2 / 2.
        lower = cdf[u]
        upper = 1.0 - (cdf[u - 1] if u > 0 else 0.0)
        return u1, min(1.0, 2.0 * min(lower, upper))
    n = n1 + n2
    mu = n1 * n2 / 2.0
    # Tie correction: sum over tie groups of (t^3 - t).
    tie_term, i = 0.0, 0
    while i < n:
        j = i
        while j + 1 < n and combined[j + 1] == combined[i]:
            j += 1
        t = j - i + 1
        tie_term += t ** 3 - t
        i = j + 1
    sigma = math.sqrt(n1 * n2 / 12.0 * ((n + 1) - tie_term / (n * (n - 1))))
    if sigma == 0:
        return u1, 1.0
    u_big = max(u1, n1 * n2 - u1)
    z = (u_big - mu - 0.5) / sigma
    p = math.erfc(z / math.sqrt(2.0))  # 2 * (1 - Phi(z))
    return u1, min(1.0, max(0.0, p))


# ---- thresholds -----------------------------------------------------------------------


@dataclass
class Rule:
    kind: str        # "time", "icount" or "accuracy"
    pattern: str     # fnmatch glob over the benchmark name (accuracy: GROUP/METRIC)
    tracked: bool    # a regression beyond `limit` fails compare
    limit: float     # time/icount: allowed slowdown in percent; accuracy: allowed increase
    line: int


def load_thresholds(path: Path = THRESHOLDS) -> list[Rule]:
    """Lines `KIND PATTERN LIMIT`, '#' comments; the first rule whose kind and pattern
    match decides. LIMIT: `N%` (time, icount: a slowdown of more than N percent is a
    regression), a number (accuracy: an increase of more than it is a regression),
    `untracked` (time, icount) or `report` (accuracy): shown, never fails."""
    rules = []
    with open(path) as f:
        for lineno, raw in enumerate(f, 1):
            line = raw.split("#", 1)[0].strip()
            if not line:
                continue
            parts = line.split()
            if len(parts) != 3:
                raise ValueError(f"{path}:{lineno}: expected `KIND PATTERN LIMIT`, found {raw.strip()!r}")
            kind, pattern, limit = parts
            if kind not in ("time", "icount", "accuracy"):
                raise ValueError(f"{path}:{lineno}: kind must be time, icount or accuracy, found {kind!r}")
            if limit in ("untracked", "report"):
                rules.append(Rule(kind, pattern, False, math.inf, lineno))
                continue
            m = re.fullmatch(r"\+?([0-9]*\.?[0-9]+)(%?)", limit)
            if not m or (kind != "accuracy" and not m.group(2)):
                raise ValueError(f"{path}:{lineno}: limit must be N% (time, icount), a number (accuracy), "
                                 f"'untracked' or 'report', found {limit!r}")
            rules.append(Rule(kind, pattern, True, float(m.group(1)), lineno))
    return rules


def find_rule(rules: list[Rule], kind: str, name: str) -> Rule | None:
    for r in rules:
        if r.kind == kind and fnmatch.fnmatchcase(name, r.pattern):
            return r
    return None


# ---- history --------------------------------------------------------------------------


def append_history(result: dict, path: Path = HISTORY) -> int:
    """Appends one line per benchmark of `result` (its median) to the history CSV."""
    ctx = result["context"]
    rows = []
    for name, b in sorted(result["benchmarks"].items()):
        if b.get("error") or not b.get("values"):
            continue
        if result["kind"] == "icount":
            value, unit = b.get("instructions_per_item") or median(b["values"]), \
                "instr/item" if b.get("instructions_per_item") else b["unit"]
        else:
            value, unit = median(b["values"]), b["unit"]
        rows.append({
            "date": ctx.get("date", ""), "commit": ctx.get("commit_short", ""),
            "dirty": int(bool(ctx.get("dirty"))), "label": ctx.get("label", ""),
            "kind": result["kind"], "benchmark": name, "isa": b.get("label", ""),
            "value": f"{value:.6g}", "unit": unit, "reps": len(b["values"]),
            "cv": f"{cv(b['values']):.4f}", "host": ctx.get("host", ""), "cpu": ctx.get("cpu_model", ""),
        })
    new_file = not path.exists() or path.stat().st_size == 0
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=HISTORY_FIELDS)
        if new_file:
            w.writeheader()
        w.writerows(rows)
    return len(rows)


def read_history(path: Path = HISTORY) -> list[dict]:
    if not path.exists():
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))
