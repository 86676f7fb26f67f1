"""Scene build benchmark (issue 23): numpy mesh arrays → built, traceable scene.

For each mesh, in a fresh subprocess so that its peak memory is its own, prints

* ``load+build s``: ``ndtrace.Scene(N).add_object("mesh", vertices=v, simplices=s)`` and
  ``.compiled()`` (handing the arrays over, validation, orientation check, prepared simplices,
  BVH), median of ``--repeat`` runs; with ``--via load_dict``, ``ndtrace.load_dict`` of the same
  scene as a dict holding the numpy arrays instead; with ``--light``, the scene has a
  directional light and shadows (whose convexity certificates are found by the first trace,
  not by the build);
* ``embree s`` (3D meshes, when ``embreex`` is installed): Embree's BVH commit of the same
  triangles in the same process (``EmbreeScene`` + ``TriangleMesh``, committed by its first
  ray query), median of as many runs; and the ratio of the two;
* ``peak B/simplex``: the growth of the process's peak resident memory over what it held with
  the mesh arrays loaded (the cost of the load itself), per simplex; after one build of a tiny
  mesh of the same dimension, so that what any first build costs once (the thread pool, the
  extension's code paged in: about 10 MB) is not counted per simplex;
* ``BVH B/simplex``: the built BVH's own memory (``bvh_stats``);
* ``trace s``: the first trace of a small retina after each build, median (it must not depend
  on the scene's size beyond tracing; with ``--light`` it finds the convexity certificate).

Meshes: the icospheres ico6 (81,920 triangles) and ico8 (1,310,720) of ``bench/trace.py``; the
3-sphere of 1,572,864 tetrahedra (the tesseract's boundary, each cubic cell cut into 32³ cubes
of 6 tetrahedra, projected onto S³); a 128³ elevation map (12.3 M tetrahedra) as mesh arrays
(``ndtrace.mesh.elevation_map``), with ``--big``.

Usage:  python bench/build.py [--only NAME ...] [--repeat 3] [--big] [--light]
                              [--via builder|load_dict]
"""

from __future__ import annotations

import argparse
import json
import os

# numpy's OpenBLAS threads busy-wait after a BLAS call and would steal the build's cores.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)


def sphere3(k: int) -> tuple[np.ndarray, np.ndarray]:
    """The tesseract's boundary, each of its 8 cubic cells cut into k³ cubes of 6 tetrahedra
    (Kuhn), projected onto the unit 3-sphere: 48·k³ tetrahedra (orientation not consistent)."""
    g = np.linspace(-1, 1, k + 1)
    a, b, c = np.meshgrid(g, g, g, indexing="ij")
    grid = np.stack([a, b, c], -1).reshape(-1, 3)
    idx = np.arange((k + 1) ** 3).reshape(k + 1, k + 1, k + 1)
    corner = idx[:-1, :-1, :-1].reshape(-1)
    steps = np.array([(k + 1) ** 2, k + 1, 1])
    tets = []
    for perm in ((0, 1, 2), (0, 2, 1), (1, 0, 2), (1, 2, 0), (2, 0, 1), (2, 1, 0)):
        path = np.cumsum([0] + [steps[p] for p in perm])
        tets.append(corner[:, None] + path[None, :])
    cube = np.concatenate(tets)
    verts, simplices = [], []
    for axis in range(4):
        for sign in (-1.0, 1.0):
            v = np.insert(grid, axis, sign, axis=1)
            simplices.append(cube + sum(len(x) for x in verts))
            verts.append(v)
    # Cells share their boundary vertices (the same grid values, bit for bit): one vertex each,
    # so that the mesh is closed.
    v, inverse = np.unique(np.concatenate(verts), axis=0, return_inverse=True)
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    return v, inverse.reshape(-1)[np.concatenate(simplices)]


def mesh(name: str) -> tuple[np.ndarray, np.ndarray]:
    from trace import icosphere

    if name == "ico6":
        return icosphere(6)
    if name == "ico8":
        return icosphere(8)
    if name == "sphere4":
        return sphere3(32)
    if name == "elevation128":
        from elevation import field
        import ndtrace

        return ndtrace.mesh.elevation_map(field(128), height=0.5)
    raise SystemExit(f"unknown mesh {name!r}")


def camera(dim: int) -> dict:
    if dim == 3:
        eye = 2.6 * np.array([0.3, 0.4, 1.0]) / np.linalg.norm([0.3, 0.4, 1.0])
        return dict(position=eye.tolist(), look_at=[0, 0, 0], up=[0, 1, 0], fov=45, resolution=16)
    return dict(position=[0.9, 1.2, 1.6, 3.2], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]],
                fov=45, resolution=16)


LIGHT = dict(type="directional", direction=[0.3, 0.5, 0.8])


def build(dim: int, obj: dict, via: str, light: bool):
    """The scene of the object `obj` (``add_object``'s keys, with ``shape``) built through the
    builder or through ``load_dict``, with a directional light and shadows when `light`: (the
    scene, its compiled form)."""
    import ndtrace

    if via == "load_dict":
        d = dict(dim=dim, camera=camera(dim), objects=[obj], render=dict(shadows=True),
                 lights=[LIGHT] if light else [])
        scene = ndtrace.load_dict(d)
    else:
        scene = ndtrace.Scene(dim).set_camera(**camera(dim)).add_object(**obj)
        if light:
            scene.add_light(**LIGHT).set_render(shadows=True)
    return scene, scene.compiled()


def _peak() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024.0


def run_one(name: str, repeat: int, via: str, light: bool) -> dict:
    import ndtrace

    v, s = mesh(name)
    v, s = np.ascontiguousarray(v, np.float64), np.ascontiguousarray(s, np.int64)
    dim = v.shape[1]
    out = {"mesh": name, "dim": dim, "simplices": len(s)}
    if dim == 3:
        try:
            from embreex import mesh_construction, rtcore_scene
        except ImportError:
            pass
        else:
            v32, s32 = v.astype(np.float32), s.astype(np.int32)
            ray_o, ray_d = np.zeros((1, 3), np.float32), np.array([[0, 0, 1]], np.float32)
            times = []
            for _ in range(repeat):
                es = rtcore_scene.EmbreeScene()
                mesh_construction.TriangleMesh(es, v32, s32)
                t = time.perf_counter()
                es.run(ray_o, ray_d)  # commits the scene: Embree's BVH build
                times.append(time.perf_counter() - t)
                del es
            out["embree_s"] = statistics.median(times)
            del v32, s32
    # One tiny build first: the costs of a process's first build are not the mesh's.
    tiny, _ = build(dim, dict(shape="simplex"), via, light)
    ndtrace.trace(tiny)
    del tiny
    base = _peak()
    times, traces = [], []
    for _ in range(repeat):
        t = time.perf_counter()
        scene, compiled = build(dim, dict(shape="mesh", vertices=v, simplices=s), via, light)
        times.append(time.perf_counter() - t)
        if len(times) == 1:
            out["peak_bytes_per_simplex"] = (_peak() - base) / len(s)
        prims, _, bvh_bytes = compiled.bvh_stats()
        out["bvh_bytes_per_simplex"] = bvh_bytes / max(prims, 1)
        t = time.perf_counter()
        ndtrace.trace(scene)
        traces.append(time.perf_counter() - t)
        del scene, compiled
    out["build_s"] = statistics.median(times)
    out["trace_s"] = statistics.median(traces)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", nargs="*")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--big", action="store_true", help="also the 128³ elevation map (12.3 M simplices)")
    ap.add_argument("--light", action="store_true",
                    help="a directional light with shadows (the first trace finds the certificate)")
    ap.add_argument("--via", choices=["builder", "load_dict"], default="builder",
                    help="build through ndtrace.Scene (default) or ndtrace.load_dict")
    ap.add_argument("--one", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one:
        print(json.dumps(run_one(a.one, a.repeat, a.via, a.light)))
        return
    names = a.only or ["ico6", "ico8", "sphere4"] + (["elevation128"] if a.big else [])
    print(f"{'mesh':<13} {'N':>2} {'simplices':>10} {'via':>9} {'light':>5} {'load+build s':>12} "
          f"{'embree s':>9} {'ratio':>6} {'peak B/simplex':>14} {'BVH B/simplex':>13} {'trace s':>8}")
    for name in names:
        cmd = [sys.executable, __file__, "--one", name, "--repeat", str(a.repeat), "--via", a.via]
        cmd += ["--light"] if a.light else []
        r = json.loads(subprocess.run(cmd, check=True, capture_output=True, text=True).stdout)
        e = r.get("embree_s")
        print(f"{r['mesh']:<13} {r['dim']:>2} {r['simplices']:>10} {a.via:>9} "
              f"{'yes' if a.light else 'no':>5} {r['build_s']:>12.3f} "
              f"{'' if e is None else format(e, '.3f'):>9} "
              f"{'' if e is None else format(r['build_s'] / e, '.2f'):>6} "
              f"{r['peak_bytes_per_simplex']:>14.0f} {r['bvh_bytes_per_simplex']:>13.0f} "
              f"{r['trace_s']:>8.3f}", flush=True)


if __name__ == "__main__":
    main()
