"""Shared code of perf/run, perf/compare, perf/steps, perf/noise and perf/plot: the
machine a result belongs to, the result files (Google Benchmark JSON, and the older
volley-perf-result/1), the thresholds file, the Mann-Whitney U test and the history.
Plain python3 (3.9+), standard library only. perf/README.md describes the formats.
"""
from __future__ import annotations

import csv
import datetime as dt
import fnmatch
import json
import math
import os
import platform
import re
import sys
from dataclasses import dataclass
from pathlib import Path

PERF_DIR = Path(__file__).resolve().parent
ROOT = PERF_DIR.parent
RESULTS_DIR = PERF_DIR / "results"
BASELINES_DIR = PERF_DIR / "baselines"
HISTORY_DIR = PERF_DIR / "history"
THRESHOLDS = PERF_DIR / "thresholds"

SCHEMA = "volley-perf-result/1"
HISTORY_FIELDS = ["date", "commit", "dirty", "label", "kind", "benchmark", "isa", "value", "unit",
                  "reps", "cv", "host", "cpu", "machine", "commit_date"]
ICOUNT_ISAS = ("avx2", "sse4.2", "scalar")  # what valgrind can run


# ---- machines -------------------------------------------------------------------------
#
# Timings compare only within one kind of machine. A kind is the CPU model string, its
# family and model numbers (virtual machines often report only "AMD EPYC", for Zen 3 and
# Zen 5 alike) and the widest ISA volley runs there; VOLLEY_PERF_MACHINE names it instead.


def slug(text: str) -> str:
    return re.sub(r"[^a-z0-9]+", "-", text.lower()).strip("-") or "unknown"


def machine_key(cpu_model: str, family: str, model: str, isa: str) -> str:
    numbers = f"-f{family}m{model}" if family or model else ""
    return f"{slug(cpu_model)}{numbers}-{slug(isa)}"


def this_machine(cpuinfo: str | None = None) -> dict:
    """CPU model, family, model number, widest ISA and the machine key, from
    /proc/cpuinfo (or the text given). VOLLEY_PERF_MACHINE, when set, is the key."""
    cpuinfo_given = cpuinfo
    if cpuinfo is None:
        try:
            cpuinfo = Path("/proc/cpuinfo").read_text()
        except OSError:
            cpuinfo = ""

    def field(name: str) -> str:
        m = re.search(rf"^{name}\s*:\s*(.*)$", cpuinfo, re.M)
        return m.group(1).strip() if m else ""

    flags = set(field("flags").split())
    isa = "avx512" if {"avx512f", "avx512bw", "avx512dq", "avx512vl"} <= flags else \
        "avx2" if {"avx2", "fma"} <= flags else "sse4.2" if "sse4_2" in flags else "scalar"
    model_name = field("model name") or platform.processor() or platform.machine()
    family, model = field("cpu family"), field("model")
    text = f"{model_name}" + (f", family {family} model {model}" if family else "") + f", {isa}"
    key = machine_key(model_name, family, model, isa)
    named = os.environ.get("VOLLEY_PERF_MACHINE", "") if cpuinfo_given is None else ""
    if named:  # the user's name for a machine the CPU fields cannot tell apart
        key, text = slug(named), f"{text} (VOLLEY_PERF_MACHINE={named})"
    return {"cpu_model": model_name, "cpu_family": family, "cpu_model_number": model, "cpu_flags_isa": isa,
            "machine": key, "machine_text": text}


def result_machine(ctx: dict) -> str:
    """The machine key of a result's context ('' when it does not say)."""
    if ctx.get("machine"):
        return ctx["machine"]
    if ctx.get("cpu_model"):
        isa = ctx.get("cpu_flags_isa") or ctx.get("isa", "")
        return machine_key(ctx["cpu_model"], ctx.get("cpu_family", ""), ctx.get("cpu_model_number", ""),
                           isa.split()[0] if isa else "")
    return ""


def timing_baseline(machine: str) -> Path:
    return BASELINES_DIR / machine / "timing.json"


def noise_file(machine: str) -> Path:
    return BASELINES_DIR / machine / "noise.json"


def icount_baseline(isa: str = "avx2") -> Path:
    return BASELINES_DIR / "icount" / f"{isa}.json"


NOISE_FACTOR = 3.0  # a timing change must exceed this many run-to-run spreads of its machine


def read_noise(path: Path) -> dict[str, float]:
    """{benchmark: run-to-run spread} of a noise file (perf/noise); {} when there is none."""
    if not path.is_file():
        return {}
    data = json.loads(path.read_text())
    return {name: float(b["spread"]) for name, b in data.get("benchmarks", {}).items() if "spread" in b}


def machine_noise(machine: str) -> dict[str, float]:
    return read_noise(noise_file(machine))


def history_file(machine: str) -> Path:
    return HISTORY_DIR / f"{machine or 'unknown'}.csv"

# ---- result files ---------------------------------------------------------------------
#
# Stored results and baselines are Google Benchmark JSON, as volley_bench writes it with
# --benchmark_out_format=json (every repetition, then the aggregates), so that Google
# Benchmark's compare.py reads them. volley's facts sit in the context block:
#
#   "context": {...Google Benchmark's own keys...,
#               "volley": {"kind": "timing" | "icount", "commit": ..., "dirty": ...,
#                          "machine": KEY, "cpu_model": ..., "flags": {...}, "scenes": {...}, ...}}
#   "accuracy": {GROUP: {METRIC: value}}       (optional; compare.py ignores it)
#
# Instruction-count results (perf/run --callgrind) hold one entry per benchmark whose
# real_time and cpu_time are the instructions of one iteration (time_unit "ns" only
# because compare.py needs a unit: context.volley.time_fields says so), and the count as
# the counter "instructions". Results written before (schema volley-perf-result/1) stay
# readable. Either way, load_result gives the form the tools work on:
#
#   {"kind": ..., "context": {volley's facts},
#    "benchmarks": {NAME: {"label": ISA, "metric": "items_per_second" | "cpu_time_ns" | "instructions",
#                          "higher_is_better": bool, "values": [one per repetition], "unit": ...,
#                          "counters": {NAME: mean}, "error": "message" when it was skipped}},
#    "accuracy": {...}}

ICOUNT_TIME_FIELDS = "instructions per iteration (callgrind), not nanoseconds"
_GBENCH_FIELDS = {"name", "run_name", "run_type", "family_index", "per_family_instance_index", "repetitions",
                  "repetition_index", "threads", "iterations", "real_time", "cpu_time", "time_unit", "label",
                  "items_per_second", "bytes_per_second", "error_occurred", "error_message", "aggregate_name",
                  "aggregate_unit"}
_TO_NS = {"ns": 1.0, "us": 1e3, "ms": 1e6, "s": 1e9}


def load_result(path: Path) -> dict:
    with open(path) as f:
        data = json.load(f)
    if not isinstance(data, dict):
        raise ValueError(f"{path}: not a result (a JSON object with a benchmarks list)")
    if data.get("schema") == SCHEMA:
        return data
    if isinstance(data.get("benchmarks"), list):
        return from_gbench(data)
    raise ValueError(f"{path}: neither Google Benchmark JSON (a benchmarks list) nor a volley perf result "
                     f"(schema {data.get('schema')!r})")


def from_gbench(gb: dict) -> dict:
    """The tools' form of a Google Benchmark JSON result (volley's or anyone's)."""
    gctx = gb.get("context", {}) if isinstance(gb.get("context"), dict) else {}
    ctx = dict(gctx.get("volley") or {})
    if not ctx:  # plain Google Benchmark output: keep what it says about the run
        ctx = {"date": gctx.get("date", ""), "host": gctx.get("host_name", ""),
               "bench": gctx.get("executable", ""), "kind": "timing"}
    kind = ctx.get("kind", "timing")
    benchmarks = icount_benchmarks(gb) if kind == "icount" else timing_benchmarks(gb)
    return {"schema": SCHEMA, "kind": kind, "context": ctx, "benchmarks": benchmarks,
            "accuracy": gb.get("accuracy", {})}


def _runs(gb: dict) -> dict[str, list[dict]]:
    """Repetitions per benchmark; a file of aggregates only gives its medians."""
    runs: dict[str, list[dict]] = {}
    medians: dict[str, list[dict]] = {}
    for b in gb.get("benchmarks", []):
        name = b.get("run_name", b.get("name", ""))
        if b.get("run_type", "iteration") == "iteration":
            runs.setdefault(name, []).append(b)
        elif b.get("aggregate_name") == "median":
            medians.setdefault(name, []).append(b)
    for name, rows in medians.items():
        runs.setdefault(name, rows)
    return runs


def timing_benchmarks(gb: dict) -> dict:
    """Per benchmark: the repetitions' items/s (or CPU time when it counts no items)."""
    out: dict[str, dict] = {}
    for name, rows in _runs(gb).items():
        e = {"label": rows[0].get("label", ""), "values": [], "cpu_time_ns": [], "real_time_ns": [],
             "iterations": [], "counters": {}}
        counters: dict[str, list[float]] = {}
        for b in rows:
            if b.get("error_occurred"):
                e["error"] = b.get("error_message", "error")
                continue
            f = _TO_NS.get(b.get("time_unit", "ns"), 1.0)
            e["cpu_time_ns"].append(b["cpu_time"] * f)
            e["real_time_ns"].append(b["real_time"] * f)
            e["iterations"].append(b.get("iterations", 0))
            if "items_per_second" in b:
                e["metric"], e["unit"], e["higher_is_better"] = "items_per_second", "items/s", True
                e["values"].append(b["items_per_second"])
            else:
                e["metric"], e["unit"], e["higher_is_better"] = "cpu_time_ns", "ns", False
                e["values"].append(b["cpu_time"] * f)
            for k, v in b.items():
                if k not in _GBENCH_FIELDS and isinstance(v, (int, float)):
                    counters.setdefault(k, []).append(v)
        e["counters"] = {k: sum(v) / len(v) for k, v in counters.items()}
        out[name] = e
    return out


def icount_benchmarks(gb: dict) -> dict:
    out: dict[str, dict] = {}
    for name, rows in _runs(gb).items():
        b = rows[0]
        if b.get("error_occurred"):
            out[name] = {"label": b.get("label", ""), "error": b.get("error_message", "error"), "values": []}
            continue
        e = {"label": b.get("label", ""), "metric": "instructions", "unit": "instr/iteration",
             "higher_is_better": False, "values": [b["cpu_time"]], "instructions": b.get("instructions"),
             "iterations": b.get("iterations", 1), "counters": {}}
        for k in ("items", "instructions_per_item"):
            if k in b:
                e[k] = b[k]
        for k, v in b.items():
            if k not in _GBENCH_FIELDS and k not in ("instructions", "items", "instructions_per_item") \
                    and isinstance(v, (int, float)):
                e["counters"][k] = v
        out[name] = e
    return out


def icount_gbench(results: dict, gctx: dict, ctx: dict) -> dict:
    """Google Benchmark JSON of instruction counts (see above), from perf/run's results."""
    entries = []
    for i, (name, e) in enumerate(results.items()):
        row = {"name": name, "family_index": i, "per_family_instance_index": 0, "run_name": name,
               "run_type": "iteration", "repetitions": 1, "repetition_index": 0, "threads": 1,
               "iterations": e.get("iterations", 1), "label": e.get("label", "")}
        if e.get("error"):
            row.update(error_occurred=True, error_message=e["error"])
        else:
            row.update(real_time=e["values"][0], cpu_time=e["values"][0], time_unit="ns",
                       instructions=e["instructions"])
            for k in ("items", "instructions_per_item"):
                if k in e:
                    row[k] = e[k]
            row.update(e.get("counters", {}))
        entries.append(row)
    context = {k: v for k, v in gctx.items() if not k.startswith("volley_scene:")}
    context["volley"] = dict(ctx, kind="icount", time_fields=ICOUNT_TIME_FIELDS)
    return {"context": context, "benchmarks": entries}


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
#
# One CSV per machine in perf/history/ (git-ignored: every run appends to it), one line
# per benchmark and run: a series per benchmark and machine. The committed record is the
# baselines and the pictures perf/plot draws from the history.


def baseline_for(result: dict) -> Path:
    """The committed baseline a result is compared with by default: this machine's timing
    baseline, or the instruction-count baseline of the ISA path it counted."""
    ctx = result["context"]
    if result["kind"] == "icount":
        return icount_baseline(ctx.get("icount_isa", "avx2"))
    return timing_baseline(result_machine(ctx))


def history_rows(result: dict) -> list[dict]:
    """One history line per benchmark of `result` (its median)."""
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
            "machine": result_machine(ctx), "commit_date": ctx.get("commit_date", ""),
        })
    return rows


def append_history(result: dict, path: Path | None = None) -> tuple[int, Path]:
    """Appends `result` to its machine's history (or to `path`); returns (lines, file)."""
    rows = history_rows(result)
    path = path or history_file(result_machine(result["context"]))
    path.parent.mkdir(parents=True, exist_ok=True)
    new_file = not path.exists() or path.stat().st_size == 0
    if not new_file:
        with open(path, newline="") as f:
            header = next(csv.reader(f), [])
        if header != HISTORY_FIELDS:  # a file of fewer columns: rewritten with today's
            old = read_history(path)
            with open(path, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=HISTORY_FIELDS, extrasaction="ignore")
                w.writeheader()
                w.writerows(old)
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=HISTORY_FIELDS)
        if new_file:
            w.writeheader()
        w.writerows(rows)
    return len(rows), path


def read_history(path: Path) -> list[dict]:
    """The lines of a history file; a column an older or trimmed file lacks reads as ''."""
    if not path.exists():
        return []
    with open(path, newline="") as f:
        return [{**{k: "" for k in HISTORY_FIELDS}, **{k: v or "" for k, v in r.items()}} for r in csv.DictReader(f)]


def in_commit_order(rows: list[dict]) -> list[dict]:
    """History lines in the order of their commits (commit date, then the run's date), as
    a series is read: a commit measured after a later one still falls in its place. A
    line without a commit date (older files) takes that of another line of its commit,
    else the date of its run."""
    dates = {r["commit"]: r["commit_date"] for r in rows if r.get("commit_date")}

    def key(item: tuple[int, dict]) -> tuple:
        i, r = item
        run = _utc(r.get("date", ""))
        return _utc(r.get("commit_date") or dates.get(r["commit"], "")) or run, run, i
    return [r for _, r in sorted(enumerate(rows), key=key)]


def _utc(stamp: str) -> str:
    """An ISO 8601 time as a sortable UTC string ('' stays '')."""
    try:
        return dt.datetime.fromisoformat(stamp).astimezone(dt.timezone.utc).isoformat()
    except ValueError:
        return stamp
