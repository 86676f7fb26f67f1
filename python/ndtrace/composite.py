"""Compositing a retina into a 2D picture: ``ndtrace.composite``.

The options are the core's (``CompositeOptions`` in ``crates/ndtrace/src/composite/options.rs``):
the keywords of :func:`composite` are the keys of a scene's ``[composite]`` table, and their
defaults and allowed ranges are declared and checked once, there.
"""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import numpy as np

from . import _ndtrace, annotate
from ._description import plain
from ._util import float32_array
from .retina import Retina

__all__ = ["composite", "scene_options", "picture_size", "MODES", "PROJECTIONS", "LEGEND", "AXES",
           "EDGE_COLOR_BY", "COLOR_BY", "PALETTES", "COLORMAPS"]

MODES: tuple[str, ...] = tuple(_ndtrace.COMPOSITE_MODES)
PROJECTIONS: tuple[str, ...] = tuple(_ndtrace.PROJECTIONS)
#: The values of ``legend`` and ``axes``: shown when they help, always, never.
LEGEND: tuple[str | bool, ...] = ("auto", True, False)
AXES: tuple[str | bool, ...] = LEGEND
#: The values of ``edge_color_by``.
EDGE_COLOR_BY: tuple[str, ...] = tuple(_ndtrace.EDGE_COLOR_BY)
#: The values of a material's ``color_by``, and its palettes and colormaps.
COLOR_BY: tuple[str, ...] = tuple(_ndtrace.COLOR_BY)
PALETTES: tuple[str, ...] = tuple(_ndtrace.PALETTES)
COLORMAPS: tuple[str, ...] = tuple(_ndtrace.COLORMAPS)

#: The default ``size``: (512, 512), or for a sections or stereo layout a picture whose panels
#: keep more than 256 pixels (the core's ``picture_size``). A caller's own (512, 512) is kept.
_DEFAULT_SIZE: tuple[int, int] = (512, 512)


def composite(
    retina,
    *,
    mode: str = "illustrative",
    azimuth: float = 30.0,
    elevation: float = 20.0,
    distance: float = 4.0,
    projection: str = "perspective",
    size: tuple[int, int] | None = _DEFAULT_SIZE,
    opacity: float = 1.0,
    depth_cue: float = 0.0,
    axis: int = 0,
    background: Sequence[float] | None = None,
    zoom: float = 1.0,
    step: float = 0.5,
    rays_per_cell: int = 1,
    samples: int = 0,
    detail: str = "scene",
    stages: Sequence[tuple[float, float]] | None = None,
    strip_height: int = 32,
    labels: bool = True,
    fit: bool = True,
    crease_angle: float = 20.0,
    edges: bool = True,
    edge_width: float = 0.0,
    edge_color: Sequence[float] | None = None,
    hidden_edges: str = "dashed",
    layout: str = "single",
    section: Sequence[float] = (0.0, 0.0, 0.0),
    stereo_angle: float = 6.0,
    cutaway: dict | None = None,
    turntable: int = 0,
    legend: str | bool = "auto",
    axes: str | bool = "auto",
    axes_frame: Sequence[Sequence[float]] | None = None,
    title: str | None = None,
    edge_color_by: str = "depth",
    cubes: dict | None = None,
    threads: int | None = None,
) -> np.ndarray:
    """Composites a retina into a 2D picture: a float32 array ``(H, W, 4)``, linear RGBA, row 0
    at the top (with ``turntable=F``: its F frames, ``(F, H, W, 4)``).

    **RGB is the retina composited over the opaque** ``background`` (``C + (1 − A)·bg``, C the
    accumulated premultiplied colour); **alpha is the opacity A of the retina's content alone**
    (1 − transmittance). With the default black background, ``(RGB, A)`` is therefore a valid
    premultiplied image.

    ``retina`` is an :class:`ndtrace.Retina` (its ``rgba`` and ``depth``) or a raw premultiplied
    rgba array of shape ``(..., 4)`` in numpy order ``[i_{N−1}, …, i_1, channel]`` (then there
    is no depth, and ``depth_cue`` must stay 0). A scene of dimension N has an (N−1)-D retina:

    * N = 4 — a 3D retina (slices, rows, columns): a 3D camera orbits the retina cube (its
      longest side spans [−1, 1]; world x = columns, y = up the rows, z = slices). At
      ``azimuth = elevation = 0`` it looks along the slices (slice 0 nearest) with columns to
      the right and row 0 on top; positive azimuth swings the eye to the right, positive
      elevation up.
    * N ≥ 5 — recursive projection: the retina is composited one leading axis at a time (an
      emission–absorption projection with its own perspective (f_k, d_k), see ``stages``) down
      to 3D, then rendered as for N = 4.
    * N = 3 — the 2D retina is the picture, scaled to fit ``size`` (aspect kept, centred,
      nearest cell, whole-number enlargement); ``size=None`` gives it at native size.
    * N = 2 — a strip ``strip_height`` pixels high across the whole width, centred vertically;
      ``size=None`` gives (R_1, strip_height).

    Keywords (defaults in brackets):

    * ``mode`` ["illustrative"] — for 3D volumes: ``"illustrative"`` (the default: nearly clear
      cells in their 4D-lit colour, with opacity where the retina has structure — creases
      between cells whose 4D normals differ by more than ``crease_angle``, occlusion contours,
      silhouettes seen edge-on — and, for a :class:`Retina` traced from a scene, its feature
      edges drawn over it with exact N-D visibility: visible ones solid, hidden ones per
      ``hidden_edges``; ``opacity`` scales the cells' interior opacity), ``"volume"``
      (front-to-back emission–absorption
      with trilinear sampling every ``step`` cells; a cell's alpha is its opacity over one cell,
      so a uniform slab of alpha a, L cells thick, has opacity exactly 1 − (1 − a)^L whatever the
      step; rays stop once transmittance < 1e-4), ``"mip"`` (maximum intensity projection: the
      crossed cell of largest luminance, shown unchanged), ``"first_hit"`` (the nearest point
      where the interpolated coverage reaches ½ — times ``opacity``, at most 1 — opaque in
      its colour there: a smooth surface, not voxel terraces) or
      ``"slices"`` (a near-square montage of the 2D slices along ``axis``, slice k in tile row
      k // cols and column k % cols, cols = ⌈√count⌉, 1-pixel grey separators, the index in each
      tile's corner in a built-in 3×5 font when ``labels``).
    * ``azimuth``, ``elevation`` [30, 20] — degrees.
    * ``distance`` [4.0] — eye distance in half-diagonals of the retina cube (> 1 for
      perspective). Perspective uses the field of view in which the cube's bounding sphere just
      fills the shorter side (tan(fov/2) = 1/√(distance² − 1)), so a larger distance only
      flattens the perspective; orthographic views span the sphere and ignore it.
    * ``projection`` ["perspective"] — or ``"orthographic"``; also used by every N ≥ 5 stage.
    * ``size`` [(512, 512); 720 × 720 for ``layout="sections"``, 960 × 540 for ``"stereo"``]
      — (W, H) pixels of the whole picture (panels, titles and legend included); None: native
      size for N ≤ 3, the default otherwise.
    * ``opacity`` [1.0] — multiplies every cell's alpha (and premultiplied colour; alpha clamped
      to 1) so inner structure shows through; e.g. 0.05 turns a solid traced body translucent.
    * ``depth_cue`` [0.0] — in [0, 1]: tints each cell by its N-D depth, warm (near) to cool
      (far), normalized over the retina's depth range. Needs a Retina.
    * ``axis`` [0] — for ``"slices"``: 0 slices, 1 rows, 2 columns of the 3D volume.
    * ``background`` [None = black] — opaque linear RGB.
    * ``zoom`` [1.0] — magnification of the 3D view.
    * ``step`` [0.5] — sample spacing of ``"volume"`` in cells, 0.01 … 4.
    * ``rays_per_cell`` [1] — for N ≥ 4 views (not ``"mip"``, which traces every pixel):
      rays are cast through every s-th pixel (s ≤ 16), s chosen so that at most this many
      cross a cell where cells look smallest; the pixels between them are traced where the
      picture changes and interpolated where it is smooth (all but a few pixels in a thousand
      within two 8-bit levels of a ray through every pixel; a 128³ retina at 1024² costs a
      fifth of a ray per pixel). 0 traces every pixel; 0 … 64.
    * ``stages`` [None] — for N ≥ 5: N − 4 pairs (f_k, d_k), from the stage collapsing the
      retina's leading axis, (f_{N−1}, d_{N−1}), down to (f_4, d_4). Each stage puts its box
      (longest axis spanning [−1, 1], collapsed axis ±a_k) with the eye at x_k = −d_k and maps
      x_j ↦ x_j·f_k/(d_k + x_k). Need f_k > 0, d_k > a_k. Default d_k = 3 and f_k chosen so
      slice 0 maps one-to-one (farther slices appear smaller).
    * ``strip_height`` [32] — for N = 2.
    * ``labels`` [True] — slice numbers in the montage.
    * ``fit`` [True] — for N ≥ 4: frame the box of the occupied cells (``distance`` then counts
      in its half-diagonals), so the object fills the picture; False frames the whole retina.
    * ``crease_angle`` [20] — degrees, 0 … 90: the illustrative mode's creases and the feature
      edges (:func:`ndtrace.mesh.feature_edges`).
    * ``edges`` [True] — the illustrative mode draws the scene's feature edges (a retina from
      :func:`ndtrace.trace`; a raw array or a retina read from a file has none).
    * ``edge_width`` [0 = automatic, max(1, min(W, H)/300)] — pixels, 0 … 64.
    * ``edge_color`` [None = near-white on dark backgrounds, near-black on light ones] — linear
      RGB; with ``depth_cue`` > 0 edges are also tinted by N-D depth.
    * ``hidden_edges`` ["dashed"] — pieces hidden in N-D: ``"dashed"``, ``"faint"`` or
      ``"none"``.
    * ``layout`` ["single"] — for N ≥ 4: ``"sections"`` puts the view in the top-left quadrant
      and three orthogonal sections through ``section`` in the others (top right across z:
      the retina slice face-on; bottom left across x: z right, y up; bottom right across y:
      x right, z down); ``"stereo"`` a side-by-side pair for parallel viewing, the left half
      from ``azimuth − stereo_angle/2``, the right from ``azimuth + stereo_angle/2``;
      ``"slice"`` the view in the left half, the right half left for the scene's ``[slice]``
      (the command line and :func:`ndtrace.animate` draw the slice there and mark the
      hyperplane in the view: :func:`ndtrace.slicing.picture`).
    * ``section`` [(0, 0, 0)] — the world point (volume centred, longest side spanning
      [−1, 1]; x columns, y up, z slices) the sections pass through.
    * ``stereo_angle`` [6] — degrees between the eyes of the stereo pair, 0 … 30.
    * ``cutaway`` [None] — for N ≥ 4: a region of the 3D volume removed so its inside shows,
      in the same world coordinates: ``{"shape": "half_space", "normal": [x, y, z],
      "offset": d}`` (removes n̂·x > d), ``{"shape": "sphere", "center": [...], "radius": r}``
      or ``{"shape": "box", "min": [...], "max": [...]}``; cells are removed smoothly by the
      fraction of a cell inside, and feature edges are cut with them.
    * ``cubes`` [None] — for N ≥ 4, ``{"size": s}`` (0 < s ≤ 1, default 0.6): each occupied
      cell (coverage ≥ ½) drawn as an opaque cube of side s cells, the course's "break into
      tiny cubes: leave a little space instead of transparency", whatever the mode; faces
      shaded by a headlight.
    * ``turntable`` [0] — F > 0 returns F frames, frame k seen from ``azimuth + 360°·k/F``:
      motion parallax for the price of one trace (the retina is prepared once).
    * ``legend`` ["auto"] — a strip along the bottom: a colour bar per colormap (its name,
      range, ticks and the isoline levels marked) and keys of the colours of ``color_by``, of
      the objects' labels and of edges coloured by direction; "auto" shows it when the
      scene has one of those (a Retina traced from a scene: a raw array has no legend), True
      and False force it.
    * ``axes`` ["auto" = for N ≥ 4] — the N-D axes glyph in the lower-left corner of the view:
      the world axes x, y, z, w (then x5 …) as arrows through the N-D camera, the stages and
      the compositing camera (``ndtrace._ndtrace.axis_arrows``), each shortened by its part
      along lines of sight and dimmed (dashed) as it points away from the N-D eye. Needs the
      retina's camera (a Retina).
    * ``axes_frame`` [None = the world axes] — N rows of N numbers: the glyph shows its columns
      (the viewer passes its rotation, so the glyph turns with the object).
    * ``title`` [None] — a caption line above the picture. Panels have their own titles
      (sections: "volume" and each section's coordinate, in the scene's units for an
      axis-aligned orthographic camera; stereo: "left", "right"; N ≥ 5: the axes the
      stages collapse).
    * ``edge_color_by`` ["depth"] — the feature edges: "depth" (the course's depth cueing:
      thicker and stronger near the N-D eye, thinner and fainter far from it), "direction"
      (parallel edges share a colour of the object's ``material.palette``, keyed in the
      legend) or "none" (one colour and width).
    Text is drawn at the picture's resolution, anti-aliased, in the DejaVu Sans subset shipped
    with ndtrace (:mod:`ndtrace.annotate`).
    * ``threads`` [None = every core] — the picture is bit-identical whatever the number.

    Raises ValueError naming the argument on bad input.
    """
    if isinstance(retina, Retina):
        rgba = float32_array("retina.rgba", retina.rgba)
        depth = float32_array("retina.depth", retina.depth)
    else:
        if isinstance(retina, (str, bytes)) or retina is None:
            raise ValueError(f"retina: expected an ndtrace.Retina or an rgba array, got {type(retina).__name__}")
        rgba = float32_array("retina", retina)
        depth = None
    if rgba.ndim < 2 or rgba.shape[-1] != 4:
        raise ValueError(f"retina: expected rgba of shape (..., 4) with 1 to 7 retina axes, got {rgba.shape}")
    if not 1 <= rgba.ndim - 1 <= 7:
        raise ValueError(f"retina: a retina has 1 to 7 axes (N = 2..8), got shape {rgba.shape}")
    if depth is not None and depth.shape != rgba.shape[:-1]:
        raise ValueError(f"retina.depth: expected shape {rgba.shape[:-1]}, got {depth.shape}")
    if threads is not None:
        if isinstance(threads, bool) or not isinstance(threads, numbers.Integral) or threads < 1:
            raise ValueError(f"threads: expected a positive integer or None, got {threads!r}")
        threads = int(threads)
    shape = rgba.shape[:-1]
    if size is None:  # the native size of a 2D or 1D retina
        size = (shape[1], shape[0]) if len(shape) == 2 else (shape[0], strip_height) if len(shape) == 1 else _DEFAULT_SIZE
    options = dict(mode=mode, azimuth=azimuth, elevation=elevation, distance=distance, zoom=zoom,
                   projection=projection, opacity=opacity, step=step,
                   rays_per_cell=rays_per_cell, samples=samples, detail=detail, depth_cue=depth_cue,
                   axis=axis, strip_height=strip_height, labels=labels, fit=fit,
                   crease_angle=crease_angle, edges=edges, edge_width=edge_width,
                   hidden_edges=hidden_edges, layout=layout, section=section,
                   stereo_angle=stereo_angle, turntable=turntable, legend=legend, axes=axes,
                   edge_color_by=edge_color_by)
    if size is not _DEFAULT_SIZE:  # else the layout's default
        options["size"] = size
    if title is not None:
        options["title"] = title
    if axes_frame is not None:
        options["axes_frame"] = np.asarray(axes_frame, dtype=float).tolist()
    if cutaway is not None:
        options["cutaway"] = cutaway
    if cubes is not None:
        options["cubes"] = cubes
    if background is not None:
        options["background"] = background
    if stages is not None:
        options["stages"] = stages
    if edge_color is not None:
        options["edge_color"] = edge_color
    normal = camera = lines = source = objects = None
    if isinstance(retina, Retina) and mode == "illustrative" and len(shape) >= 3:
        normal = float32_array("retina.normal", retina.normal)
        camera = retina._camera_info()
        if edges:
            lines = retina._edges(crease_angle)
    if isinstance(retina, Retina) and detail == "scene" and retina._source is not None and len(shape) == 3:
        source = retina._source
        objects = np.ascontiguousarray(retina.object_id, dtype=np.int32)
    given = plain(options)
    rows = annotate.legend_rows(retina, options)
    picture = _ndtrace.composite(rgba, depth, given, threads, normal, camera, lines, source, objects,
                                 len(rows))
    return _annotate(picture, retina, shape, options, rows)


def _annotate(picture: np.ndarray, retina, shape: tuple[int, ...], options: dict,
              rows: list) -> np.ndarray:
    """Draws the caption, panel titles, legend and axes glyph into the composite (every frame
    of a turntable, each with its own glyph)."""
    camera = retina._camera_info() if isinstance(retina, Retina) else None
    layout = _ndtrace.picture_layout(list(shape), plain(options), len(rows), camera)
    titled = options.get("title") is not None or any(p["title"] for p in layout["panels"])
    glyph = layout["axes"] is not None and camera is not None
    if not (titled or rows or glyph):
        return picture
    background = options.get("background")
    background = (0.0, 0.0, 0.0) if background is None else tuple(float(v) for v in background)
    turntable = int(options.get("turntable") or 0)
    frames = picture if turntable else picture[None]
    for k, frame in enumerate(frames):
        o = dict(options, azimuth=float(options["azimuth"]) + 360.0 * k / turntable) if turntable else options
        arrows = _ndtrace.axis_arrows(list(shape), camera, plain(o)) if glyph and camera else None
        annotate.draw(frame, annotate.items(layout, rows, arrows, o, background))
    return picture


def picture_size(shape: Sequence[int], options: dict) -> tuple[int, int]:
    """The size of the picture :func:`composite` makes of a retina of numpy ``shape`` with the
    keywords ``options``: their ``size``, or the default of their ``layout``."""
    w, h = _ndtrace.picture_layout(list(shape), plain(options))["size"]
    return int(w), int(h)


def scene_options(description: dict) -> dict:
    """The :func:`composite` keyword arguments a scene asks for: its ``[composite]`` table, with
    the scene's ``background`` unless the table sets one. ``description`` is ``Scene.to_dict()``."""
    options = dict(description.get("composite") or {})
    options.setdefault("background", description["background"])
    return options
