"""4D hidden-line drawings as vector files: ``ndtrace.write_svg`` and ``-o out.svg``.

The drawing is the illustrative composite's edge layer as SVG paths: every object's feature
edges (:func:`ndtrace.mesh.feature_edges`) split exactly into the pieces the N-D camera sees and
those hidden in N-D (:func:`ndtrace.edge_segments`), projected through the same maps as the
raster picture (the retina, the N ≥ 5 stages, the compositing camera), so a line of the SVG lies
where the composite draws it. Visible pieces are solid, hidden ones dashed or faint (or left
out), coloured by N-D depth with ``depth_cue``; beneath them, optionally, the composite itself
(without its edges) as an embedded image, which fills the object's silhouette.
"""

from __future__ import annotations

import base64
import io
import os

import numpy as np

from . import _ndtrace, annotate
from ._description import plain
from ._util import c_array, float32_array, output_done, output_temp
from .composite import scene_options
from .retina import Retina, trace
from .scene import Scene

__all__ = ["write_svg", "svg_text"]

#: Hidden pieces: their dash pattern (pixels), opacity and width relative to visible ones, as
#: the raster overlay draws them.
DASH = (4.5, 3.5)
HIDDEN_OPACITY = {"dashed": 0.6, "faint": 0.3}
HIDDEN_WIDTH = 0.6


def _hex(rgb) -> str:
    """Linear RGB in [0, 1] → ``#rrggbb`` (sRGB)."""
    px = np.asarray([[list(rgb) + [1.0]]], dtype=np.float32)
    r, g, b = _ndtrace.to_srgb8(px, True)[0, 0]
    return f"#{int(r):02x}{int(g):02x}{int(b):02x}"


def _options(source, options: dict) -> dict:
    base = scene_options(source.to_dict()) if isinstance(source, Scene) else {}
    merged = {**base, **options}
    merged.pop("turntable", None)
    merged.pop("layout", None)
    merged["mode"] = "illustrative"
    return merged


def svg_text(scene_or_retina, *, fill: bool = True, threads: int | None = None, **options) -> str:
    """The SVG document of :func:`write_svg` as a string."""
    if isinstance(scene_or_retina, Scene):
        retina = trace(scene_or_retina, threads=threads)
    elif isinstance(scene_or_retina, Retina):
        retina = scene_or_retina
    else:
        raise ValueError(f"scene: expected an ndtrace.Scene or a Retina traced from one, got "
                         f"{type(scene_or_retina).__name__}")
    if retina._source is None:
        raise ValueError("scene: this retina has no scene (read from a file?): its edges are "
                         "unknown; pass the Scene or a retina from ndtrace.trace")
    if retina.dim < 4:
        raise ValueError(f"scene: an SVG drawing needs N ≥ 4 (a 3D or larger retina), got N = {retina.dim}")
    opts = _options(scene_or_retina, options)
    angle = float(opts.get("crease_angle", 20.0))
    hidden = opts.get("hidden_edges", "dashed")
    keys = {k: v for k, v in opts.items() if v is not None}
    rgba = float32_array("retina.rgba", retina.rgba)
    depth = float32_array("retina.depth", retina.depth)
    normal = float32_array("retina.normal", retina.normal)
    camera = retina._camera_info()
    source = retina._source if keys.get("detail", "scene") == "scene" and retina.rgba.ndim == 4 else None
    objects = np.ascontiguousarray(retina.object_id, dtype=np.int32) if source is not None else None
    rows = annotate.legend_rows(retina, keys)
    given = plain(keys)
    edges = np.asarray(_ndtrace.picture_edges(rgba, depth, given, threads, normal, camera,
                                              retina._edges(angle), source, objects, len(rows)))
    layout = _ndtrace.picture_layout(list(retina.shape), given, len(rows), camera)
    w, h = (int(v) for v in layout["size"])
    width = float(opts.get("edge_width") or 0.0) or max(1.0, min(w, h) / 300.0)
    bg = opts.get("background") or [0.0, 0.0, 0.0]
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" '
        f'width="{w}" height="{h}" viewBox="0 0 {w} {h}">',
        "<title>ndtrace: feature edges with exact N-D visibility</title>",
        f'<rect width="{w}" height="{h}" fill="{_hex(bg)}"/>',
    ]
    if fill:
        from PIL import Image

        # The composite without its edges and without its annotations (drawn below as vectors).
        picture = _ndtrace.composite(rgba, depth, plain({**keys, "edges": False}), threads, normal,
                                     camera, None, source, objects, len(rows))
        buf = io.BytesIO()
        Image.fromarray(_ndtrace.to_srgb8(c_array(picture, np.float32), True)).save(buf, "PNG")
        data = base64.b64encode(buf.getvalue()).decode("ascii")
        out.append(f'<image width="{w}" height="{h}" preserveAspectRatio="none" '
                   f'href="data:image/png;base64,{data}" xlink:href="data:image/png;base64,{data}"/>')

    def layer(visible: bool) -> list[str]:
        pieces = edges[edges[:, 9] == (1.0 if visible else 0.0)] if len(edges) else edges
        if not len(pieces):
            return []
        if visible:
            style = f'stroke-width="{width:.3g}"'
            name = "visible"
        else:
            style = (f'stroke-width="{HIDDEN_WIDTH * width:.3g}" stroke-opacity="{HIDDEN_OPACITY[hidden]}"'
                     + (f' stroke-dasharray="{DASH[0]} {DASH[1]}"' if hidden == "dashed" else ""))
            name = "hidden"
        lines = [f'<g id="{name}-edges" fill="none" stroke-linecap="round" {style}>']
        for x0, y0, x1, y1, _d0, _d1, r, g, b, _v, scale, strength in pieces:
            weight = "" if scale == 1.0 and strength == 1.0 else (
                f' stroke-width="{scale * (width if visible else HIDDEN_WIDTH * width):.3g}"'
                + (f' opacity="{strength:.3g}"' if strength != 1.0 else ""))
            lines.append(f'<path d="M{x0:.2f} {y0:.2f}L{x1:.2f} {y1:.2f}" stroke="{_hex((r, g, b))}"{weight}/>')
        lines.append("</g>")
        return lines

    if hidden != "none":
        out += layer(False)
    out += layer(True)
    arrows = (_ndtrace.axis_arrows(list(retina.shape), camera, given)
              if layout["axes"] is not None and camera is not None else None)
    drawing = annotate.items(layout, rows, arrows, keys, bg)
    if drawing:
        out.append('<g id="annotations">')
        out += annotate.svg_elements(drawing)
        out.append("</g>")
    out.append("</svg>")
    return "\n".join(out) + "\n"


def write_svg(path: str | os.PathLike, scene, *, fill: bool = True, threads: int | None = None,
              **options) -> None:
    """Writes a 4D (or higher) scene's hidden-line drawing as an SVG file.

    ``scene`` is an :class:`ndtrace.Scene` (traced here) or a :class:`ndtrace.Retina` traced from
    one. The drawing has the picture's size and framing: ``options`` are the keywords of
    :func:`ndtrace.composite` (the scene's ``[composite]`` table by default; ``mode``,
    ``layout`` and ``turntable`` do not apply), notably ``size``, ``azimuth``, ``elevation``,
    ``crease_angle``, ``hidden_edges`` (``"dashed"``, ``"faint"`` or ``"none"``), ``edge_width``,
    ``edge_color``, ``edge_color_by`` and ``depth_cue`` (stroke colour and width by N-D depth or
    direction, as the raster), ``title``, ``legend`` and ``axes`` (SVG text, a gradient and
    lines in the group ``annotations``). Each
    piece of an edge is one ``<path>``; the hidden pieces (group ``hidden-edges``) are drawn
    beneath the visible ones (group ``visible-edges``). ``fill`` embeds the raster composite
    without its edges beneath them (a PNG), which fills the object's silhouette; False gives a
    pure vector drawing over the background colour. The file is written atomically.
    """
    path = os.fspath(path)
    if not path.lower().endswith(".svg"):
        raise ValueError(f"{path}: expected a .svg path")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise OSError(f"{path}: cannot write: folder {folder} does not exist")
    text = svg_text(scene, fill=fill, threads=threads, **options)
    tmp = output_temp(path, ".svg")
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
        output_done(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
