"""A/B of the 4D trace: two builds of ndtrace, back to back, on the fixed bench scenes.

Each build is a Python interpreter that imports its own ndtrace (a venv, or ``python`` with a
``PYTHONPATH``: ``--a /venv-main/bin/python --b /venv-new/bin/python``). For each scene of
``../shared/bench/`` (tesseract48, s3_3072, elev_3072: shaded, one directional light with
shadows, two-sided, at a 128³ retina; ``--res`` changes it) and each thread count, the builds
run in alternating rounds (A B B A A B …); a round loads the scene once and takes the minimum of
3 traces. Prints the median of the rounds' minimums for each build, and B's speed over A's
(above 1: B is faster).

Usage:  python bench/ab.py --a PYTHON_A --b PYTHON_B [--rounds 6] [--res 128] [--threads 1 2]
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
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--only", nargs="*")
    a = ap.parse_args()
    print(f"{'scene':<12} {'threads':>7} {'A s (median)':>13} {'B s (median)':>13} {'B speed / A':>12}")
    for scene in a.only or SCENES:
        times: dict = {("a", k): [] for k in a.threads} | {("b", k): [] for k in a.threads}
        for r in range(a.rounds):
            order = ("a", "b") if r % 2 == 0 else ("b", "a")
            for which in order:
                for k, t in one_round(getattr(a, which), scene, a.res, a.threads).items():
                    times[(which, k)].append(t)
        for k in a.threads:
            ta, tb = statistics.median(times[("a", k)]), statistics.median(times[("b", k)])
            print(f"{scene:<12} {k:>7} {ta:>13.4f} {tb:>13.4f} {ta / tb:>12.3f}", flush=True)


if __name__ == "__main__":
    sys.exit(main())
