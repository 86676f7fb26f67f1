"""Instancing benchmark: what tracing objects in their own space costs against one tree.

Prints, for K 3-spheres in 4D (the mesh of ``bench/build.py`` at 6 divisions, each object with
its own ``scale`` and ``translate``: each is traced in its own space, one tree per object) and
the same spheres given as untransformed meshes of their world vertices (one tree over all, as every scene was traced before
instancing): the build time and the median trace time of a 48³ retina with shadows, for
K = 1, 8, 64, 256. The rays test each instance's padded world box before entering its tree.

Usage:  python bench/instances.py [--quick]
  --quick   K = 1, 8, 64 at a 24³ retina
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import sys  # noqa: E402

import numpy as np  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from build import sphere3  # noqa: E402  (the 3-sphere mesh of the build benchmark)


def scene(k: int, res: int, baked: bool):
    import ndtrace

    v, s = ndtrace.mesh.orient(*sphere3(6))
    rng = np.random.default_rng(7)
    sc = ndtrace.Scene(4)
    sc.set_camera(position=[0.5, 0.8, 1.1, 4.0], look_at=[0, 0, 0, 0],
                  up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=50, resolution=res)
    sc.add_light("point", position=[2, 2, 1, 3])
    sc.set_render(shadows=True)
    side = max(1, round(k ** 0.25))
    for _ in range(k):
        centre = (rng.random(4) * 2 - 1) * (0.0 if k == 1 else 1.2)
        radius = 0.8 / side
        if baked:
            # The sphere's world vertices, untransformed: traced in world space.
            sc.add_object("mesh", vertices=v * radius + centre, simplices=s)
        else:
            sc.add_object("mesh", vertices=v, simplices=s,
                          transform=[{"scale": radius}, {"translate": centre.tolist()}])
    return sc


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    import ndtrace

    res = 24 if args.quick else 48
    counts = (1, 8, 64) if args.quick else (1, 8, 64, 256)
    print(f"K 3-spheres in 4D, a {res}³ retina with shadows; median of 3 traces")
    print(f"{'K':>5} {'simplices':>10} {'own space: build':>17} {'trace':>8} {'one tree: build':>16} {'trace':>8} {'ratio':>6}")
    for k in counts:
        row = []
        for baked in (False, True):
            start = time.perf_counter()
            sc = scene(k, res, baked)
            sc.compiled()
            build = time.perf_counter() - start
            times = []
            for _ in range(3):
                start = time.perf_counter()
                ndtrace.trace(sc)
                times.append(time.perf_counter() - start)
            row.append((build, statistics.median(times), sc.compiled().bvh_stats()[0]))
        (b0, t0, n), (b1, t1, _) = row
        print(f"{k:>5} {n:>10,} {b0:>15.3f} s {t0:>6.3f} s {b1:>14.3f} s {t1:>6.3f} s {t0 / t1:>5.2f}×")


if __name__ == "__main__":
    main()
