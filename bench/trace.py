"""Tracing benchmark: rays/s, BVH build time and peak memory.

Prints, for each fixed scene of ../shared/bench/ (see its README) and at 1 and 2 threads:
rays/s = retina cells / wall time of ``ndtrace.trace(scene, threads=k)`` called from Python on
an already loaded scene (best of 3; shading and shadow rays included), the BVH build time
(loading the scene: validation, mesh, prepared simplices and BVH) and the peak resident memory
of a process that loads and traces only that scene. Then the N-cubes cube5 … cube8 (their
facets Kuhn-triangulated, (N−1)! simplices each) at 2²¹ retina cells (cube7 and cube8: one
run each).

Usage:  python bench/trace.py [--quick] [--only NAME ...]
  --quick   64³ retinas and 256² images, 2¹⁷ cells for the cubes, and no million-simplex
            sphere nor cube8
"""

from __future__ import annotations

import argparse
import json
import os

# numpy's OpenBLAS threads busy-wait after a BLAS call and would steal the cores the tracer is
# being measured on; the scenes are generated with single-threaded BLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SHARED = os.path.normpath(os.path.join(HERE, "..", "..", "shared", "bench"))


def icosphere(subdivisions: int) -> tuple[np.ndarray, np.ndarray]:
    """The icosphere of trimesh.creation.icosphere: 20·4^s triangles on the unit sphere."""
    t = (1 + 5**0.5) / 2
    v = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
                  [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], float)
    f = np.array([[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9],
                  [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2],
                  [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10],
                  [8, 6, 7], [9, 8, 1]])
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    for _ in range(subdivisions):
        edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
        uniq, inv = np.unique(edges, axis=0, return_inverse=True)
        mids = v[uniq].mean(axis=1)
        mids /= np.linalg.norm(mids, axis=1, keepdims=True)
        m = inv.reshape(3, -1).T + len(v)
        v = np.vstack([v, mids])
        a, b, c = f[:, 0], f[:, 1], f[:, 2]
        ab, bc, ca = m[:, 0], m[:, 1], m[:, 2]
        f = np.concatenate([np.stack([a, ab, ca], 1), np.stack([b, bc, ab], 1),
                            np.stack([c, ca, bc], 1), np.stack([ab, bc, ca], 1)])
    return v, f


def scene_4d(name: str, res: int) -> dict:
    d = np.load(os.path.join(SHARED, f"{name}.npz"))
    return {
        "dim": 4,
        "background": d["background"].tolist(),
        "ambient": d["ambient_light"].tolist(),
        "camera": {"position": d["camera_position"].tolist(),
                   "orientation": d["camera_orientation"].tolist(),
                   "fov": float(d["fov_degrees"]), "resolution": res},
        "lights": [{"type": "directional", "direction": d["light_direction"].tolist(),
                    "color": d["light_color"].tolist()}],
        "objects": [{"shape": "mesh", "file": os.path.join(SHARED, f"{name}.npz"),
                     "material": {"color": d["material_color"].tolist(),
                                  "ambient": np.asarray(d["material_ambient"]).tolist(),
                                  "specular": np.asarray(d["material_specular"]).tolist(),
                                  "shininess": float(d["material_shininess"])}}],
        "render": {"two_sided": True, "cull_backfaces": False, "shadows": True},
    }


def scene_ico(subdivisions: int, res: int, tmp: str) -> dict:
    v, f = icosphere(subdivisions)
    path = os.path.join(tmp, f"ico{subdivisions}.npz")
    np.savez(path, vertices=v, simplices=f.astype(np.int64))
    eye = 2.6 * np.array([0.3, 0.4, 1.0]) / np.linalg.norm([0.3, 0.4, 1.0])
    return {
        "dim": 3,
        "camera": {"position": eye.tolist(), "look_at": [0, 0, 0], "up": [[0, 1, 0]],
                   "fov": 45, "resolution": res},
        "lights": [{"type": "point", "position": [3, 4, 2]}],
        "objects": [{"shape": "mesh", "file": path}],
        "render": {"shadows": True},
    }


def scene_sphere4(res: int) -> dict:
    d = scene_4d("s3_3072", res)
    d["objects"] = [{"shape": "sphere", "subdivisions": 5, "material": d["objects"][0]["material"]}]
    return d


#: Retina resolutions of the N-cube scenes: 2²¹ cells (2¹⁷ with --quick), as even as powers of
#: two allow.
CUBE_RES = {5: [64, 32, 32, 32], 6: [32, 16, 16, 16, 16], 7: [16, 16, 16, 8, 8, 8],
            8: [8, 8, 8, 8, 8, 8, 8]}
CUBE_RES_QUICK = {5: [32, 16, 16, 16], 6: [16, 16, 8, 8, 8], 7: [8, 8, 8, 8, 4, 4],
                  8: [8, 4, 4, 4, 4, 4, 4]}


def scene_cube(dim: int, quick: bool) -> dict:
    """The N-cube (its facets Kuhn-triangulated: 2N·(N−1)! simplices), tilted, seen in
    perspective with a light, at 2²¹ retina cells."""
    up = [[1.0 if i == k else 0.0 for i in range(dim)] for k in range(1, dim - 1)]
    return {
        "dim": dim,
        "camera": {"position": [0.9 + 0.35 * i for i in range(dim)], "look_at": [0.0] * dim,
                   "up": up, "fov": 55, "resolution": (CUBE_RES_QUICK if quick else CUBE_RES)[dim]},
        "lights": [{"type": "directional", "direction": [0.3 + 0.1 * i for i in range(dim)]}],
        "objects": [{"shape": "hypercube", "transform": [{"rotate": {"plane": [0, dim - 1], "degrees": 20}}],
                     "material": {"color": [0.3, 0.6, 0.9]}}],
    }


def run_one(name: str, quick: bool) -> dict:
    """Loads and traces one scene in this process; returns its figures."""
    import ndtrace

    vol = 64 if quick else 128
    img = 256 if quick else 512
    with tempfile.TemporaryDirectory() as tmp:
        desc = {
            "s3_3072": lambda: scene_4d("s3_3072", vol),
            "elev_3072": lambda: scene_4d("elev_3072", vol),
            "ico6_81920": lambda: scene_ico(6, img, tmp),
            "ico8_1310720": lambda: scene_ico(8, img, tmp),
            "sphere4_1572864": lambda: scene_sphere4(vol),
            **{f"cube{n}": (lambda n=n: scene_cube(n, quick)) for n in CUBE_RES},
        }[name]()
        t0 = time.perf_counter()
        scene = ndtrace.load_dict(desc)
        build = time.perf_counter() - t0
        cells = int(np.prod(scene.retina_shape))
        prims, nodes, bvh_bytes = scene.compiled().bvh_stats()
        out = {"scene": name, "simplices": prims, "cells": cells, "build_s": build,
               "bvh_bytes_per_simplex": bvh_bytes / max(prims, 1)}
        # One run each for the slow high-N cubes (seconds per trace), else the best of 3.
        runs = 1 if name in ("cube7", "cube8") else 3
        for k in (1, 2):
            best = min(_timed(ndtrace.trace, scene, k) for _ in range(runs))
            out[f"rays_per_s_{k}t"] = cells / best
        out["peak_rss_mib"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        return out


def _timed(f, scene, k) -> float:
    t = time.perf_counter()
    f(scene, threads=k)
    return time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", nargs="*")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one:
        print(json.dumps(run_one(a.one, a.quick)))
        return
    names = a.only or (["s3_3072", "elev_3072", "ico6_81920", "ico8_1310720"]
                       + ([] if a.quick else ["sphere4_1572864"])
                       + ["cube5", "cube6", "cube7"] + ([] if a.quick else ["cube8"]))
    print(f"{'scene':<16} {'simplices':>10} {'cells':>9} {'build s':>8} {'Mrays/s 1t':>10} "
          f"{'Mrays/s 2t':>10} {'2t/1t':>6} {'BVH B/simplex':>13} {'peak MiB':>9}")
    for name in names:
        cmd = [sys.executable, __file__, "--one", name] + (["--quick"] if a.quick else [])
        r = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
        print(f"{r['scene']:<16} {r['simplices']:>10} {r['cells']:>9} {r['build_s']:>8.3f} "
              f"{r['rays_per_s_1t'] / 1e6:>10.2f} {r['rays_per_s_2t'] / 1e6:>10.2f} "
              f"{r['rays_per_s_2t'] / r['rays_per_s_1t']:>6.2f} {r['bvh_bytes_per_simplex']:>13.0f} "
              f"{r['peak_rss_mib']:>9.0f}", flush=True)


if __name__ == "__main__":
    main()
