"""A/B of the 4D trace: two builds of ndtrace, back to back, on the fixed bench scenes.

Each build is a Python interpreter that imports its own ndtrace (a venv, or ``python`` with a
``PYTHONPATH``: ``--a /venv-main/bin/python --b /venv-new/bin/python``). For each scene of
``../shared/bench/`` (tesseract48, s3_3072, elev_3072: shaded, one directional light with
shadows, two-sided, at a 128³ retina; ``--res`` changes it) and each thread count, the builds
run in alternating rounds (A B B A A B …); a round loads the scene once and takes the minimum of
3 traces. Prints the median of the rounds' minimums for each build, and B's (and C's) speed over A's
(above 1: faster than A).

Usage:  python bench/ab.py --a PYTHON_A --b PYTHON_B [--c PYTHON_C] [--rounds 6] [--res 128] [--threads 1 2]
                           [--only tesseract48 ...]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = ["tesseract48", "s3_3072", "elev_3072"]

# One round in a fresh process: load the scene, trace it 3 times per thread count, print the
# minimum seconds per thread count as JSON.
ROUND = r"""
import json, os, sys, time
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
sys.path.insert(0, sys.argv[1])
from trace import scene_4d
import ndtrace
scene = ndtrace.load_dict(scene_4d(sys.argv[2], int(sys.argv[3])))
out = {}
for k in json.loads(sys.argv[4]):
    best = float("inf")
    for _ in range(3):
        t = time.perf_counter()
        ndtrace.trace(scene, threads=k)
        best = min(best, time.perf_counter() - t)
    out[k] = best
print(json.dumps(out))
"""


def one_round(python: str, scene: str, res: int, threads: list[int]) -> dict:
    out = subprocess.run([python, "-c", ROUND, HERE, scene, str(res), json.dumps(threads)],
                         check=True, capture_output=True, text=True).stdout
    return {int(k): v for k, v in json.loads(out).items()}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--a", required=True, help="the interpreter of build A (the base)")
    ap.add_argument("--b", required=True, help="the interpreter of build B (the change)")
    ap.add_argument("--c", help="the interpreter of a third build C (optional, e.g. an older base)")
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--only", nargs="*")
    a = ap.parse_args()
    builds = [("A", a.a), ("B", a.b)] + ([("C", a.c)] if a.c else [])
    names = [n for n, _ in builds]
    head = "".join(f" {n + ' s (median)':>13}" for n in names)
    ratios = "".join(f" {n + ' speed / A':>12}" for n in names[1:])
    print(f"{'scene':<12} {'threads':>7}{head}{ratios}")
    for scene in a.only or SCENES:
        times: dict = {(n, k): [] for n in names for k in a.threads}
        for r in range(a.rounds):
            # Alternating rounds: A B (C), then the reverse order, and so on.
            order = builds if r % 2 == 0 else builds[::-1]
            for name, python in order:
                for k, t in one_round(python, scene, a.res, a.threads).items():
                    times[(name, k)].append(t)
        for k in a.threads:
            med = [statistics.median(times[(n, k)]) for n in names]
            cols = "".join(f" {t:>13.4f}" for t in med)
            speed = "".join(f" {med[0] / t:>12.3f}" for t in med[1:])
            print(f"{scene:<12} {k:>7}{cols}{speed}", flush=True)

if __name__ == "__main__":
    sys.exit(main())
