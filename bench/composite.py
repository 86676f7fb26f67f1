"""Compositing benchmark: time to composite a 128³ retina into a 1024×1024 picture.

Prints, for two synthetic 128³ retinas and at 1 and 2 threads, the best of 3 wall times of
``ndtrace.composite(retina, size=(1024, 1024), threads=k, ...)`` called from Python:

* ``sphere``: a traced 4D unit sphere (``shape = "sphere"``, 4 subdivisions), an opaque solid
  ball of shaded cells on the retina, in volume mode at opacity 1 (rays stop at the surface)
  and at opacity 0.05 (a translucent cloud every ray crosses), and in mip / first_hit mode;
* ``tesseract``: ``scenes/tesseract.toml`` traced at 128³ with 4 samples, in the default
  illustrative mode with its feature edges (exact N-D visibility) drawn; the first call also
  finds the edges (BVH visibility, then cached on the retina): its time is printed apart;
* ``cloud``: a procedural volume, smooth noise-like alpha in (0, 0.25] filling the whole cube
  (the worst case for the volume mode: no empty space, no early termination).

Then, with ``--pictures`` (or alone with ``--only-pictures``), the figures of issue 47: the
wall time of a picture at 1024² drawn from its scene (``detail="scene"``, the default) beside
the same picture from the retina's cells (``detail="retina"``, the grid path), each trace +
composite, best of 3:

* the tesseract (``scenes/tesseract.toml``, its 64³ retina, 4 samples), default picture;
* the 3-sphere of 1,572,864 tetrahedra (``bench/build.py``'s ``sphere3``: the tesseract's
  boundary cut into 32³ cubes per cell, projected onto S³) under the camera, light and
  composite of ``scenes/sphere3.toml``, after its build (the first composite also finds its
  ridges: printed apart);
* the bear-haired Clifford torus (``scenes/clifford_torus_hair.py``, 80³, first_hit).

Usage:  python bench/composite.py [--res 128] [--size 1024] [--pictures | --only-pictures]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import ndtrace


def traced_sphere(res: int) -> ndtrace.Retina:
    scene = ndtrace.load_dict({
        "dim": 4,
        "camera": {"position": [0, 0, 0, 3.2], "look_at": [0, 0, 0, 0],
                   "up": [[0, 1, 0, 0], [0, 0, 1, 0]], "fov": 45, "resolution": res},
        "lights": [{"type": "directional", "direction": [0.5, 0.8, 0.3, 1.0]}],
        "objects": [{"shape": "sphere", "subdivisions": 4,
                     "material": {"color": [0.9, 0.6, 0.3], "specular": 0.3, "shininess": 30}}],
    })
    return ndtrace.trace(scene)


def cloud(res: int) -> np.ndarray:
    """Sum of a few sines in a ball: alpha in (0, 0.25], colour from position."""
    g = (np.arange(res, dtype=np.float32) + 0.5) / res * 2 - 1
    z, y, x = np.meshgrid(g, g, g, indexing="ij")
    field = (np.sin(5 * x + 1) * np.sin(4 * y + 2) * np.sin(6 * z) + 1.2) / 2.2
    alpha = (0.25 * field * np.clip(1.3 - (x * x + y * y + z * z), 0.05, 1.0)).astype(np.float32)
    rgba = np.stack([(0.5 + 0.5 * x) * alpha, (0.5 + 0.5 * y) * alpha, (0.5 + 0.5 * z) * alpha, alpha], -1)
    return np.ascontiguousarray(rgba, dtype=np.float32)


def traced_tesseract(res: int) -> ndtrace.Retina:
    import os

    scenes = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "scenes")
    d = ndtrace.load_file(os.path.join(scenes, "tesseract.toml")).to_dict()
    d["camera"]["resolution"] = res
    d.setdefault("render", {})["samples"] = 4
    return ndtrace.trace(ndtrace.load_dict(d, base=scenes))


def best(f, repeat: int = 3) -> float:
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return min(times)


def pictures(size: tuple[int, int]) -> None:
    """Issue 47's figures: trace + composite at `size`, from the scene and from the cells."""
    import importlib
    import os
    import runpy
    import sys

    here = os.path.dirname(os.path.abspath(__file__))
    scenes = os.path.join(here, "..", "scenes")
    sys.path.insert(0, here)
    from build import sphere3

    def with_options(scene):
        return dict(importlib.import_module("ndtrace.composite").scene_options(scene.to_dict()), size=size)

    tesseract = ndtrace.load_file(os.path.join(scenes, "tesseract.toml"))
    v, t = sphere3(32)
    desc = ndtrace.load_file(os.path.join(scenes, "sphere3.toml")).to_dict()
    desc["objects"] = [dict(desc["objects"][0], shape="mesh", vertices=v, simplices=t)]
    desc["objects"][0].pop("subdivisions", None)
    t0 = time.perf_counter()
    big = ndtrace.load_dict(desc)
    big.compiled()
    print(f"3-sphere of {len(t):,} tetrahedra built in {time.perf_counter() - t0:.2f} s")
    t0 = time.perf_counter()
    ndtrace.composite(ndtrace.trace(big), **with_options(big))
    print(f"3-sphere: first trace + composite (finds its ridges) {time.perf_counter() - t0:.2f} s")
    hair = runpy.run_path(os.path.join(scenes, "clifford_torus_hair.py"))["scene"]()
    hair.compiled()
    print(f"{'picture':<28} {'from the scene s':>16} {'from the cells s':>16}   (trace + composite, {size[0]}×{size[1]})")
    for name, scene in (("tesseract (64³)", tesseract), ("3-sphere 1.57 M tets (64³)", big),
                        ("Clifford torus hair (80³)", hair)):
        opts = with_options(scene)
        times = []
        for detail in ("scene", "retina"):
            times.append(best(lambda: ndtrace.composite(ndtrace.trace(scene), detail=detail, **opts)))
        print(f"{name:<28} {times[0]:>16.3f} {times[1]:>16.3f}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--size", type=int, default=1024)
    ap.add_argument("--pictures", action="store_true", help="also issue 47's figures")
    ap.add_argument("--only-pictures", action="store_true", help="only issue 47's figures")
    a = ap.parse_args()
    size = (a.size, a.size)
    if a.only_pictures:
        pictures(size)
        return
    t = time.perf_counter()
    sphere = traced_sphere(a.res)
    print(f"traced a {a.res}³ retina of a 4D sphere in {time.perf_counter() - t:.2f} s "
          f"({sphere.hit.mean() * 100:.0f}% of cells hit)")
    tesseract = traced_tesseract(a.res)
    t = time.perf_counter()
    ndtrace.composite(tesseract, size=size)
    print(f"tesseract illustrative, first call (finds the edges): {time.perf_counter() - t:.3f} s")
    cases = [
        ("tesseract", "illustrative + edges", tesseract, dict()),
        ("sphere", "illustrative", sphere, dict()),
        ("sphere", "volume, opacity 1", sphere, dict(mode="volume")),
        ("sphere", "volume, opacity 0.05", sphere, dict(mode="volume", opacity=0.05)),
        ("sphere", "mip", sphere, dict(mode="mip")),
        ("sphere", "first_hit", sphere, dict(mode="first_hit")),
        ("cloud", "volume", cloud(a.res), dict(mode="volume")),
    ]
    print(f"{'retina':<9} {'mode':<22} {'1 thread s':>10} {'2 threads s':>11} {'speed-up':>8}")
    for name, label, retina, kw in cases:
        t1 = best(lambda: ndtrace.composite(retina, size=size, threads=1, **kw))
        t2 = best(lambda: ndtrace.composite(retina, size=size, threads=2, **kw))
        print(f"{name:<9} {label:<22} {t1:>10.3f} {t2:>11.3f} {t1 / t2:>8.2f}", flush=True)
    if a.pictures:
        pictures(size)


if __name__ == "__main__":
    main()
