#!/usr/bin/env python3
"""ctest perf.changepoint: the change-point detector (perf/changepoint.py, perf/steps).

- Welch's t-test and the incomplete beta function against scipy's values.
- Synthetic series with known steps: found at the right points, with their sizes.
- A recorded history of one binary run repeatedly (perf/tests/data/history_repeat.csv.gz:
  the 16 runs perf/noise made on an AMD EPYC Zen 5 at one commit, labels noise-1 ..
  noise-16, the triangle, traversal, build and render series)
  reports no step; relabelled as a history of commits with a 10% slowdown injected from
  one commit on, the step is found at that commit in the quiet series and never more
  than two runs away from it in the others.
"""
import csv
import gzip
import json
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

PERF = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(PERF))
import changepoint as cp  # noqa: E402

REPEAT = PERF / "tests" / "data" / "history_repeat.csv.gz"


def read(path: Path) -> list[dict]:
    with gzip.open(path, "rt", newline="") as f:
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
        self.assertGreaterEqual(len(self.labels), 12)
        self.assertEqual(len({r["commit"] for r in self.rows}), 1)
        self.assertEqual(steps_of(self.rows), [])

    def test_injected_step_found_at_its_commit(self):
        """A 10% slowdown from commit c05 on, then from c06 on, ... c09 (each leaves at
        least eight runs after it): in the quiet series (every run within 6% of the
        series' median) it is found at exactly that commit, with its size; in the others,
        where slow spells of the machine lie beside it, it may be found up to two runs
        early or late, or not at all, and nothing else is found."""
        rows = [dict(r, commit=f"c{self.order[r['label']] + 1:02d}", label="") for r in self.rows]
        quiet = self.quiet_series(0.06)
        self.assertGreaterEqual(len(quiet), 5, "the recorded history has quiet series")
        for at in range(5, 10):
            with self.subTest(commit=at):
                found = steps_of(inject(rows, at, 1.10, lambda r: int(r["commit"][1:])))
                by_series = {s["benchmark"]: s for s in found}
                self.assertEqual(len(by_series), len(found), "at most one step per series")
                self.assertGreaterEqual(len(found), 30)
                offsets = [int(s["commit"][1:]) - at for s in found]
                self.assertLessEqual(max(abs(o) for o in offsets), 2, found)
                for name in quiet:
                    self.assertIn(name, by_series)
                    self.assertEqual(by_series[name]["commit"], f"c{at:02d}", by_series[name])
                # By how much: the 10% on top of what the recorded series itself did across
                # that commit (the machine drifts).
                for s in (s for s in found if s["commit"] == f"c{at:02d}"):
                    own = self.own_change(s["benchmark"], s["index"])
                    self.assertAlmostEqual(s["change"], (1 + own) * 1.10 - 1, delta=0.01, msg=s)

    def quiet_series(self, within: float) -> list[str]:
        values: dict[str, list[float]] = {}
        for r in self.rows:
            values.setdefault(r["benchmark"], []).append(float(r["value"]))
        return sorted(n for n, v in values.items() if max(abs(x / cp.median(v) - 1) for x in v) <= within)

    def own_change(self, name: str, index: int) -> float:
        """The recorded series' change in time per item across a split, uninjected."""
        cost = [1 / float(r["value"]) if r["unit"] == "items/s" else float(r["value"])
                for r in sorted((r for r in self.rows if r["benchmark"] == name), key=lambda r: self.order[r["label"]])]
        return cp.median(cost[index:]) / cp.median(cost[:index]) - 1


if __name__ == "__main__":
    unittest.main(verbosity=2)
