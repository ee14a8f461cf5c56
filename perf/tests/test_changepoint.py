#!/usr/bin/env python3
"""ctest perf.changepoint: the change-point detector (perf/changepoint.py, perf/steps).

- Welch's t-test and the incomplete beta function against scipy's values.
- Synthetic series with known steps: found at the right points, with their sizes.
- A recorded history of one binary run repeatedly (perf/tests/data/history_repeat.csv:
  the runs perf/noise made on an AMD EPYC Zen 5, one commit, labels noise-1 .. noise-N)
  reports no step; with a 10% slowdown injected from one run on, relabelled as a
  history of commits, the step is found at that commit in every series whose noise
  allows a 10% step to be told apart, and nowhere else.
"""
import csv
import json
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

PERF = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(PERF))
import changepoint as cp  # noqa: E402

REPEAT = PERF / "tests" / "data" / "history_repeat.csv"


def read(path: Path) -> list[dict]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def write(rows: list[dict], path: Path) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        w.writeheader()
        w.writerows(rows)


def steps_of(rows: list[dict], *extra: str) -> list[dict]:
    """perf/steps on these rows, as a user runs it; its steps from --json."""
    with tempfile.TemporaryDirectory() as tmp:
        history, out = Path(tmp) / "h.csv", Path(tmp) / "steps.json"
        write(rows, history)
        r = subprocess.run([sys.executable, str(PERF / "steps"), "--history", str(history), "--machine", "test",
                            "--json", str(out), *extra], capture_output=True, text=True)
        if r.returncode != 0:
            raise AssertionError(f"perf/steps exited with {r.returncode}: {r.stdout}{r.stderr}")
        return json.loads(out.read_text())["steps"]


def inject(rows: list[dict], start_run: int, factor: float, runs_of) -> list[dict]:
    """A copy with every value from the `start_run`-th run on made `factor` times slower
    (items/s divided, instructions multiplied)."""
    out = []
    for r in rows:
        r = dict(r)
        if runs_of(r) >= start_run:
            v = float(r["value"])
            r["value"] = f"{v / factor if r['unit'] == 'items/s' else v * factor:.6g}"
        out.append(r)
    return out


class WelchTest(unittest.TestCase):
    def test_against_scipy(self):
        # scipy.stats.ttest_ind(a, b, equal_var=False).pvalue
        self.assertAlmostEqual(cp.welch_pvalue([10.1, 9.8, 10.3, 10.0, 9.9], [10.9, 11.2, 10.7, 11.4]),
                               0.0024928551249413906, places=12)
        self.assertAlmostEqual(cp.welch_pvalue([1, 2, 3, 4], [1.5, 2.5, 3.5, 4.5, 5.5, 6.5]),
                               0.17227907729130926, places=12)
        self.assertEqual(cp.welch_pvalue([1.0, 1.0], [1.0, 1.0]), 1.0)

    def test_incomplete_beta(self):
        # scipy.special.betainc
        self.assertAlmostEqual(cp.regularized_beta(2.5, 0.5, 0.3), 0.01892712407194565, places=12)
        self.assertAlmostEqual(cp.regularized_beta(10, 0.5, 0.95), 0.3171515754655451, places=12)


class Synthetic(unittest.TestCase):
    WOBBLE = [0.3, -0.5, 0.1, 0.6, -0.2, -0.4, 0.5, 0.0, -0.6, 0.2]  # +-0.6% around 100

    def series(self, levels):
        out = []
        for level, n in levels:
            out += [level * (1 + self.WOBBLE[len(out) % len(self.WOBBLE)] / 100) for _ in range(n)]
        return out

    def test_two_steps(self):
        x = self.series([(100.0, 12), (110.0, 10), (95.0, 12)])
        steps = cp.detect(x)
        self.assertEqual([s.index for s in steps], [12, 22])
        self.assertAlmostEqual(steps[0].change, 0.10, delta=0.01)
        self.assertAlmostEqual(steps[1].change, 95 / 110 - 1, delta=0.01)

    def test_flat_and_small_changes(self):
        self.assertEqual(cp.detect(self.series([(100.0, 30)])), [])
        self.assertEqual(cp.detect(self.series([(100.0, 15), (101.0, 15)])), [])   # 1% < min_change 2%

    def test_splits_only_between_runs(self):
        x = self.series([(100.0, 6), (110.0, 6)])
        runs = [0] * 5 + [1] * 7   # the step falls inside run 1: it is placed at that run's start
        self.assertEqual([s.index for s in cp.detect(x, runs)], [5])


@unittest.skipUnless(REPEAT.is_file(), f"{REPEAT} not recorded")
class RecordedRepeat(unittest.TestCase):
    def setUp(self):
        self.rows = read(REPEAT)
        self.labels = sorted({r["label"] for r in self.rows}, key=lambda s: int(s.rsplit("-", 1)[1]))
        self.order = {label: i for i, label in enumerate(self.labels)}

    def test_one_binary_has_no_step(self):
        self.assertGreaterEqual(len(self.labels), 8)
        self.assertEqual(len({r["commit"] for r in self.rows}), 1)
        self.assertEqual(steps_of(self.rows), [])

    def test_injected_step_found_at_its_commit(self):
        start = len(self.labels) // 2
        rows = []
        for r in self.rows:  # a history of commits c01, c02, ... instead of one commit's runs
            rows.append(dict(r, commit=f"c{self.order[r['label']] + 1:02d}", label=""))
        stepped = inject(rows, start + 1, 1.10, lambda r: int(r["commit"][1:]))
        found = steps_of(stepped)
        by_series = {s["benchmark"]: s for s in found}
        self.assertEqual(len(by_series), len(found), "at most one step per series")
        for s in found:
            self.assertEqual(s["commit"], f"c{start + 1:02d}", s)
            self.assertAlmostEqual(s["change"], 0.10, delta=0.03, msg=s)
        # Every series whose own noise lets a 10% step stand out (3 spreads below it) has it.
        quiet = [name for name, spread in self.spreads().items() if 3 * spread < 0.06]
        self.assertGreaterEqual(len(quiet), 20, "the recorded history has enough quiet series")
        self.assertEqual(sorted(set(quiet) - set(by_series)), [])

    def spreads(self) -> dict:
        values: dict[str, list[float]] = {}
        for r in self.rows:
            values.setdefault(r["benchmark"], []).append(float(r["value"]))
        out = {}
        for name, v in values.items():
            m = sum(v) / len(v)
            out[name] = (sum((x - m) ** 2 for x in v) / (len(v) - 1)) ** 0.5 / m
        return out


if __name__ == "__main__":
    unittest.main(verbosity=2)
