"""A machine's history read as series, and their steps: what perf/steps prints and
perf/plot marks (the detection itself is changepoint.py)."""
from __future__ import annotations

import math

import changepoint as cp
import volley_perf as vp


def series_of(rows: list[dict], kind: str, pattern) -> dict[str, list[dict]]:
    out: dict[str, list[dict]] = {}
    for r in rows:
        if r["kind"] == kind and (not pattern or pattern.search(r["benchmark"])):
            out.setdefault(r["benchmark"], []).append(r)
    return out


def cost(row: dict) -> float:
    """What a step is measured in: time (or instructions) per item, so + is slower."""
    v = float(row["value"])
    return 1.0 / v if row["unit"] == "items/s" and v > 0 else v


def run_key(row: dict) -> tuple:
    return row["commit"], row["dirty"], row["label"]


def neighbour_noise(values: list[float]) -> float:
    """Relative noise of a series from its neighbouring points: the median absolute
    successive difference over 0.954 sqrt 2 (a normal sigma), divided by the median; a
    step moves one difference only, so it barely counts."""
    if len(values) < 3:
        return 0.0
    diffs = [abs(b - a) for a, b in zip(values, values[1:])]
    m = cp.median(values)
    return cp.median(diffs) / (0.954 * math.sqrt(2.0)) / m if m else 0.0


def find_steps(points: list[dict], noise: float, min_change: float = 0.02, max_pvalue: float = 0.001) -> list[dict]:
    """The steps of one series (its history lines in commit order). `noise`: the
    machine's measured spread of this benchmark (0 when not measured); the minimum change
    is raised to NOISE_FACTOR times it and times the series' own neighbour noise."""
    values = [cost(r) for r in points]
    if any(v <= 0 or not math.isfinite(v) for v in values):
        return []
    floor = max(min_change, vp.NOISE_FACTOR * noise, vp.NOISE_FACTOR * neighbour_noise(values))
    steps = cp.detect(values, [run_key(r) for r in points], max_pvalue=max_pvalue, min_change=floor)
    out = []
    for s in steps:
        first, last = points[s.index], points[s.index - 1]
        out.append({"benchmark": first["benchmark"], "commit": first["commit"], "label": first["label"],
                    "dirty": first["dirty"] == "1", "date": first["date"], "previous_commit": last["commit"],
                    "previous_label": last["label"], "index": s.index, "before": s.before, "after": s.after,
                    "change": s.change, "pvalue": s.pvalue, "min_change": floor, "unit": points[0]["unit"]})
    return out


def describe(step: dict) -> str:
    at = step["commit"][:12] + ("+" if step["dirty"] else "") + (f" [{step['label']}]" if step["label"] else "")
    prev = step["previous_commit"][:12] + (f" [{step['previous_label']}]" if step["previous_label"] else "")
    word = "slower" if step["change"] > 0 else "faster"
    measure = "instructions" if step["unit"].startswith("instr") else "time per item"
    return f"{at} (after {prev}): {step['change'] * 100:+.1f}% {measure}, {word} (p = {step['pvalue']:.1e})"
