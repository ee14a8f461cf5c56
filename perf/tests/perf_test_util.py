"""Helpers of the perf/ ctest scripts: run perf/run and perf/compare as a user would."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

PERF = Path(__file__).resolve().parent.parent
SKIP = 77  # ctest SKIP_RETURN_CODE
sys.path.insert(0, str(PERF))
import volley_perf as vp  # noqa: E402


def run_perf(args: list[str], env: dict | None = None) -> subprocess.CompletedProcess:
    """perf/run with `args`; never appends to the history (the tests use --out)."""
    cmd = [sys.executable, str(PERF / "run"), "--no-history", "--quiet"] + args
    print("$", " ".join(cmd), flush=True)
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    sys.stdout.write(r.stderr)
    return r


def compare(base: Path, new: Path, *extra: str) -> tuple[int, dict]:
    """perf/compare BASE NEW; returns its exit status and {benchmark: verdict}."""
    out = Path(str(new) + ".compare.json")
    cmd = [sys.executable, str(PERF / "compare"), str(base), str(new), "--json", str(out), *extra]
    print("$", " ".join(cmd), flush=True)
    r = subprocess.run(cmd, capture_output=True, text=True)
    sys.stdout.write(r.stdout + r.stderr)
    print(f"(exit status {r.returncode})", flush=True)
    verdicts = {}
    if out.is_file():
        for row in json.loads(out.read_text())["rows"]:
            verdicts[row["benchmark"]] = row["verdict"] + (" regression" if row.get("regression") else "")
    return r.returncode, verdicts


def load(path: Path) -> dict:
    """A result (Google Benchmark JSON or the older format) in the tools' form."""
    return vp.load_result(path)


def have_valgrind() -> bool:
    return shutil.which("valgrind") is not None


def fail(message: str) -> None:
    print(f"FAIL: {message}", flush=True)
    sys.exit(1)
