"""Dask benchmark: animation frames/s and slab-traced rays/s, here vs a LocalCluster.

Prints, for ``scenes/tesseract_spin.toml`` (24 frames, 48³ cells, 4 samples) and the same spin
at 96³ (12 frames): frames/s of ``ndtrace.animate(scene, out.gif)`` in this process with every
core, and with ``client=`` a 2-worker LocalCluster (one thread each); then rays/s of one 128³
retina, 1 and 8 samples per cell (``ndtrace.trace(scene)`` vs ``trace(scene, client=…)``,
slabs: the retina's 48 bytes per cell travel back from the workers). Medians of 3 runs;
the cluster's start-up is printed apart (it is paid once per session). Every Dask result is
checked to be bit-identical to the local one.

Usage:  python bench/dask.py [--quick]
  --quick   one run each, and no 96³ animation
"""

from __future__ import annotations

import argparse
import logging
import os
import statistics
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
# This file is named dask.py: keep its folder off the import path, or `import dask` finds it.
sys.path = [p for p in sys.path if os.path.abspath(p or os.curdir) != HERE]
SPIN = os.path.join(HERE, "..", "scenes", "tesseract_spin.toml")


def spin(resolution: int, samples: int = 4):
    import ndtrace

    data = ndtrace.load_file(SPIN).to_dict()
    data["camera"]["resolution"] = resolution
    data["render"]["samples"] = samples
    return ndtrace.load_dict(data)


def timed(runs: int, fn) -> tuple[float, object]:
    times, out = [], None
    for _ in range(runs):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    import distributed

    import ndtrace

    runs = 1 if args.quick else 3
    start = time.perf_counter()
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       host="127.0.0.1", dashboard_address="127.0.0.1:0",
                                       silence_logs=logging.ERROR)
    client = distributed.Client(cluster)
    print(f"LocalCluster of 2 workers × 1 thread started in {time.perf_counter() - start:.2f} s "
          f"({os.cpu_count()} cores)")
    cases = [("spin 48³ ×4 samples", spin(48), 24)]
    if not args.quick:
        cases.append(("spin 96³ ×4 samples", spin(96), 12))
    print(f"{'animation':<22} {'frames':>6} {'local f/s':>10} {'dask f/s':>10} {'ratio':>6}")
    with tempfile.TemporaryDirectory() as tmp:
        for name, scene, frames in cases:
            def render(where):
                out = os.path.join(tmp, f"{where}.gif")
                ndtrace.animate(scene, out, frames=frames,
                                client=client if where == "dask" else None)
                return open(out, "rb").read()
            local_s, local = timed(runs, lambda: render("local"))
            dask_s, remote = timed(runs, lambda: render("dask"))
            assert remote == local, f"{name}: the Dask GIF differs from the local one"
            print(f"{name:<22} {frames:>6} {frames / local_s:>10.2f} {frames / dask_s:>10.2f} "
                  f"{local_s / dask_s:>6.2f}")
    for samples in (1,) if args.quick else (1, 8):
        scene = spin(128, samples)
        rays = 128**3 * samples
        local_s, local = timed(runs, lambda: ndtrace.trace(scene))
        dask_s, remote = timed(runs, lambda: ndtrace.trace(scene, client=client))
        for field in ("rgba", "depth", "normal", "object_id", "primitive_id"):
            assert np.array_equal(getattr(local, field).view(np.uint8),
                                  getattr(remote, field).view(np.uint8)), field
        print(f"{f'trace 128³ ×{samples} (slabs)':<22} {'':>6} {rays / local_s / 1e6:>8.2f} M "
              f"{rays / dask_s / 1e6:>8.2f} M {local_s / dask_s:>6.2f}   rays/s, local vs dask")
    client.close()
    cluster.close()


if __name__ == "__main__":
    main()
