"""Surfaces and points in 4D (issue 21): building and tracing thickened meshes.

Prints the median of 3 wall times of

* ``thicken``: ``ndtrace.mesh.thicken_surface`` on the 64×64 Clifford torus at segments 16
  and 64, the spun trefoil (120 × 36) at segments 16, and their tetrahedron counts;
* ``trace``: the segments = 16 torus traced at ``--res``³, 1 sample (load + BVH, then trace);
* ``hair``: the same torus as a ``surface`` object (bear hair, no thickening): load, then the
  trace with its projection into the retina, beside the thickened mesh's thicken + load + trace
  and the ratio;
* ``points`` (with ``--points P``, e.g. 1000000): ``thicken_points`` of P random points of the
  unit 3-sphere at ``--subdivisions``, written to an ``.npz`` and loaded as a mesh ``file``
  (no dict round trip), then traced at ``--res``³; once (it takes minutes at 10⁶), with the
  process's peak resident memory.

Usage:  python bench/surfaces.py [--res 64] [--points 1000000] [--subdivisions 1]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import tempfile
import time

import numpy as np

import ndtrace
from ndtrace import surfaces

CAMERA = {"position": [0.4, 0.9, 1.6, 2.6], "look_at": [0, 0, 0, 0], "up": [[0, 1, 0, 0], [0, 0, 1, 0]], "fov": 42}
LIGHTS = [{"type": "point", "position": [2.0, 3.0, 2.0, 2.5]}]


def median_time(f, runs: int = 3):
    times, out = [], None
    for _ in range(runs):
        t = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def scene_with(obj: dict, res: int) -> ndtrace.Scene:
    return ndtrace.load_dict({"dim": 4, "camera": {**CAMERA, "resolution": res}, "lights": LIGHTS,
                              "objects": [{**obj, "material": {"color": [0.9, 0.7, 0.3]}}],
                              "render": {"samples": 1}})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=64)
    ap.add_argument("--points", type=int, default=0)
    ap.add_argument("--subdivisions", type=int, default=1)
    args = ap.parse_args()

    torus = surfaces.clifford_torus(64)
    knot = surfaces.spun_knot(120, 36)
    for name, (v, t), m in (("clifford 64x64", torus, 16), ("clifford 64x64", torus, 64), ("spun knot", knot, 16)):
        dt, (tv, ts) = median_time(lambda: ndtrace.mesh.thicken_surface(v, t, 0.03, m))
        print(f"thicken  {name:<15} segments={m:<3} {len(ts):>9} tets  {dt:6.2f} s", flush=True)

    t0 = time.perf_counter()
    tv, ts = ndtrace.mesh.thicken_surface(*torus, 0.03, 16)
    thick = time.perf_counter() - t0
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "torus.npz")
        np.savez(path, vertices=tv, simplices=ts)
        t0 = time.perf_counter()
        scene = scene_with({"shape": "mesh", "file": path}, args.res)
        scene.compiled()
        load = time.perf_counter() - t0
        dt, r = median_time(lambda: ndtrace.trace(scene))
        print(f"trace    clifford segments=16 {len(ts):>9} tets  load+BVH {load:6.2f} s  "
              f"trace {args.res}^3 {dt:6.2f} s  hit {r.hit.mean():.3f}", flush=True)

    v, t = torus
    t0 = time.perf_counter()
    hair = scene_with({"shape": "surface", "vertices": v, "triangles": t}, args.res)
    hair.compiled()
    hload = time.perf_counter() - t0
    hdt, hr = median_time(lambda: ndtrace.trace(hair))
    thick_total = thick + load + dt
    print(f"hair     clifford 64x64      {len(t):>9} tris  load {hload:6.2f} s  "
          f"trace {args.res}^3 {hdt:6.2f} s  hit {hr.hit.mean():.3f}  |  thickened: thicken+load+trace "
          f"{thick_total:6.2f} s, trace alone {dt:6.2f} s: bear hair {thick_total / (hload + hdt):5.1f}x "
          f"faster in all, {dt / hdt:5.1f}x per trace", flush=True)

    if args.points:
        rng = np.random.default_rng(1)
        p = rng.normal(size=(args.points, 4))
        p /= np.linalg.norm(p, axis=1, keepdims=True)
        t0 = time.perf_counter()
        v, s = ndtrace.mesh.thicken_points(p, 0.004, args.subdivisions)
        t1 = time.perf_counter()
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "cloud.npz")
            np.savez(path, vertices=v, simplices=s)
            count = len(s)
            del v, s
            t2 = time.perf_counter()
            scene = scene_with({"shape": "mesh", "file": path}, args.res)
            scene.compiled()
            t3 = time.perf_counter()
            r = ndtrace.trace(scene)
            t4 = time.perf_counter()
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6
        print(f"points   {args.points} subdivisions={args.subdivisions} {count} tets  thicken {t1 - t0:.2f} s  "
              f"load+BVH {t3 - t2:.2f} s  trace {args.res}^3 {t4 - t3:.2f} s  hit {r.hit.mean():.4f}  "
              f"peak RSS {peak:.2f} GB", flush=True)


if __name__ == "__main__":
    main()
