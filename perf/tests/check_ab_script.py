#!/usr/bin/env python3
"""perf/ab.sh: refuses two identical executables and bad arguments with a clear message,
and prints one summary line for two different ones, timed or counted (ICOUNT=1; ctest
perf.ab_script)."""
import os
import re
import shutil
import stat
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
AB = os.path.join(ROOT, "perf", "ab.sh")


def run(args, env=None):
    done = subprocess.run(["bash", AB] + args, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          env=env)
    return done.returncode, done.stdout, done.stderr


def main():
    volley = sys.argv[1]
    with tempfile.TemporaryDirectory() as tmp:
        scene = os.path.join(ROOT, "scenes", "cornell.json")
        rays = os.path.join(tmp, "shadow.vray")
        subprocess.run([volley, "rays", scene, "--workload", "shadow", "--width", "32", "--height", "32", "-o", rays,
                        "--threads", "1"], cwd=ROOT, check=True, stdout=subprocess.DEVNULL)
        rc, out, err = run([])
        assert rc == 2 and "ABBA pairs" in out, (rc, out, err)
        rc, out, err = run([volley, volley, scene, rays])
        assert rc == 2 and "same executable" in err and "volley_cli" in err, (rc, out, err)
        rc, out, err = run([volley, os.path.join(tmp, "missing"), scene, rays])
        assert rc == 2 and "not an executable" in err, (rc, out, err)
        rc, out, err = run([volley, volley, scene, os.path.join(tmp, "missing.vray")])
        assert rc == 2 and "no such file" in err, (rc, out, err)
        # B: the same program behind a wrapper (other bytes), two pairs of short runs.
        wrapper = os.path.join(tmp, "volley_b")
        with open(wrapper, "w") as f:
            f.write(f'#!/bin/sh\nexec "{volley}" "$@"\n')
        os.chmod(wrapper, os.stat(wrapper).st_mode | stat.S_IXUSR)
        rc, out, err = run([volley, wrapper, scene, rays, "--occluded --mode stream", "x"])
        assert rc == 2 and "PAIRS must be a positive integer" in err, (rc, out, err)
        rc, out, err = run([volley, wrapper, scene, rays, "--no-such-option", "1"], dict(os.environ, REPS="1"))
        assert rc == 1 and "printed no rate" in err and "--no-such-option" in err, (rc, out, err)
        rc, out, err = run([volley, wrapper, scene, rays, "--occluded --mode stream", "2"], dict(os.environ, REPS="2"))
        assert rc == 0, (rc, out, err)
        assert re.search(r"^cornell\.json shadow\.vray --occluded --mode stream: A [0-9.]+ B [0-9.]+ Mrays/s, "
                         r"B/A best [0-9.]+, median of 2 pairs [0-9.]+$", out.strip()), out
        # ICOUNT=1: the traced calls' instructions, the same program on both sides (valgrind
        # cannot run a sanitizer build).
        sanitized = any(tag in open(volley, "rb").read() for tag in (b"__asan_init", b"__tsan_init"))
        if shutil.which("valgrind") and not sanitized:
            rc, out, err = run([volley, wrapper, scene, rays, "--occluded --mode stream"], dict(os.environ, ICOUNT="1"))
            m = re.search(r"^cornell\.json shadow\.vray --occluded --mode stream: instructions A ([0-9]+) "
                          r"B ([0-9]+), B/A ([0-9.]+)$", out.strip())
            assert rc == 0 and m and m[1] == m[2] and m[3] == "1.0000", (rc, out, err)
            rc, out, err = run([volley, wrapper, scene, rays, "--no-such-option"], dict(os.environ, ICOUNT="1"))
            assert rc == 1 and "counted nothing" in err and "--no-such-option" in err, (rc, out, err)
        else:
            print("ICOUNT=1 not checked: no valgrind, or a sanitizer build")
    print("perf/ab.sh: checks pass")


if __name__ == "__main__":
    main()
