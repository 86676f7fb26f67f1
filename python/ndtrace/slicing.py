"""Pictures of a scene's ``[slice]``: what the command line and :func:`ndtrace.animate` draw
for a scene cut by a hyperplane (the 4D Toys view: an N-D object passing through our space).

* Without ``[composite] layout = "slice"``, the picture is the (N−1)-dimensional slice alone
  (:func:`ndtrace.slice_scene`), traced and composited like any scene: :func:`sliced` gives
  the scene to trace.
* With ``layout = "slice"``, the picture is the N-D projection (left half) with the slicing
  hyperplane marked where it crosses the objects (a band of cells whose hit point lies within
  :data:`BAND_CELLS` cells of the hyperplane, drawn in :data:`BAND_COLOR`; the projection in
  the ``first_hit`` mode unless the scene's ``[composite]`` names a mode) beside the current
  slice (right half): :func:`picture`. A slice of dimension 3 is traced at the picture's
  resolution (its retina is the picture).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .composite import composite
from .retina import Retina, trace
from .scene import Scene, load_dict, slice_scene

__all__ = ["sliced", "slice_options", "at_size", "picture", "hit_points", "BAND_COLOR",
           "BAND_CELLS"]

#: Linear RGB of the band that marks the slicing hyperplane in the projection.
BAND_COLOR = (0.0, 0.75, 1.0)
#: Half-width of that band, in retina cells (at the hit's depth).
BAND_CELLS = 1.0

#: Composite options that mean the same for the slice's picture as for the projection's.
_SHARED = ("size", "background", "mode", "azimuth", "elevation", "distance", "zoom",
           "projection", "opacity", "step", "rays_per_cell", "depth_cue", "fit", "crease_angle",
           "edges", "edge_width", "edge_color", "hidden_edges")


def _layout(description: dict) -> str:
    return str((description.get("composite") or {}).get("layout") or "single")


#: The picture size when the options give none (the compositor's default).
DEFAULT_SIZE = (512, 512)


def at_size(cut: Scene, size) -> Scene:
    """A 3D slice traced at the picture's size (its 2D retina is the picture), else as is."""
    if cut.dim != 3:
        return cut
    data = cut.to_dict()
    data["camera"]["resolution"] = [int(v) for v in (size or DEFAULT_SIZE)]
    return load_dict(data, base=cut._base)


def sliced(scene: Scene, size=None) -> Scene:
    """The scene to trace for a still of ``size`` (width, height): its ``[slice]`` when it has
    one and its layout is not ``"slice"`` (a 3D slice at the picture's resolution), else the
    scene itself."""
    data = scene.to_dict()
    if data.get("slice") is None or _layout(data) == "slice":
        return scene
    return at_size(slice_scene(scene), size)


def slice_options(options: dict, dim: int) -> dict:
    """The composite options of the projection's picture (``options``) that the picture of a
    slice of dimension ``dim`` takes: all that mean the same (``mode``, the view, edges …) for
    dim ≥ 4; ``size`` and ``background`` for a 3D or 2D slice, whose retina is the picture."""
    keep = _SHARED if dim >= 4 else ("size", "background")
    return {k: v for k, v in options.items() if k in keep}


def hit_points(retina: Retina) -> np.ndarray:
    """The world-space point of each cell's nearest hit (NaN on a miss), shape
    ``retina.depth.shape + (N,)``: x = C + depth·d̂ along the cell's centre ray (perspective),
    or from the cell's point of the image plane along the view (orthographic)."""
    info = retina._camera_info()
    if info is None or "position" not in info:
        raise ValueError("retina: its scene's camera is unknown (a retina traced from a scene "
                         "is needed)")
    n = retina.dim
    o = np.asarray(info["orientation"], dtype=np.float64).reshape(n, n)
    shape = retina.depth.shape  # (R_{N−1}, …, R_2, R_1)
    res = shape[::-1]
    s = float(info["cell"])
    idx = np.meshgrid(*[np.arange(r, dtype=np.float64) for r in shape], indexing="ij")
    # u_k of each cell centre, k = 1 … N−1 (u_2 counted down so that image rows go down).
    u = [(idx[n - 2 - k] + 0.5 - res[k] / 2) * s for k in range(n - 1)]
    if n >= 3:
        u[1] = -u[1]
    offset = sum(u[k][..., None] * o[:, k] for k in range(n - 1))
    position = np.asarray(info["position"], dtype=np.float64)
    view = o[:, n - 1]
    depth = retina.depth.astype(np.float64)[..., None]
    if info["perspective"]:
        d = view + offset
        x = position + depth * d / np.linalg.norm(d, axis=-1, keepdims=True)
    else:
        x = position + offset + depth * view
    x[~np.isfinite(retina.depth)] = np.nan
    return x


def _band(retina: Retina, normal, offset: float) -> Retina:
    """``retina`` with the cells whose hit lies within :data:`BAND_CELLS` cells of the
    hyperplane n̂·x = offset painted :data:`BAND_COLOR`, opaque, their normals turned across
    the surface (the in-surface direction of n̂), so that the illustrative mode draws the band
    as a crease and the other modes as a coloured stripe."""
    x = hit_points(retina)
    n = np.asarray(normal, dtype=np.float64)
    n = n / np.linalg.norm(n)
    info = retina._camera_info() or {}
    cell = float(info.get("cell", 0.0))
    depth = retina.depth.astype(np.float64)
    width = BAND_CELLS * cell * (depth if info.get("perspective") else 1.0)
    with np.errstate(invalid="ignore"):
        on = np.abs(x @ n - offset) <= width
    rgba = retina.rgba.copy()
    rgba[on] = (*BAND_COLOR, 1.0)
    # The normals: n̂ made orthogonal to each band cell's own (or an axis, where they agree).
    normals = retina.normal.copy()
    m = normals[on].astype(np.float64)
    across = n - (m @ n)[:, None] * m
    flat = np.linalg.norm(across, axis=1) < 1e-6
    if np.any(flat):
        axis = np.zeros(len(n))
        axis[int(np.argmin(np.abs(n)))] = 1.0
        across[flat] = axis - (m[flat] @ axis)[:, None] * m[flat]
    normals[on] = (across / np.linalg.norm(across, axis=1, keepdims=True)).astype(normals.dtype)
    return Retina(retina.dim, rgba, retina.depth, normals, retina.object_id,
                  retina.primitive_id, retina.camera, retina._source)


def picture(scene: Scene, retina: Retina, options: dict, *, threads: int | None = None,
            progress: Callable[[int, int], object] | None = None) -> np.ndarray:
    """The picture of ``retina`` (traced from ``scene``) composited with ``options``; with
    ``layout = "slice"`` the projection, with the scene's slicing hyperplane marked, beside
    the slice, traced here (``threads``, ``progress`` as for :func:`ndtrace.trace`)."""
    if options.get("layout") != "slice":
        return composite(retina, threads=threads, **options)
    data = scene.to_dict()
    cut = data.get("slice")
    if cut is None:
        raise ValueError('composite.layout: "slice" needs the scene\'s [slice] table (or '
                         "--slice) to say which hyperplane")
    # The band reads on the surface the first-hit mode draws; the illustrative mode's nearly
    # clear cells would hide it: first_hit unless the scene's [composite] chooses a mode.
    given = data.get("composite") or {}
    left_options = {**options, "mode": options.get("mode") if "mode" in given else "first_hit"}
    left = composite(_band(retina, cut["normal"], float(cut["offset"])), threads=threads,
                     **left_options)
    height, width = left.shape[:2]
    half = width - width // 2
    cut_scene = at_size(slice_scene(scene), (half, height))
    right_options = slice_options({**options, "size": (half, height)}, cut_scene.dim)
    right = composite(trace(cut_scene, threads=threads, progress=progress), threads=threads,
                      **right_options)
    out = left.copy()
    out[:, width // 2:] = right
    return out
