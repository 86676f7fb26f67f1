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

Usage:  python bench/composite.py [--res 128] [--size 1024]
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--size", type=int, default=1024)
    a = ap.parse_args()
    size = (a.size, a.size)
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


if __name__ == "__main__":
    main()
