"""What a picture says about itself: its caption, panel titles, colour bar and keys, and the
N-D axes glyph (``composite.title``, ``legend``, ``axes``; issue 48).

The core decides where each goes (``_ndtrace.picture_layout``: the caption band across the
top, the panels with their title bands, the legend strip across the bottom, the glyph's box
in the lower-left corner of the view) and where the glyph's arrows point
(``_ndtrace.axis_arrows``: the world axes through the N-D camera, the stages and the
compositing camera). This module says what goes there — :func:`legend_rows` reads the scene:
its colormaps and their ranges, isoline levels, ``color_by`` colours, object labels, the
directions of coloured edges — turns it into drawing items (:class:`Text`, :class:`Ramp`,
:class:`Box`, :class:`Line`) in picture pixels, and draws them: into a float picture at its
resolution (:func:`draw`; text anti-aliased with the DejaVu Sans subset shipped in
``ndtrace/fonts``, never a system font) or as SVG elements (:func:`svg_elements`).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from . import _ndtrace

__all__ = ["FONT", "Text", "Ramp", "Box", "Line", "Row", "legend_rows", "items", "draw",
           "svg_elements", "direction_label", "AXIS_COLORS"]

#: The font every label is drawn in: a subset of DejaVu Sans (Latin, Greek, the signs and
#: arrows the labels use), shipped with ndtrace under its licence (``fonts/LICENSE_DEJAVU``).
FONT: str = os.path.join(os.path.dirname(os.path.abspath(__file__)), "fonts", "DejaVuSans-subset.ttf")

#: The CSS font of SVG text: the same face where the viewer has it.
SVG_FONT = "'DejaVu Sans', Verdana, Arial, sans-serif"

#: The glyph's axis colours (linear RGB) on a dark background: x red, y green, z blue, w orange,
#: then x5 … x8; darkened on a light one.
AXIS_COLORS: tuple[tuple[float, float, float], ...] = (
    (0.90, 0.12, 0.10), (0.20, 0.65, 0.12), (0.15, 0.30, 0.95), (1.00, 0.45, 0.03),
    (0.55, 0.22, 0.95), (0.10, 0.70, 0.70), (0.80, 0.75, 0.10), (0.95, 0.25, 0.55),
)

#: Most legend rows (colour bars and keys) a picture gets.
MAX_ROWS = 3

#: The smallest glyph box drawn, pixels (a picture under about 180 px has no glyph).
MIN_GLYPH = 44


# -- drawing items ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Text:
    """A line of text: ``x`` at its left, centre or right (``anchor`` "l", "m", "r"), ``y`` its
    baseline, ``size`` the font size in pixels, linear RGB ``color``."""

    x: float
    y: float
    text: str
    size: float
    anchor: str = "l"
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    opacity: float = 1.0
    role: str = ""


@dataclass(frozen=True)
class Ramp:
    """A colour bar: ``colors`` (linear RGB, left to right) over the rectangle."""

    x: float
    y: float
    w: float
    h: float
    colors: tuple[tuple[float, float, float], ...]
    role: str = "colorbar"


@dataclass(frozen=True)
class Box:
    """A filled rectangle (a swatch)."""

    x: float
    y: float
    w: float
    h: float
    color: tuple[float, float, float]
    opacity: float = 1.0
    role: str = ""


@dataclass(frozen=True)
class Line:
    """A line segment ``width`` pixels wide, with an arrow head of ``head`` pixels at its end
    (0: none), dashed or solid."""

    x0: float
    y0: float
    x1: float
    y1: float
    width: float
    color: tuple[float, float, float]
    opacity: float = 1.0
    head: float = 0.0
    dashed: bool = False
    role: str = ""


Item = Text | Ramp | Box | Line


# -- what the legend says ------------------------------------------------------------------

@dataclass
class Row:
    """One row of the legend: a colour bar (``kind`` "ramp": ``colormap``, ``range``,
    ``isolines``) or a key (``kind`` "key": ``entries`` of (colour, label), drawn as swatches,
    or as line samples with ``lines``), with its ``title``."""

    kind: str
    title: str
    colormap: str = ""
    range: tuple[float, float] = (0.0, 1.0)
    isolines: tuple[float, ...] = ()
    isoline_color: tuple[float, float, float] = (0.0, 0.0, 0.0)
    entries: list[tuple[tuple[float, float, float], str]] = field(default_factory=list)
    lines: bool = False


def _axis(i: int) -> str:
    return "xyzw"[i] if i < 4 else f"x{i + 1}"


def direction_label(v, *, both: bool = False) -> str | None:
    """A direction in the course's axis names: ``"x"`` for ±e_1, ``"x+y−w"`` for a direction
    whose non-zero components have one magnitude, else None. ``both`` prefixes ``"±"`` (a pair
    of opposite cells)."""
    v = np.asarray(v, dtype=float)
    big = np.abs(v) > 1e-6 * max(float(np.abs(v).max()), 1e-300)
    if not big.any():
        return None
    mags = np.abs(v[big])
    if np.ptp(mags) > 1e-6 * mags.max():
        return None
    parts: list[str] = []
    for i in np.flatnonzero(big):
        sign = "−" if v[i] < 0 else "+"
        parts.append(("" if not parts and sign == "+" else sign) + _axis(int(i)))
    text = "".join(parts)
    return ("±" + (f"({text})" if len(parts) > 1 else text)) if both else text


def legend_rows(retina, options: dict) -> list[Row]:
    """The rows of the legend of ``retina`` composited with ``options`` (``legend``: "auto",
    True or False): a colour bar per colormap (name, range, isoline levels), a key of the cells'
    colours (``color_by = "cell"``), of the objects (their ``label`` or ``color_by =
    "object"``) and of the edges' directions (``edge_color_by = "direction"``); "auto" shows
    them when there is one. ``retina`` may be a raw array or a retina without its scene: then
    nothing is known and the legend is empty."""
    legend = options.get("legend", "auto")
    if legend is False:
        return []
    source = getattr(retina, "_source", None)
    if source is None:
        return []
    info = source.legend_info()
    rows: list[Row] = []
    # 1. A colour bar per colormap and range.
    maps = set()
    for o in info:
        cm = o["colormap"]
        if not cm:
            continue
        key = (cm["name"], tuple(cm["range"]), cm["of"])
        if key in maps:
            continue
        maps.add(key)
        iso = o["isolines"] or {}
        if cm["of"] == "depth":
            title = "N-D depth (distance from the eye)"
        else:
            title = o["label"] or "value"
        rows.append(Row("ramp", title, colormap=cm["name"], range=tuple(cm["range"]),
                        isolines=tuple(iso.get("values", ())) if cm["of"] == "values" else (),
                        isoline_color=tuple(iso.get("color", (0.0, 0.0, 0.0)))))
    # 2. The cells' colours: those of the cells the retina sees.
    for o in info:
        if not o["cells"]:
            continue
        seen: set[int] | None = None
        ids = getattr(retina, "primitive_id", None)
        if ids is not None and o.get("cell_class") is not None:
            mine = ids[retina.object_id == o["index"]]
            classes = np.asarray(o["cell_class"])
            seen = set(np.unique(classes[mine[(mine >= 0) & (mine < len(classes))]]).tolist())
        entries = []
        for k, c in enumerate(o["cells"]):
            if seen is not None and k not in seen:
                continue
            name = direction_label(c["normal"], both=c["count"] == 2)
            entries.append((tuple(c["color"]), name or f"{k + 1}"))
        count = sum(c["count"] for c in o["cells"])
        pairs = any(c["count"] > 1 for c in o["cells"])
        what = f"{o['label']}: " if o["label"] else ""
        rows.append(Row("key", f"{what}{count} cells" + (", opposite ones alike:" if pairs else ":"),
                        entries=entries))
    # 3. The objects: their labels (and colours by object).
    named = [o for o in info if o["label"] and not o["colormap"] and not o["cells"]]
    by_object = [o for o in info if o["color_by"] == "object"]
    keyed = {o["index"]: o for o in named + by_object}
    if keyed:
        entries = []
        for k in sorted(keyed):
            o = keyed[k]
            entry = (tuple(o["color"]), o["label"] or f"object {k}")
            if entry not in entries:
                entries.append(entry)
        rows.append(Row("key", "colour:" if named else "objects:", entries=entries))
    # 4. The edges' directions.
    edges_drawn = options.get("mode", "illustrative") == "illustrative" and options.get("edges", True)
    if edges_drawn and options.get("edge_color_by", "depth") == "direction":
        dirs = source.edge_directions(float(options.get("crease_angle", 20.0)))
        entries = [(tuple(d["color"]), direction_label(d["own"]) or f"{k + 1}") for k, d in enumerate(dirs)]
        if entries:
            rows.append(Row("key", "edges along:", entries=entries, lines=True))
    if legend is True and not rows and edges_drawn:
        rows.append(Row("key", "edges:", entries=[], lines=True))
    return rows[:MAX_ROWS]


# -- the items of a picture ------------------------------------------------------------------

def _srgb(c: float) -> float:
    c = min(max(float(c), 0.0), 1.0)
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


def _linear(c: float) -> float:
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def _luminance(rgb) -> float:
    return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]


def _ink(background) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """(text colour, faint colour) readable on ``background`` (linear RGB)."""
    if _luminance(background) < 0.18:
        return (0.92, 0.92, 0.90), (0.45, 0.45, 0.45)
    return (0.02, 0.02, 0.025), (0.30, 0.30, 0.30)


def _ticks(lo: float, hi: float, count: int = 5) -> list[float]:
    """About ``count`` round values between lo and hi (both ends included when round)."""
    a, b = min(lo, hi), max(lo, hi)
    span = b - a
    if not span > 0 or not math.isfinite(span):
        return [lo]
    raw = span / max(count - 1, 1)
    mag = 10 ** math.floor(math.log10(raw))
    step = min((s * mag for s in (1, 2, 2.5, 5, 10) if s * mag >= raw), default=10 * mag)
    first = math.ceil(a / step - 1e-9) * step
    ticks = []
    v = first
    while v <= b + step * 1e-9:
        ticks.append(0.0 if abs(v) < step * 1e-9 else v)
        v += step
    return ticks


def _number(v: float, step: float = 0.0) -> str:
    """A tick label: as many decimals as the ticks' step needs, a true minus sign."""
    if v != 0 and (abs(v) >= 1e5 or abs(v) < 1e-3):
        return f"{v:.2g}".replace("-", "−")
    decimals = 2
    if step > 0:
        decimals = next((d for d in range(5) if abs(round(step, d) - step) < 1e-9 * max(1.0, step)), 4)
    return f"{v:.{decimals}f}".replace("-", "−")


@lru_cache(maxsize=16)
def _font(size: int):
    from PIL import ImageFont

    try:
        return ImageFont.truetype(FONT, size)
    except OSError:  # Pillow without FreeType: its own bundled font
        return ImageFont.load_default(size)


def text_width(text: str, size: float) -> float:
    """The advance width of ``text`` at ``size`` pixels in :data:`FONT`."""
    return float(_font(max(1, round(size))).getlength(text))


def _rgb(c) -> tuple[float, float, float]:
    return (float(c[0]), float(c[1]), float(c[2]))


def _ramp_colors(name: str, samples: int = 64) -> tuple[tuple[float, float, float], ...]:
    table = np.asarray(_ndtrace.colormap_table(name))
    idx = np.linspace(0, len(table) - 1, samples)
    lo = np.floor(idx).astype(int)
    hi = np.minimum(lo + 1, len(table) - 1)
    f = (idx - lo)[:, None]
    out = table[lo] * (1 - f) + table[hi] * f
    return tuple(_rgb(c) for c in out)


def _row_items(row: Row, r: dict, u: float, ink, faint, background) -> list[Item]:
    """The items of one legend row in the rectangle ``r`` (dict x, y, w, h), text size u."""
    out: list[Item] = []
    x0, y0, w, h = r["x"], r["y"], r["w"], r["h"]
    pad = 0.8 * u
    small = 0.85 * u
    mid = y0 + h * 0.42
    title_w = min(text_width(row.title, small), 0.45 * w)
    if row.kind == "ramp":
        # The quantity and the map's name at the left, the ramp and its ticks to the right.
        title = row.title
        name = f"({row.colormap})"
        label_w = max(text_width(title, small), text_width(name, 0.8 * small))
        left = x0 + pad
        lo, hi = row.range
        ticks = _ticks(lo, hi, 5 if w > 24 * u else 3)
        step = abs(ticks[1] - ticks[0]) if len(ticks) > 1 else 0.0
        half = [0.5 * text_width(_number(v, step), small) for v in (lo, hi)]
        bar_x = left + min(label_w, 0.4 * w) + pad + half[0]
        bar_w = x0 + w - pad - half[1] - bar_x
        bar_h = 0.75 * u
        bar_y = y0 + 0.45 * u
        out.append(Text(left, bar_y + 0.5 * bar_h + 0.36 * small, _fit(title, small, 0.4 * w), small, "l", ink, role="legend-title"))
        out.append(Text(left, bar_y + 0.5 * bar_h + 0.36 * small + 1.05 * small, _fit(name, 0.8 * small, 0.4 * w), 0.8 * small, "l", faint, role="legend-name"))
        if bar_w < 4 * u:
            return out
        out.append(Ramp(bar_x, bar_y, bar_w, bar_h, _ramp_colors(row.colormap)))
        for v in ticks:
            t = (v - lo) / (hi - lo) if hi != lo else 0.0
            x = bar_x + t * bar_w
            out.append(Line(x, bar_y + bar_h, x, bar_y + bar_h + 0.3 * u, max(1.0, u / 12), ink, role="tick"))
            out.append(Text(x, bar_y + bar_h + 0.3 * u + small, _number(v, step), small, "m", ink, role="tick-label"))
        for v in row.isolines:
            t = (v - lo) / (hi - lo) if hi != lo else 0.0
            if 0 <= t <= 1:
                x = bar_x + t * bar_w
                out.append(Line(x, bar_y - 0.15 * u, x, bar_y + bar_h + 0.15 * u, max(1.5, u / 6), row.isoline_color, role="isoline"))
        return out
    # A key: its title, then swatches (or line samples) with their labels, in as many columns
    # as fit; labels too long for the row become numbers.
    left = x0 + pad
    out.append(Text(left, mid + 0.36 * small, row.title, small, "l", ink, role="legend-title"))
    start = left + title_w + pad
    room = x0 + w - pad - start
    sw = 1.1 * u
    gap = 0.9 * u
    if not row.entries and row.lines:
        # The depth cue of the edges: near thick and strong, far thin and faint.
        for k, (label, width, op) in enumerate((("near", 0.28 * u, 1.0), ("far", 0.1 * u, 0.4))):
            x = start + k * (3 * sw + 4 * u)
            out.append(Line(x, mid, x + 2 * sw, mid, max(1.0, width), ink, opacity=op, role="swatch"))
            out.append(Text(x + 2 * sw + 0.4 * u, mid + 0.36 * small, label, small, "l", ink, role="key-label"))
        return out
    labels = [label for _, label in row.entries]
    widths = [text_width(label, small) for label in labels]
    need = sum(sw + 0.35 * u + lw + gap for lw in widths)
    if need > room:
        labels = [str(k + 1) for k in range(len(labels))]
        widths = [text_width(label, small) for label in labels]
        need = sum(sw + 0.35 * u + lw + gap for lw in widths)
    x = start
    spread: float | None = None
    if need > room:  # still too many: swatches only, evenly spread
        spread = room / max(len(labels), 1)
    for (color, _), label, lw in zip(row.entries, labels, widths):
        if row.lines:
            out.append(Line(x, mid, x + sw, mid, max(1.5, 0.22 * u), _rgb(color), role="swatch"))
        else:
            out.append(Box(x, mid - 0.5 * sw, sw, sw, _rgb(color), role="swatch"))
        if spread is None:
            out.append(Text(x + sw + 0.35 * u, mid + 0.36 * small, label, small, "l", ink, role="key-label"))
            x += sw + 0.35 * u + lw + gap
        else:
            x += spread
    return out


def _fit(text: str, size: float, width: float) -> str:
    """``text``, shortened with an ellipsis to fit ``width`` pixels."""
    if text_width(text, size) <= width:
        return text
    while len(text) > 1 and text_width(text + "…", size) > width:
        text = text[:-1]
    return text.rstrip() + "…"


def _glyph_items(box: dict, arrows: list[dict], u: float, background) -> list[Item]:
    """The axes glyph in ``box``: an arrow per axis from the box's centre toward its tip,
    labelled, dimmed (and dashed) as it points away from the N-D eye; an axis along a line of
    sight (shorter than a fifth) is a label marked ⊙ (toward the eye) or ⊗ (away), put where no
    arrow goes. Every item lies inside the box."""
    out: list[Item] = []
    side = float(min(box["w"], box["h"]))
    cx, cy = box["x"] + side / 2, box["y"] + side / 2
    size = max(8.0, min(0.85 * u, side / 6))
    reach = side / 2 - 0.75 * size  # the labels' centres stay this far from the centre
    length = reach - 0.55 * size
    dark = _luminance(background) < 0.18
    out.append(Box(cx - 0.06 * size, cy - 0.06 * size, 0.12 * size, 0.12 * size, _ink(background)[1], role="axes"))
    shown = [math.atan2(a["tip"][1], a["tip"][0]) for a in arrows if math.hypot(*a["tip"]) >= 0.2]
    taken: list[float] = []

    def free_direction() -> float:
        """The compass direction farthest from every arrow and label placed so far."""
        def gap(t: float) -> float:
            return min((abs((t - s + math.pi) % (2 * math.pi) - math.pi) for s in shown + taken), default=math.pi)
        return max((k * math.pi / 4 for k in range(8)), key=gap)

    # Farthest from the eye first, so the nearer arrows are drawn over them.
    for k in sorted(range(len(arrows)), key=lambda k: arrows[k]["toward"]):
        a = arrows[k]
        tx, ty = a["tip"]
        color = AXIS_COLORS[k % len(AXIS_COLORS)]
        if not dark:
            color = (0.55 * color[0], 0.55 * color[1], 0.55 * color[2])
        strength = 0.35 + 0.65 * (1 + a["toward"]) / 2
        away = a["toward"] < -0.05
        short = math.hypot(tx, ty)
        width = max(1.2, side / 45) * (0.7 if away else 1.0)
        label = a["label"]
        if short >= 0.2:
            x1, y1 = cx + length * tx, cy + length * ty
            out.append(Line(cx, cy, x1, y1, width, color, opacity=strength,
                            head=min(0.45 * size, 0.5 * short * length), dashed=away, role="axes"))
            # The label just beyond the tip.
            # (a glyph is taller than wide: more room above and below the tip)
            r = length * short + (0.55 + 0.3 * abs(ty) / short) * size
            lx, ly = cx + r * tx / short, cy + r * ty / short
        else:
            if short * length > 0.5:
                out.append(Line(cx, cy, cx + length * tx, cy + length * ty, width, color, opacity=strength,
                                dashed=away, role="axes"))
            t = free_direction()
            taken.append(t)
            label = ("⊗" if away else "⊙") + label
            lx, ly = cx + 0.55 * reach * math.cos(t), cy + 0.55 * reach * math.sin(t)
        lx = min(max(lx, box["x"] + 0.8 * size), box["x"] + side - 0.8 * size)
        ly = min(max(ly, box["y"] + 0.6 * size), box["y"] + side - 0.6 * size)
        out.append(Text(lx, ly + 0.36 * size, label, size, "m", color, opacity=max(strength, 0.5), role="axes-label"))
    return out


def items(layout: dict, rows: list[Row], arrows: list[dict] | None, options: dict,
          background) -> list[Item]:
    """Every drawing item of a picture: the caption, the panel titles, the legend rows and the
    axes glyph, in the places of ``layout`` (``_ndtrace.picture_layout``)."""
    u = float(layout["text"])
    ink, faint = _ink(background)
    out: list[Item] = []
    cap = layout["caption"]
    title = options.get("title")
    if cap and title:
        size = 1.15 * u
        out.append(Text(cap["x"] + cap["w"] / 2, cap["y"] + cap["h"] / 2 + 0.36 * size,
                        _fit(str(title), size, cap["w"] - 2 * u), size, "m", ink, role="caption"))
    for p in layout["panels"]:
        band = p["title_band"]
        if band and p["title"]:
            out.append(Text(band["x"] + band["w"] / 2, band["y"] + band["h"] / 2 + 0.36 * u,
                            _fit(p["title"], u, band["w"] - u), u, "m", ink, role="panel-title"))
    strip = layout["legend"]
    if strip and rows:
        hr = strip["h"] / len(rows)
        for k, row in enumerate(rows):
            r = {"x": strip["x"], "y": strip["y"] + k * hr, "w": strip["w"], "h": hr}
            out += _row_items(row, r, u, ink, faint, background)
    box = layout["axes"]
    if box and arrows and min(box["w"], box["h"]) >= MIN_GLYPH:
        out += _glyph_items(box, arrows, u, background)
    return out


# -- raster ------------------------------------------------------------------------------------

_SS = 4  # supersampling of lines


def _blend(picture: np.ndarray, x0: int, y0: int, cover: np.ndarray, color, opacity: float) -> None:
    """Blends ``color`` over ``picture`` (linear RGBA, RGB over the background) where
    ``cover`` (coverage in [0, 1], its top-left at (x0, y0)) is, in sRGB as text is
    rasterized for; alpha gains the coverage."""
    h, w = picture.shape[:2]
    ch, cw = cover.shape
    xa, ya, xb, yb = max(x0, 0), max(y0, 0), min(x0 + cw, w), min(y0 + ch, h)
    if xa >= xb or ya >= yb:
        return
    a = (cover[ya - y0:yb - y0, xa - x0:xb - x0] * opacity).astype(np.float32)
    region = picture[ya:yb, xa:xb]
    ink = a > 0  # the pixels the item covers; the others are left to the bit
    if not ink.any():
        return
    px, a = region[ink], a[ink][:, None]
    rgb = np.clip(px[:, :3], 0.0, 1.0)
    srgb = np.where(rgb <= 0.0031308, 12.92 * rgb, 1.055 * np.power(rgb, 1 / 2.4) - 0.055)
    target = np.array([_srgb(c) for c in color], dtype=np.float32)
    mixed = srgb + (target - srgb) * a
    px[:, :3] = np.where(mixed <= 0.04045, mixed / 12.92, np.power((mixed + 0.055) / 1.055, 2.4))
    px[:, 3:4] = px[:, 3:4] + (1.0 - px[:, 3:4]) * a
    region[ink] = px


def _text_mask(item: Text) -> tuple[int, int, np.ndarray]:
    from PIL import Image, ImageDraw

    font = _font(max(1, round(item.size)))
    anchor = {"l": "ls", "m": "ms", "r": "rs"}[item.anchor]
    left, top, right, bottom = font.getbbox(item.text, anchor=anchor)
    x, y = round(item.x), round(item.y)
    w, h = max(1, right - left + 2), max(1, bottom - top + 2)
    img = Image.new("L", (w, h), 0)
    ImageDraw.Draw(img).text((1 - left, 1 - top), item.text, fill=255, font=font, anchor=anchor)
    return x + left - 1, y + top - 1, np.asarray(img, dtype=np.float32) / 255.0


def _line_mask(item: Line) -> tuple[int, int, np.ndarray]:
    from PIL import Image, ImageDraw

    pad = max(item.width, 1.0) + max(item.head, 0.0) + 2
    x0, y0 = math.floor(min(item.x0, item.x1) - pad), math.floor(min(item.y0, item.y1) - pad)
    x1, y1 = math.ceil(max(item.x0, item.x1) + pad), math.ceil(max(item.y0, item.y1) + pad)
    w, h = x1 - x0, y1 - y0
    img = Image.new("L", (w * _SS, h * _SS), 0)
    d = ImageDraw.Draw(img)
    p = ((item.x0 - x0) * _SS, (item.y0 - y0) * _SS)
    q = ((item.x1 - x0) * _SS, (item.y1 - y0) * _SS)
    length = math.hypot(q[0] - p[0], q[1] - p[1])
    ux, uy = ((q[0] - p[0]) / length, (q[1] - p[1]) / length) if length > 0 else (1.0, 0.0)
    head = item.head * _SS
    end = (q[0] - ux * head * 0.8, q[1] - uy * head * 0.8) if head else q
    lw = max(1, round(item.width * _SS))
    if item.dashed:
        dash, gap = 3.0 * item.width * _SS, 2.2 * item.width * _SS
        s = 0.0
        total = math.hypot(end[0] - p[0], end[1] - p[1])
        while s < total:
            e = min(s + dash, total)
            d.line([(p[0] + ux * s, p[1] + uy * s), (p[0] + ux * e, p[1] + uy * e)], fill=255, width=lw)
            s = e + gap
    else:
        d.line([p, end], fill=255, width=lw)
    if head:
        nx, ny = -uy, ux
        d.polygon([q, (q[0] - ux * head + nx * head * 0.45, q[1] - uy * head + ny * head * 0.45),
                   (q[0] - ux * head - nx * head * 0.45, q[1] - uy * head - ny * head * 0.45)], fill=255)
    small = img.resize((w, h), Image.Resampling.BOX)
    return x0, y0, np.asarray(small, dtype=np.float32) / 255.0


def draw(picture: np.ndarray, drawing: list[Item]) -> np.ndarray:
    """Draws the items into ``picture`` (float32 linear RGBA ``(H, W, 4)``, changed in place
    and returned): boxes and colour bars exactly, lines supersampled 4×, text anti-aliased at
    the picture's resolution."""
    h, w = picture.shape[:2]
    for item in drawing:
        if isinstance(item, Ramp):
            xa, xb = max(0, round(item.x)), min(w, round(item.x + item.w))
            ya, yb = max(0, round(item.y)), min(h, round(item.y + item.h))
            if xa >= xb or ya >= yb:
                continue
            colors = np.asarray(item.colors, dtype=np.float32)
            t = (np.arange(xa, xb) + 0.5 - item.x) / item.w * (len(colors) - 1)
            t = np.clip(t, 0, len(colors) - 1)
            lo = np.floor(t).astype(int)
            hi = np.minimum(lo + 1, len(colors) - 1)
            f = (t - lo)[:, None]
            row = colors[lo] * (1 - f) + colors[hi] * f
            picture[ya:yb, xa:xb, :3] = row[None]
            picture[ya:yb, xa:xb, 3] = 1.0
        elif isinstance(item, Box):
            xa, xb = max(0, round(item.x)), min(w, round(item.x + item.w))
            ya, yb = max(0, round(item.y)), min(h, round(item.y + item.h))
            if xa < xb and ya < yb:
                _blend(picture, xa, ya, np.ones((yb - ya, xb - xa), np.float32), item.color, item.opacity)
        elif isinstance(item, Line):
            x0, y0, mask = _line_mask(item)
            _blend(picture, x0, y0, mask, item.color, item.opacity)
        elif isinstance(item, Text):
            if item.text:
                x0, y0, mask = _text_mask(item)
                _blend(picture, x0, y0, mask, item.color, item.opacity)
    return picture


# -- SVG --------------------------------------------------------------------------------------

def _hex(rgb) -> str:
    return "#" + "".join(f"{round(_srgb(c) * 255):02x}" for c in rgb)


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


def svg_elements(drawing: list[Item]) -> list[str]:
    """The items as SVG elements (one group per role), in picture pixels."""
    out: list[str] = []
    defs: list[str] = []
    for k, item in enumerate(drawing):
        role = f' class="{item.role}"' if item.role else ""
        if isinstance(item, Ramp):
            gid = f"ramp{k}"
            stops = "".join(
                f'<stop offset="{i / (len(item.colors) - 1):.4f}" stop-color="{_hex(c)}"/>'
                for i, c in enumerate(item.colors))
            defs.append(f'<linearGradient id="{gid}" x1="0" x2="1" y1="0" y2="0">{stops}</linearGradient>')
            out.append(f'<rect{role} x="{item.x:.2f}" y="{item.y:.2f}" width="{item.w:.2f}" height="{item.h:.2f}" fill="url(#{gid})"/>')
        elif isinstance(item, Box):
            out.append(f'<rect{role} x="{item.x:.2f}" y="{item.y:.2f}" width="{item.w:.2f}" height="{item.h:.2f}" '
                       f'fill="{_hex(item.color)}" fill-opacity="{item.opacity:.3g}"/>')
        elif isinstance(item, Line):
            dash = f' stroke-dasharray="{3 * item.width:.2f} {2.2 * item.width:.2f}"' if item.dashed else ""
            x1, y1 = item.x1, item.y1
            length = math.hypot(x1 - item.x0, y1 - item.y0)
            if item.head and length > 0:
                ux, uy = (x1 - item.x0) / length, (y1 - item.y0) / length
                x1, y1 = item.x1 - ux * item.head * 0.8, item.y1 - uy * item.head * 0.8
            out.append(f'<line{role} x1="{item.x0:.2f}" y1="{item.y0:.2f}" x2="{x1:.2f}" y2="{y1:.2f}" '
                       f'stroke="{_hex(item.color)}" stroke-opacity="{item.opacity:.3g}" '
                       f'stroke-width="{item.width:.2f}" stroke-linecap="butt"{dash}/>')
            if item.head and length > 0:
                nx, ny = -uy, ux
                h = item.head
                pts = [(item.x1, item.y1), (item.x1 - ux * h + nx * h * 0.45, item.y1 - uy * h + ny * h * 0.45),
                       (item.x1 - ux * h - nx * h * 0.45, item.y1 - uy * h - ny * h * 0.45)]
                out.append(f'<polygon{role} points="' + " ".join(f"{x:.2f},{y:.2f}" for x, y in pts)
                           + f'" fill="{_hex(item.color)}" fill-opacity="{item.opacity:.3g}"/>')
        elif isinstance(item, Text):
            anchor = {"l": "start", "m": "middle", "r": "end"}[item.anchor]
            out.append(f'<text{role} x="{item.x:.2f}" y="{item.y:.2f}" font-size="{item.size:.2f}" '
                       f'font-family="{SVG_FONT}" text-anchor="{anchor}" fill="{_hex(item.color)}" '
                       f'fill-opacity="{item.opacity:.3g}">{_escape(item.text)}</text>')
    if defs:
        out.insert(0, "<defs>" + "".join(defs) + "</defs>")
    return out
