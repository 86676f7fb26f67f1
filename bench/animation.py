"""Animation benchmark: the cost of a frame with and without rebuilding the scene.

Prints, for a 4D mesh of 1.57 M tetrahedra (the boundary of a 4D ball: the 3-sphere
tessellation of ``bench/build.py``, oriented) and a 24-frame orbit of the camera around it at a 64³
retina: the build (load) time, the time of one trace, and per frame of ``ndtrace.animate`` —
the camera animation (frames share the BVH: ``frame_scene`` reuses it) and the same orbit
written as an animation of the object (the world turned the other way; every frame traces the
scene's BVH, which holds the mesh in its own space, through the frame's turn) — and the time of
a frame built anew (``load_dict`` of the frame's description, median of 3), what an object's
frame would cost with a rebuild.

Usage:  python bench/animation.py [--quick]
  --quick   the 3-sphere at 24,576 tetrahedra, 6 frames
"""

from __future__ import annotations

import argparse
import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from build import sphere3  # noqa: E402  (the fixed 3-sphere mesh of the build benchmark)


def scene(v, s, target: str, frames: int):
    import ndtrace

    sc = ndtrace.Scene(4)
    sc.set_camera(position=[0.5, 0.8, 1.1, 3.0], look_at=[0, 0, 0, 0],
                  up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=50, resolution=64)
    sc.add_light("directional", direction=[0.3, 0.6, 0.5, 1.0])
    sc.add_object("mesh", vertices=v, simplices=s)
    data = sc.to_dict()
    data["animation"] = {"frames": frames, "target": target,
                         "sweep": {"plane": [0, 3], "degrees": [0, 90 if target == "camera" else -90]}}
    data["composite"] = {"size": [256, 256]}
    return ndtrace.load_dict(data)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    import ndtrace

    # Oriented (outward normals), as a user's mesh would be: none is culled, and every frame
    # certifies the moved mesh convex (its shadow rays' shortcut) as its build does.
    v, s = ndtrace.mesh.orient(*sphere3(8 if args.quick else 32))
    frames = 6 if args.quick else 24
    print(f"3-sphere mesh: {len(s):,} tetrahedra, {frames} frames of 64³ cells, 256² pictures")
    start = time.perf_counter()
    cam = scene(v, s, "camera", frames)
    build = time.perf_counter() - start
    start = time.perf_counter()
    ndtrace.trace(cam)
    one_trace = time.perf_counter() - start
    print(f"build {build:.2f} s, one trace {one_trace:.3f} s")
    obj = scene(v, s, "objects", frames)
    with tempfile.TemporaryDirectory() as tmp:
        for name, sc in (("camera moves (BVH shared)", cam), ("object moves (BVH instanced)", obj)):
            start = time.perf_counter()
            ndtrace.animate(sc, os.path.join(tmp, "a.gif"))
            total = time.perf_counter() - start
            print(f"{name:<28} {total:7.2f} s for {frames} frames = {total / frames:.3f} s per frame "
                  f"({total / (build + frames * one_trace):.2f}× one build + {frames} traces)")
    times = []
    for k in range(3):
        start = time.perf_counter()
        ndtrace.load_dict(obj.compiled().animation_frame(k))
        times.append(time.perf_counter() - start)
    print(f"a frame of the object built anew: {sorted(times)[1]:.2f} s before its trace")


if __name__ == "__main__":
    main()
