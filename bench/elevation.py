"""3D scalar fields as 4D elevation maps (issue 20): building and tracing an ``elevation`` scene.

For each field size n³ (a sum of Gaussians plus noise), in a fresh subprocess so that its peak
memory is its own, prints

* ``mesh``: ``ndtrace.mesh.elevation_map`` alone (field → vertices and tetrahedra);
* ``build``: field file (``.npy``) → scene → built BVH, the path of ``ndtrace scan.toml``,
  and the same from the numpy array through the builder (``add_object("elevation", field=f)``);
* ``trace``: the built scene traced at ``--res``³, 1 sample (median of 3), with the hit fraction;
* the process's peak resident memory (a built scene and one retina at a time), in bytes per
  tetrahedron (6·(n−1)³ of them).

Usage:  python bench/elevation.py [--sizes 64 128 256] [--res 128]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import ndtrace

CAMERA = {"position": [0.9, 1.2, 1.6, 3.2], "look_at": [0, 0, 0, 0.2], "up": [[0, 1, 0, 0], [0, 0, 1, 0]],
          "fov": 45}


def field(n: int) -> np.ndarray:
    axis = np.linspace(-1, 1, n)
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    f = np.exp(-6 * ((x - 0.3) ** 2 + y**2 + z**2)) + 0.6 * np.exp(-10 * ((x + 0.4) ** 2 + (y - 0.3) ** 2 + z**2))
    return f + 0.02 * np.random.default_rng(0).standard_normal(f.shape)


def scene_dict(obj: dict, res: int) -> dict:
    return {"dim": 4, "camera": {**CAMERA, "resolution": res},
            "lights": [{"type": "directional", "direction": [0.3, 0.6, 0.4, 1.0]}],
            "objects": [{"shape": "elevation", "height": 0.5, "smooth": True, **obj,
                         "material": {"colormap": "viridis"}}],
            "render": {"samples": 1}}


def one(n: int, res: int) -> dict:
    f = field(n)
    tets = 6 * (n - 1) ** 3
    t = time.perf_counter()
    ndtrace.mesh.elevation_map(f, height=0.5)
    mesh = time.perf_counter() - t
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "f.npy")
        np.save(path, f)
        t = time.perf_counter()
        scene = ndtrace.load_dict(scene_dict({"field": path}, res))
        scene.compiled()
        build_file = time.perf_counter() - t
    del scene
    t = time.perf_counter()
    scene = ndtrace.Scene(4).set_camera(**CAMERA, resolution=res)
    scene.add_light("directional", direction=[0.3, 0.6, 0.4, 1.0])
    scene.add_object("elevation", field=f, height=0.5, smooth=True, material={"colormap": "viridis"})
    scene.set_render(samples=1)
    scene.compiled()
    build_array = time.perf_counter() - t
    times = []
    for _ in range(3):
        r = None  # one retina alive at a time, as when rendering frames one after another
        t = time.perf_counter()
        r = ndtrace.trace(scene)
        times.append(time.perf_counter() - t)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    return {"n": n, "tets": tets, "mesh": mesh, "build_file": build_file, "build_array": build_array,
            "trace": statistics.median(times), "hit": float(r.hit.mean()), "peak": peak}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[64, 128, 256])
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.one:
        print(json.dumps(one(args.one, args.res)))
        return
    print(f"ndtrace {ndtrace.__version__}, {os.cpu_count()} cores, retina {args.res}^3, 1 sample", flush=True)
    for n in args.sizes:
        p = subprocess.run([sys.executable, __file__, "--one", str(n), "--res", str(args.res)],
                           capture_output=True, text=True)
        if p.returncode:
            print(f"{n}^3: failed: {p.stderr.strip().splitlines()[-1] if p.stderr.strip() else p.returncode}")
            continue
        m = json.loads(p.stdout.strip().splitlines()[-1])
        print(f"{n:>4}^3 {m['tets']:>11,} tets  mesh {m['mesh']:6.2f} s  build from .npy {m['build_file']:6.2f} s"
              f"  from array {m['build_array']:6.2f} s  trace {m['trace']:5.2f} s (hit {m['hit']:.2f})"
              f"  peak {m['peak'] / 2**20:7.0f} MiB = {m['peak'] / m['tets']:5.0f} B/tet", flush=True)


if __name__ == "__main__":
    main()
