#!/usr/bin/env python3
"""ctest perf.tools: unit tests of the regression tooling itself (perf/volley_perf.py and
perf/compare, embree_best.py's callgrind reading) on hand-made inputs: the Mann-Whitney U test against exact values,
the thresholds file, compare's verdicts, accuracy reporting and exit codes, the Google
Benchmark JSON format, machine keys, per-machine noise and the markdown summary."""
import itertools
import json
import math
import subprocess
import sys
import tempfile
import unittest
from pathlib import Path

PERF = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(PERF))
import volley_perf as vp  # noqa: E402
import embree_best as eb  # noqa: E402


def brute_force_p(x, y):
    """Two-sided exact p of the U statistic by enumerating every split of the ranks."""
    n1, n = len(x), len(x) + len(y)
    u_obs = sum(1 for a in x for b in y if a > b)
    us = []
    for chosen in itertools.combinations(range(n), n1):
        s = set(chosen)
        us.append(sum(1 for i in s for j in range(n) if j not in s and i > j))
    lower = sum(u <= u_obs for u in us) / len(us)
    upper = sum(u >= u_obs for u in us) / len(us)
    return min(1.0, 2 * min(lower, upper))


class MannWhitney(unittest.TestCase):
    def test_complete_separation_exact(self):
        # 5 vs 5, no overlap: p = 2 / C(10, 5) (scipy.stats.mannwhitneyu: 0.007937).
        u, p = vp.mann_whitney_u([1, 2, 3, 4, 5], [6, 7, 8, 9, 10])
        self.assertEqual(u, 0)
        self.assertAlmostEqual(p, 2 / 252, places=12)
        # 3 vs 3 cannot reach 0.05: p = 2 / C(6, 3) = 0.1.
        self.assertAlmostEqual(vp.mann_whitney_u([1, 2, 3], [4, 5, 6])[1], 0.1, places=12)

    def test_exact_matches_enumeration(self):
        x, y = [0.3, 1.7, 2.2, 5.0], [1.1, 2.5, 3.3, 4.0, 6.1]
        self.assertAlmostEqual(vp.mann_whitney_u(x, y)[1], brute_force_p(x, y), places=12)
        x, y = [9.0, 8.0, 7.5, 3.0, 2.0], [1.0, 4.0, 5.0, 6.0, 10.0, 11.0]
        self.assertAlmostEqual(vp.mann_whitney_u(x, y)[1], brute_force_p(x, y), places=12)

    def test_symmetric(self):
        x, y = [1.0, 2.5, 2.7, 4.0, 9.0], [2.0, 3.0, 5.0, 6.0, 7.0]
        self.assertAlmostEqual(vp.mann_whitney_u(x, y)[1], vp.mann_whitney_u(y, x)[1], places=12)

    def test_asymptotic_with_continuity(self):
        # 9 vs 9 (no sample below 8: normal approximation), complete separation:
        # z = (81 - 40.5 - 0.5) / sqrt(81 * 19 / 12), p = erfc(z / sqrt 2) = 4.12e-4.
        _, p = vp.mann_whitney_u(list(range(1, 10)), list(range(10, 19)))
        self.assertAlmostEqual(p, math.erfc(40 / math.sqrt(81 * 19 / 12) / math.sqrt(2)), places=12)
        self.assertAlmostEqual(p, 4.12e-4, delta=1e-6)

    def test_ties_and_degenerate(self):
        self.assertEqual(vp.mann_whitney_u([1, 1, 1, 1], [1, 1, 1, 1])[1], 1.0)
        _, p = vp.mann_whitney_u([1, 2, 2, 3], [2, 3, 4, 5])
        self.assertTrue(0 < p <= 1)
        self.assertIsNone(vp.mann_whitney_u([1.0], [2.0, 3.0]))


class Thresholds(unittest.TestCase):
    def write(self, text):
        f = tempfile.NamedTemporaryFile("w", suffix=".thresholds", delete=False)
        f.write(text)
        f.close()
        self.addCleanup(Path(f.name).unlink)
        return Path(f.name)

    def test_first_match_wins(self):
        rules = vp.load_thresholds(self.write(
            "# comment\ntime triangle/*/scalar/* untracked\ntime triangle/* 10%\nicount * 1%\n"
            "accuracy *leak* 0\naccuracy * report\n"))
        self.assertFalse(vp.find_rule(rules, "time", "triangle/moller/scalar/1x1/aimed").tracked)
        r = vp.find_rule(rules, "time", "triangle/moller/avx2/1xblock/aimed")
        self.assertTrue(r.tracked)
        self.assertEqual(r.limit, 10)
        self.assertIsNone(vp.find_rule(rules, "time", "render/cornell/avx2/whitted"))
        self.assertEqual(vp.find_rule(rules, "icount", "anything").limit, 1)
        self.assertEqual(vp.find_rule(rules, "accuracy", "watertight/leaks").limit, 0)
        self.assertFalse(vp.find_rule(rules, "accuracy", "watertight/median_ulp").tracked)

    def test_bad_lines(self):
        for text in ("time triangle/*\n", "speed * 10%\n", "time * 10\n", "time * fast\n"):
            with self.assertRaises(ValueError, msg=text):
                vp.load_thresholds(self.write(text))

    def test_checked_in_file_parses(self):
        rules = vp.load_thresholds(vp.THRESHOLDS)
        self.assertTrue(vp.find_rule(rules, "time", "triangle/moller/avx2/1xblock/aimed").tracked)
        self.assertTrue(vp.find_rule(rules, "icount", "traversal/teapot/avx2/packet/primary").tracked)


def result(kind, benchmarks, accuracy=None, **context):
    r = {"schema": vp.SCHEMA, "kind": kind, "context": {"commit_short": "abc", **context}, "benchmarks": {}}
    for name, values in benchmarks.items():
        if kind == "icount":
            r["benchmarks"][name] = {"label": "avx2", "metric": "instructions", "unit": "instr/iteration",
                                     "higher_is_better": False, "values": values, "instructions": values[0],
                                     "iterations": 1, "counters": {}}
        else:
            r["benchmarks"][name] = {"label": "avx2", "metric": "items_per_second", "unit": "items/s",
                                     "higher_is_better": True, "values": values, "counters": {"hit_rate": 0.5}}
    if accuracy is not None:
        r["accuracy"] = accuracy
    return r


class Compare(unittest.TestCase):
    THRESHOLDS = "time tracked/* 10%\ntime * untracked\nicount * 1%\naccuracy *leak* 0\naccuracy * report\n"

    def setUp(self):
        self.tmp = tempfile.TemporaryDirectory()
        self.dir = Path(self.tmp.name)
        (self.dir / "thresholds").write_text(self.THRESHOLDS)

    def tearDown(self):
        self.tmp.cleanup()

    def run_compare(self, base, new, *extra):
        (self.dir / "a.json").write_text(json.dumps(base))
        (self.dir / "b.json").write_text(json.dumps(new))
        out = self.dir / "cmp.json"
        r = subprocess.run([sys.executable, str(PERF / "compare"), str(self.dir / "a.json"), str(self.dir / "b.json"),
                            "--thresholds", str(self.dir / "thresholds"), "--json", str(out), "--no-noise", *extra],
                           capture_output=True, text=True)
        rows = {}
        if out.exists():
            rows = {row["benchmark"]: row for row in json.loads(out.read_text())["rows"]}
        return r.returncode, rows, r.stdout + r.stderr

    def test_regression_noise_and_untracked(self):
        base = result("timing", {"tracked/a": [100, 101, 99, 98, 102], "tracked/b": [100, 101, 99, 100, 102],
                                 "other/c": [100, 101, 99, 100, 102]})
        new = result("timing", {"tracked/a": [80, 81, 79, 78, 82], "tracked/b": [99, 100, 101, 100, 98],
                                "other/c": [50, 51, 49, 50, 52]})
        status, rows, text = self.run_compare(base, new)
        self.assertEqual(status, 1, text)
        self.assertEqual(rows["tracked/a"]["verdict"], "slower")
        self.assertTrue(rows["tracked/a"]["regression"])
        self.assertAlmostEqual(rows["tracked/a"]["change"], 0.25, places=9)   # 100 -> 80 items/s: 25% more time
        self.assertAlmostEqual(rows["tracked/a"]["p"], 2 / 252, places=9)   # exact: no ties, 5 vs 5
        self.assertEqual(rows["tracked/b"]["verdict"], "noise")
        self.assertEqual(rows["other/c"]["verdict"], "slower")
        self.assertFalse(rows["other/c"]["regression"])
        self.assertIn("REGRESSION: tracked/a", text)
        # The other way round it is an improvement, not a failure.
        status, rows, _ = self.run_compare(new, base)
        self.assertEqual(status, 0)
        self.assertEqual(rows["tracked/a"]["verdict"], "faster")

    def test_small_slowdown_is_not_a_regression(self):
        base = result("timing", {"tracked/a": [100, 101, 99, 100, 102]})
        new = result("timing", {"tracked/a": [95, 96, 94, 95, 97]})  # significant, 5% < 10%
        status, rows, _ = self.run_compare(base, new)
        self.assertEqual(status, 0)
        self.assertEqual(rows["tracked/a"]["verdict"], "slower")
        self.assertFalse(rows["tracked/a"]["regression"])

    def test_one_repetition_never_fails(self):
        status, rows, text = self.run_compare(result("timing", {"tracked/a": [100]}), result("timing", {"tracked/a": [50]}))
        self.assertEqual(status, 0, text)
        self.assertEqual(rows["tracked/a"]["verdict"], "slower?")
        self.assertIn("no significance test", text)

    def test_icount(self):
        base = result("icount", {"k/a": [1000000], "k/b": [1000000]})
        same = result("icount", {"k/a": [1000000], "k/b": [1005000]})      # +0.5% <= 1%
        status, rows, _ = self.run_compare(base, same)
        self.assertEqual(status, 0)
        self.assertEqual(rows["k/a"]["verdict"], "same")
        self.assertEqual(rows["k/b"]["verdict"], "same")
        status, rows, _ = self.run_compare(base, result("icount", {"k/a": [1020000], "k/b": [900000]}))
        self.assertEqual(status, 1)
        self.assertEqual(rows["k/a"]["verdict"], "slower")
        self.assertEqual(rows["k/b"]["verdict"], "faster")

    def test_accuracy_changes(self):
        base = result("timing", {"tracked/a": [100, 101, 99, 100, 102]},
                      accuracy={"watertight": {"leaks": 0, "median_ulp": 0.5}, "plane": {"leaks": 3}})
        drift = result("timing", {"tracked/a": [100, 101, 99, 100, 102]},
                       accuracy={"watertight": {"leaks": 0, "median_ulp": 0.75}, "plane": {"leaks": 1}})
        status, _, text = self.run_compare(base, drift)
        self.assertEqual(status, 0, text)
        self.assertIn("watertight/median_ulp: 0.5 -> 0.75", text)
        self.assertIn("plane/leaks: 3 -> 1", text)
        leak = result("timing", {"tracked/a": [100, 101, 99, 100, 102]},
                      accuracy={"watertight": {"leaks": 2, "median_ulp": 0.5}, "plane": {"leaks": 3}})
        status, _, text = self.run_compare(base, leak)
        self.assertEqual(status, 1, text)
        self.assertIn("watertight/leaks: 0 -> 2 (+2)  REGRESSION", text)

    def test_counters_and_context(self):
        base = result("timing", {"tracked/a": [100, 101, 99, 100, 102]}, compiler_version="g++ 12")
        new = result("timing", {"tracked/a": [100, 101, 99, 100, 102]}, compiler_version="g++ 13")
        new["benchmarks"]["tracked/a"]["counters"]["hit_rate"] = 0.25
        status, _, text = self.run_compare(base, new)
        self.assertEqual(status, 0)
        self.assertIn("tracked/a/hit_rate: 0.5 -> 0.25", text)
        self.assertIn("warning: compiler_version", text)

    def test_kinds_must_match(self):
        status, _, text = self.run_compare(result("timing", {"a": [1, 2]}), result("icount", {"a": [1]}))
        self.assertEqual(status, 2, text)


    def test_machines_must_match_for_timing_verdicts(self):
        base = result("timing", {"tracked/a": [100, 101, 99, 98, 102]}, machine="zen-1-avx2")
        new = result("timing", {"tracked/a": [50, 51, 49, 48, 52]}, machine="zen-5-avx512")
        status, rows, text = self.run_compare(base, new)
        self.assertEqual(status, 0, text)
        self.assertEqual(rows["tracked/a"]["verdict"], "n/a")
        self.assertIn("two kinds of machine", text)

    def test_noise_raises_the_threshold(self):
        base = result("timing", {"tracked/a": [100, 101, 99, 98, 102]}, machine="m")
        new = result("timing", {"tracked/a": [85, 86, 84, 83, 87]}, machine="m")  # 17.6% more time
        status, rows, text = self.run_compare(base, new)
        self.assertEqual(status, 1, text)
        noise = self.dir / "noise.json"
        noise.write_text(json.dumps({"benchmarks": {"tracked/a": {"spread": 0.07}}}))
        args = ["--thresholds", str(self.dir / "thresholds"), "--noise", str(noise)]
        r = subprocess.run([sys.executable, str(PERF / "compare"), str(self.dir / "a.json"), str(self.dir / "b.json"),
                            *args], capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stdout)   # 3 x 7% = 21% > 17.6%: noise on this machine
        self.assertIn("noise", r.stdout)

    def test_markdown(self):
        base = result("timing", {"tracked/a": [100, 101, 99, 98, 102], "tracked/b": [100, 101, 99, 100, 102]})
        new = result("timing", {"tracked/a": [80, 81, 79, 78, 82], "tracked/b": [99, 100, 101, 100, 98]})
        md = self.dir / "cmp.md"
        status, _, _ = self.run_compare(base, new, "--markdown", str(md))
        self.assertEqual(status, 1)
        text = md.read_text()
        self.assertIn("**REGRESSION**: tracked/a", text)
        self.assertIn("| benchmark | old median | new median | change | p | verdict |", text)
        changed = text.split("<details>")[0]
        self.assertIn("| `tracked/a` | 100 /s | 80 /s | +25.0% | 0.008 | slower REGRESSION (> 10%) |", changed)
        self.assertNotIn("tracked/b", changed)   # noise: only in the folded full table
        self.assertIn("`tracked/b`", text.split("<details>")[1])


def gbench_json(values_by_name, context=None, aggregates=True):
    """Google Benchmark JSON as volley_bench writes it with repetitions (items/s)."""
    rows = []
    for f, (name, values) in enumerate(values_by_name.items()):
        for i, v in enumerate(values):
            rows.append({"name": name, "family_index": f, "per_family_instance_index": 0, "run_name": name,
                         "run_type": "iteration", "repetitions": len(values), "repetition_index": i, "threads": 1,
                         "iterations": 10, "real_time": 1e9 / v, "cpu_time": 1e9 / v, "time_unit": "ns",
                         "items_per_second": v, "label": "avx2", "hit_rate": 0.5})
        if aggregates:
            m = sorted(values)[len(values) // 2]
            rows.append({"name": name + "_median", "family_index": f, "per_family_instance_index": 0,
                         "run_name": name, "run_type": "aggregate", "repetitions": len(values), "threads": 1,
                         "aggregate_name": "median", "aggregate_unit": "time", "iterations": len(values),
                         "real_time": 1e9 / m, "cpu_time": 1e9 / m, "time_unit": "ns", "items_per_second": m})
    return {"context": {"date": "2026-12-02T00:00:00+00:00", "host_name": "vm", "executable": "volley_bench",
                        **(context or {})}, "benchmarks": rows}


class GoogleBenchmarkFormat(unittest.TestCase):
    def test_plain_google_benchmark_json(self):
        r = vp.from_gbench(gbench_json({"tracked/a": [100.0, 110.0, 90.0]}))
        b = r["benchmarks"]["tracked/a"]
        self.assertEqual(r["kind"], "timing")
        self.assertEqual(sorted(b["values"]), [90.0, 100.0, 110.0])   # repetitions, not the aggregates
        self.assertEqual(b["counters"], {"hit_rate": 0.5})
        self.assertEqual(r["context"]["host"], "vm")

    def test_aggregates_only(self):
        gb = gbench_json({"tracked/a": [100.0, 110.0, 90.0]})
        gb["benchmarks"] = [x for x in gb["benchmarks"] if x["run_type"] == "aggregate"]
        self.assertEqual(vp.from_gbench(gb)["benchmarks"]["tracked/a"]["values"], [100.0])

    def test_volley_context_and_icount_round_trip(self):
        e = {"label": "avx2", "values": [1234.0], "instructions": 1234, "iterations": 1, "items": 10,
             "instructions_per_item": 123.4, "counters": {"nodes": 7}}
        gb = vp.icount_gbench({"k/a": e, "k/b": {"label": "avx2", "error": "no such benchmark"}},
                              {"host_name": "vm", "volley_scene:teapot": "/x"}, {"commit_short": "abc"})
        self.assertNotIn("volley_scene:teapot", gb["context"])
        self.assertEqual(gb["benchmarks"][0]["cpu_time"], 1234.0)   # compare.py compares these
        r = vp.from_gbench(json.loads(json.dumps(gb)))
        self.assertEqual(r["kind"], "icount")
        self.assertEqual(r["benchmarks"]["k/a"]["values"], [1234.0])
        self.assertEqual(r["benchmarks"]["k/a"]["instructions_per_item"], 123.4)
        self.assertEqual(r["benchmarks"]["k/a"]["counters"], {"nodes": 7})
        self.assertEqual(r["benchmarks"]["k/b"]["error"], "no such benchmark")

    def test_compare_reads_both_formats(self):
        with tempfile.TemporaryDirectory() as tmp:
            d = Path(tmp)
            (d / "old.json").write_text(json.dumps(result("timing", {"traversal/x": [100, 101, 99, 98, 102]})))
            (d / "new.json").write_text(json.dumps(gbench_json({"traversal/x": [50.0, 51.0, 49.0, 48.0, 52.0]})))
            r = subprocess.run([sys.executable, str(PERF / "compare"), str(d / "old.json"), str(d / "new.json"),
                                "--no-noise", "--json", str(d / "c.json")], capture_output=True, text=True)
            rows = json.loads((d / "c.json").read_text())["rows"]
            self.assertEqual(r.returncode, 1, r.stdout + r.stderr)
            self.assertEqual(rows[0]["verdict"], "slower")
            (d / "bad.json").write_text("[1, 2]")
            r = subprocess.run([sys.executable, str(PERF / "compare"), str(d / "bad.json"), str(d / "new.json")],
                               capture_output=True, text=True)
            self.assertEqual(r.returncode, 2)
            self.assertIn("bad.json: not a result", r.stderr)


class Machines(unittest.TestCase):
    ZEN5 = "processor\t: 0\nvendor_id\t: AuthenticAMD\ncpu family\t: 26\nmodel\t\t: 2\n" \
           "model name\t: AMD EPYC\nflags\t\t: fpu sse4_2 avx2 fma avx512f avx512bw avx512dq avx512vl\n"

    def test_key(self):
        m = vp.this_machine(self.ZEN5)
        self.assertEqual(m["machine"], "amd-epyc-f26m2-avx512")
        self.assertEqual(m["machine_text"], "AMD EPYC, family 26 model 2, avx512")
        zen3 = self.ZEN5.replace("26", "25").replace("model\t\t: 2", "model\t\t: 1").replace(
            " avx512f avx512bw avx512dq avx512vl", "")
        self.assertEqual(vp.this_machine(zen3)["machine"], "amd-epyc-f25m1-avx2")

    def test_baseline_paths(self):
        timing = {"kind": "timing", "context": {"machine": "amd-epyc-f26m2-avx512"}}
        self.assertEqual(vp.baseline_for(timing), vp.BASELINES_DIR / "amd-epyc-f26m2-avx512" / "timing.json")
        icount = {"kind": "icount", "context": {"icount_isa": "sse4.2"}}
        self.assertEqual(vp.baseline_for(icount), vp.BASELINES_DIR / "icount" / "sse4.2.json")


class History(unittest.TestCase):
    def test_append(self):
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "history.csv"
            r = result("timing", {"x/a": [1.0, 2.0, 3.0]}, date="2026-01-01T00:00:00+00:00", dirty=True)
            self.assertEqual(vp.append_history(r, path), (1, path))
            self.assertEqual(vp.append_history(result("icount", {"x/a": [500.0]}), path)[0], 1)
            rows = vp.read_history(path)
            self.assertEqual([row["kind"] for row in rows], ["timing", "icount"])
            self.assertEqual(rows[0]["value"], "2")
            self.assertEqual(rows[0]["dirty"], "1")
            self.assertEqual(rows[0]["reps"], "3")


    def test_commit_order(self):
        rows = [{"commit": "new", "commit_date": "2026-12-02T10:00:00+00:00", "date": "2026-12-02T11:00:00+00:00"},
                {"commit": "old", "commit_date": "2026-12-01T10:00:00+01:00", "date": "2026-12-02T12:00:00+00:00"},
                {"commit": "new", "commit_date": "", "date": "2026-12-02T10:30:00+00:00"},   # an older line
                {"commit": "old", "commit_date": "2026-12-01T10:00:00+01:00", "date": "2026-12-02T11:30:00+00:00"}]
        ordered = vp.in_commit_order(rows)
        self.assertEqual([(r["commit"], r["date"][11:16]) for r in ordered],
                         [("old", "11:30"), ("old", "12:00"), ("new", "10:30"), ("new", "11:00")])


class EmbreeIcount(unittest.TestCase):
    """embree_best.py's ICOUNT mode: the entries' costs read from callgrind_annotate."""

    ANNOTATED = """\
--------------------------------------------------------------------------------
Ir                     file:function
--------------------------------------------------------------------------------
1,294,071,271 (100.0%)  PROGRAM TOTALS
  149,971,220 (11.59%)  ???:volley::Accel::occluded(volley::Ray const&) const [/b/volley_vs_embree]
  139,458,892 (10.78%)  ???:rtcOccluded1 [/usr/lib/x86_64-linux-gnu/libembree3.so.3.13.5]
   97,000,000 ( 7.50%)  src/a.cpp:volley::f(float [3]) const [/b/volley_vs_embree]
      500,000 ( 0.04%)  ???:rtcOccluded1 [/other/copy.so]
"""

    def test_inclusive_costs(self):
        costs = eb.inclusive_costs(self.ANNOTATED)
        self.assertEqual(costs["rtcOccluded1"], 139458892)  # the first listing kept
        self.assertEqual(costs["volley::Accel::occluded(volley::Ray const&) const"], 149971220)
        self.assertEqual(costs["volley::f(float [3]) const"], 97000000)
        self.assertNotIn("PROGRAM TOTALS", costs)
        self.assertEqual(eb.entry_cost(costs, eb.VOLLEY_ENTRY["occluded1"]), 149971220)
        with self.assertRaises(SystemExit):
            eb.entry_cost(costs, "rtcIntersect1")


if __name__ == "__main__":
    unittest.main(verbosity=2)
