"""A view of a scene: the state the page controls (the object rotation, the composite
options) and the frames it asks for.

One :class:`ViewSession` serves one page (or one notebook widget). Its messages are small
JSON objects (see ``static/viewer.js``); :meth:`ViewSession.handle` applies one and returns the
reply, and :meth:`ViewSession.render` makes a frame of a snapshot. The rotation is applied to
the scene's objects as a ``{ matrix = … }`` transform step (after their own steps, about the
camera's ``look_at`` point), so lights stay where the scene put them and the shading changes as
the object turns, and "copy TOML" gives a scene file of the current view.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import io
import json
import math
import re
import time
import tomllib
from collections.abc import Callable
from typing import Any

import numpy as np

from .._ndtrace import check_picture_memory
from .._util import check_memory
from ..composite import composite, picture_size, scene_options
from ..display import camera_resolution, reduced_resolution
from ..files import to_srgb8
from ..retina import Retina, trace
from ..scene import Scene, load_dict, slice_scene
from ..slicing import at_size, slice_options
from . import controls
from .worker import DRAFT, FULL, Superseded

__all__ = ["ViewSession", "Snapshot", "composite_modes", "display_aids", "parse_message", "nesting",
           "BASE_KEYWORDS", "DRAFT_CELLS", "DRAFT_SCALE", "DRAFT_STEP", "MAX_MESSAGE_BYTES",
           "MAX_NESTING", "UNSETTABLE"]

#: Retina cells of a draft frame (traced while the mouse moves): 32³ for a 4D scene.
DRAFT_CELLS: int = 32 ** 3

#: The draft picture's size over the full picture's: 192×192 for 512×512, drawn scaled up while
#: the mouse moves (the composite's cost goes with its pixels: this is most of a draft's time).
DRAFT_SCALE: float = 0.375

#: The volume marching step (in cells) of a draft frame at least: one sample per cell.
DRAFT_STEP: float = 1.0

#: The keywords of ``ndtrace.composite`` that the page has its own controls for (or sets
#: itself); every other keyword is a display aid with a generic control.
BASE_KEYWORDS = frozenset({
    "retina", "mode", "azimuth", "elevation", "distance", "projection", "size", "opacity",
    "depth_cue", "axis", "background", "zoom", "step", "stages", "strip_height", "labels",
    "threads", "axes_frame",
})

_ZOOM_RANGE = (0.05, 50.0)

#: The longest message a page may send (UTF-8 bytes): its messages are a few hundred bytes, a
#: drag's batch of mouse steps a few kilobytes.
MAX_MESSAGE_BYTES: int = 1 << 16

#: The deepest nesting of lists and objects in a message, and of a TOML value in ``set`` (a
#: rotation matrix is two levels inside the message, a cutaway's centre three).
MAX_NESTING: int = 16

#: The keywords of ``ndtrace.composite`` that ``set`` refuses: what the server decides (the
#: picture's size, the threads), what is not one picture (a turntable's frames), the retina.
UNSETTABLE = frozenset({"retina", "threads", "size", "turntable"})

_JSON_STRING = re.compile(r'"(?:[^"\\]|\\.)*"')
_TOML_STRING = re.compile(r'"(?:[^"\\\n]|\\.)*"|\'[^\'\n]*\'')


def nesting(text: str, strings: re.Pattern = _JSON_STRING) -> int:
    """The deepest nesting of brackets (``[`` and ``{``) in JSON or TOML ``text``, not counting
    those inside strings: checked before a parser that recurses sees the text."""
    bare = strings.sub('""', text).encode("utf-8", "replace")
    codes = np.frombuffer(bare, dtype=np.uint8)
    if not len(codes):
        return 0
    step = (np.isin(codes, (0x5B, 0x7B)).astype(np.int32)
            - np.isin(codes, (0x5D, 0x7D)).astype(np.int32))
    return int(max(0, np.cumsum(step).max()))


def _depth_exceeds(value: Any, limit: int) -> bool:
    """Whether ``value`` (JSON data: dicts, lists, scalars) nests deeper than ``limit``."""
    stack = [(value, 0)]
    while stack:
        v, d = stack.pop()
        if isinstance(v, dict):
            v = list(v.values())
        if isinstance(v, list):
            if d + 1 > limit:
                return True
            stack.extend((x, d + 1) for x in v)
    return False


def _refuse_constant(name: str) -> float:
    raise ValueError(f"message: {name} is not a JSON number")


def parse_message(text: str | bytes) -> dict:
    """A page's message, checked before it is parsed: at most :data:`MAX_MESSAGE_BYTES` bytes,
    lists and objects nested at most :data:`MAX_NESTING` deep, valid JSON (without NaN or
    Infinity), an object. Anything else is a ValueError saying what is wrong."""
    size = len(text.encode("utf-8", "replace") if isinstance(text, str) else text)
    if size > MAX_MESSAGE_BYTES:
        raise ValueError(f"message: {size} bytes, more than the {MAX_MESSAGE_BYTES} allowed")
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError:
            raise ValueError("message: not UTF-8 text") from None
    if nesting(text) > MAX_NESTING:
        raise ValueError(f"message: nested more than {MAX_NESTING} levels deep")
    try:
        data = json.loads(text, parse_constant=_refuse_constant)
    except RecursionError:
        raise ValueError(f"message: nested more than {MAX_NESTING} levels deep") from None
    except ValueError as e:  # json.JSONDecodeError is a ValueError
        raise ValueError(f"message: not JSON: {e}") from None
    if not isinstance(data, dict):
        raise ValueError("message: expected an object with a 'type'")
    return data

# The module, not the function ``ndtrace.composite`` that the package's attribute names.
_composite_module = importlib.import_module("ndtrace.composite")


def composite_modes() -> tuple[str, ...]:
    """The composite modes this ndtrace offers (``ndtrace.composite.MODES``)."""
    return tuple(getattr(_composite_module, "MODES", ()))


def _parameters() -> dict[str, inspect.Parameter]:
    return dict(inspect.signature(composite).parameters)


def display_aids() -> list[dict]:
    """Controls for the keywords of ``ndtrace.composite`` beyond :data:`BASE_KEYWORDS` (the
    sections, cutaways and other display aids of this ndtrace, found by inspecting the
    function's signature): one dict per keyword with its ``name``, ``kind`` (``"bool"``,
    ``"number"``, ``"choice"`` with ``choices`` from the module's tuple named after the keyword,
    e.g. ``LAYOUTS`` for ``layout`` — strings, or strings and booleans as ``LEGEND`` = ("auto",
    True, False) —, ``"string"`` for a keyword of ``str | None`` (plain text, empty for None)
    or ``"text"``: a TOML value, empty for the default), ``default`` and ``hint`` (the
    annotation)."""
    out = []
    for name, p in _parameters().items():
        if name in BASE_KEYWORDS or p.kind not in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD):
            continue
        default = None if p.default is inspect.Parameter.empty else p.default
        hint = p.annotation if isinstance(p.annotation, str) else getattr(p.annotation, "__name__", "")
        aid: dict[str, Any] = {"name": name, "default": default, "hint": str(hint)}
        if isinstance(default, bool):
            aid["kind"] = "bool"
        elif isinstance(default, (int, float)):
            aid["kind"] = "number"
        elif isinstance(default, str):
            # The choices: a tuple of strings (or strings and booleans) in the module named
            # after the keyword (``layout`` → ``LAYOUTS``), as ``mode`` has ``MODES``.
            named = [getattr(_composite_module, k, None) for k in (name.upper() + "S", name.upper() + "ES", name.upper())]
            choices = [c for c in named if isinstance(c, tuple) and default in c and all(isinstance(v, (str, bool)) for v in c)]
            aid.update(kind="choice", choices=list(choices[0])) if choices else aid.update(kind="text")
        elif default is None and str(hint).replace(" ", "") in ("str|None", "Optional[str]"):
            aid["kind"] = "string"
        else:
            aid["kind"] = "text"
            aid["default"] = _jsonable(default)
        out.append(aid)
    return out


def _jsonable(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    return repr(value)


def _numbers(objects: Any) -> int:
    """About how many numbers the arrays of a description's objects hold (numpy arrays by
    their size, lists of rows by rows × the first row's length)."""
    count = 0
    for o in objects if isinstance(objects, list) else []:
        for v in (o.values() if isinstance(o, dict) else []):
            if isinstance(v, np.ndarray):
                count += v.size
            elif isinstance(v, list) and v:
                first = v[0]
                count += len(v) * (len(first) if isinstance(first, list) else 1)
    return count


def camera_shape(resolution: list[int]) -> list[int]:
    """The numpy shape of a retina of ``resolution`` (retina axes u_1 … u_{N−1}): reversed."""
    return list(reversed([int(r) for r in resolution]))


@dataclasses.dataclass(frozen=True)
class Snapshot:
    """What a frame shows: the object rotation and the composite options, frozen at an input."""

    seq: int
    rotation: np.ndarray
    options: dict
    slice: float | None = None


def draft_resolution(resolution: list[int], cells: int = DRAFT_CELLS) -> list[int]:
    """The retina resolution of a draft: every axis scaled by the same factor so that about
    ``cells`` cells remain (never more than the full frame's), at least 2 per axis."""
    return reduced_resolution(resolution, cells)


class ViewSession:
    """The view state of one page: see the module doc.

    ``size`` is the picture (W, H) in pixels (default: the scene's ``[composite]`` size, else
    512×512); drafts trace about ``draft_cells`` retina cells and composite at ``draft_scale``
    of the picture's size; ``threads`` as for :func:`ndtrace.trace`. The rotation turns the
    objects about the camera's ``look_at`` point (the origin for a camera given by its
    ``orientation``). Bad arguments raise ValueError naming them.
    """

    def __init__(self, scene: Scene, *, size: tuple[int, int] | None = None,
                 draft_cells: int = DRAFT_CELLS, draft_scale: float = DRAFT_SCALE,
                 threads: int | None = None, name: str | None = None) -> None:
        if not isinstance(scene, Scene):
            raise TypeError(f"scene: expected an ndtrace.Scene, got {type(scene).__name__}")
        for arg, value, low in (("draft_cells", draft_cells, 1), ("threads", threads, 1)):
            if value is not None and (isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < low):
                raise ValueError(f"{arg}: expected an integer ≥ {low}, got {value!r}")
        if not 0 < draft_scale <= 1:
            raise ValueError(f"draft_scale: expected a number in (0, 1], got {draft_scale!r}")
        if size is not None:
            try:
                w, h = (int(v) for v in size)
            except (TypeError, ValueError):
                raise ValueError(f"size: expected (width, height) in pixels, got {size!r}") from None
            if w < 1 or h < 1:
                raise ValueError(f"size: width and height must be at least 1, got {size!r}")
        self.scene = scene
        self.name = name or "scene"
        desc = scene.to_dict()
        desc.pop("animation", None)
        self._desc = desc
        self.dim = int(desc["dim"])
        camera = desc["camera"]
        self.center = np.asarray(camera.get("look_at") or [0.0] * self.dim, dtype=float)
        self.resolution = camera_resolution(camera, self.dim)
        self.draft = draft_resolution(self.resolution, draft_cells)
        self.draft_scale = float(draft_scale)
        self.threads = threads
        initial = scene_options(desc)
        initial.pop("turntable", None)  # a view is one picture
        shape = list(reversed(self.resolution))
        picture = size or initial.get("size") or picture_size(shape, initial)
        self.size = (int(picture[0]), int(picture[1]))
        initial["size"] = list(self.size)
        # The full frame's picture, checked by the memory guard before the server starts.
        check_picture_memory(list(camera_shape(self.resolution)), {
            k: v for k, v in _jsonable(initial).items() if k in ("size", "mode")})
        self.initial_options = initial
        self.options = dict(initial)
        self.rotation = np.eye(self.dim)
        # Slice mode: the offset of the hyperplane x_{N−1} = offset the page shows the scene's
        # slice by (None: off). The rolling ball turns the objects through it, i.e. turns the
        # hyperplane by the inverse rotation in the objects' frame.
        self.slice: float | None = None
        self.slice_normal = [0.0] * (self.dim - 1) + [1.0]
        self.seq = 0
        self._arcball: tuple[np.ndarray, np.ndarray, bool] | None = None
        self._retina: tuple[bytes, str, Retina] | None = None  # the last traced retina
        self.modes = composite_modes()
        self.aids = display_aids() if self.dim >= 4 else []
        params = _parameters()
        default = params["mode"].default if "mode" in params else None
        self._mode_default = default if isinstance(default, str) else None

    # -- what the page is told -----------------------------------------------------------
    def hello(self) -> dict:
        """The first message: what the page needs to build its controls."""
        return {
            **self.state(), "type": "hello", "scene": self.name, "dim": self.dim, "picture": list(self.size),
            "radius": self.radius, "modes": list(self.modes) if self.dim >= 4 else [],
            "mode_default": self._mode_default, "aids": self.aids,
            "arcball": self.dim == 4, "orbit": self.dim >= 4, "slices": self.dim >= 4,
            "resolution": self.resolution, "draft": self.draft,
        }

    @property
    def radius(self) -> float:
        """The rolling ball's radius in picture pixels: half the picture's shorter side, so a
        drag across half the picture turns by atan(1) = 45°."""
        return min(self.size) / 2.0

    def state(self) -> dict:
        return {"type": "state", "seq": self.seq, "rotation": self.rotation.tolist(),
                "options": _jsonable(self.options), "slice": self.slice}

    def snapshot(self) -> Snapshot:
        return Snapshot(self.seq, self.rotation.copy(), dict(self.options), self.slice)

    # -- inputs --------------------------------------------------------------------------
    def handle(self, msg: dict) -> tuple[dict | None, str | None]:
        """Applies one message from the page. Returns (reply, frame) where frame is
        ``"draft"`` (a new view: a draft now, the full frame at rest), ``"now"`` (a new view:
        a draft, then the full frame at once), ``"release"`` (the interaction ended: the full
        frame now) or None. A bad message raises ValueError (the page shows it; the state is unchanged)."""
        if not isinstance(msg, dict) or not isinstance(msg.get("type"), str):
            raise ValueError("message: expected an object with a 'type'")
        if _depth_exceeds(msg, MAX_NESTING):
            raise ValueError(f"message: nested more than {MAX_NESTING} levels deep")
        kind = msg["type"]
        seq = msg.get("seq")
        if seq is not None:
            if isinstance(seq, bool) or not isinstance(seq, int):
                raise ValueError(f"seq: expected an integer, got {seq!r}")
        handler = getattr(self, "_on_" + kind, None)
        if handler is None:
            raise ValueError(f"message type {kind!r}: unknown")
        frame = handler(msg)
        if seq is not None:
            self.seq = seq
        if kind == "toml":
            return {"type": "toml", "seq": self.seq, "text": self.view_toml()}, None
        if kind == "hello":
            return self.hello(), "draft"
        return self.state(), frame

    def _number(self, msg: dict, key: str) -> float:
        v = msg.get(key)
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ValueError(f"{msg['type']}.{key}: expected a finite number, got {v!r}")
        return float(v)

    def _on_hello(self, msg: dict) -> str:
        return "draft"

    def _on_roll(self, msg: dict) -> str | None:
        steps = msg.get("steps")
        if not isinstance(steps, list) or not all(
                isinstance(s, list) and len(s) == 2 and all(
                    isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in s)
                for s in steps):
            raise ValueError("roll.steps: expected a list of [dx, dy] pairs of finite numbers")
        if not steps:
            return None
        self.rotation = controls.roll(self.rotation, steps, self.radius)
        return "draft"

    def _on_arcball(self, msg: dict) -> str | None:
        if self.dim != 4:
            raise ValueError(f"arcball: the 4D arcball needs a 4D scene, this one is {self.dim}D")
        point = controls.arcball_point(self._number(msg, "x"), self._number(msg, "y"), *self.size)
        if msg.get("phase") == "press":
            self._arcball = (self.rotation.copy(), point, bool(msg.get("right")))
            return None
        if self._arcball is None:
            raise ValueError("arcball: a drag must start with phase 'press'")
        press_rotation, a0, right = self._arcball
        self.rotation = controls.arcball(press_rotation, a0, point, right)
        return "draft"

    def _on_orbit(self, msg: dict) -> str:
        az, el = controls.orbit(float(self.options.get("azimuth", 30.0)),
                                float(self.options.get("elevation", 20.0)),
                                self._number(msg, "dx"), self._number(msg, "dy"))
        self.options["azimuth"], self.options["elevation"] = az, el
        return "draft"

    def _on_zoom(self, msg: dict) -> str:
        factor = self._number(msg, "factor")
        if factor <= 0:
            raise ValueError(f"zoom.factor: must be > 0, got {factor}")
        zoom = float(self.options.get("zoom", 1.0)) * factor
        self.options["zoom"] = min(_ZOOM_RANGE[1], max(_ZOOM_RANGE[0], zoom))
        return "draft"

    def _on_view(self, msg: dict) -> str:
        self.options["azimuth"] = self._number(msg, "azimuth")
        self.options["elevation"] = self._number(msg, "elevation")
        return "now"

    def _on_set(self, msg: dict) -> str:
        given = msg.get("options")
        if not isinstance(given, dict):
            raise ValueError("set.options: expected an object of composite keywords")
        options = dict(self.options)
        kinds = {a["name"]: a["kind"] for a in self.aids}
        params = _parameters()
        for key, value in given.items():
            if key not in params or key in UNSETTABLE:
                raise ValueError(f"set.options.{key}: not a keyword of ndtrace.composite the page can set")
            if kinds.get(key) == "text" and isinstance(value, str):
                text = value.strip()
                if not text:
                    options.pop(key, None)
                    continue
                if nesting(text, _TOML_STRING) > MAX_NESTING:
                    raise ValueError(f"{key}: nested more than {MAX_NESTING} levels deep")
                try:
                    value = tomllib.loads(f"v = {text}")["v"]
                except tomllib.TOMLDecodeError as e:
                    raise ValueError(f"{key}: expected a TOML value, e.g. [0, 0, 1] or {{ a = 1 }}: {e}") from None
                except RecursionError:
                    raise ValueError(f"{key}: nested more than {MAX_NESTING} levels deep") from None
                if _depth_exceeds(value, MAX_NESTING):
                    raise ValueError(f"{key}: nested more than {MAX_NESTING} levels deep")
            if value is None:
                options.pop(key, None)
            else:
                options[key] = value
        self._check_options(options)
        self.options = options
        return "draft"

    def _check_options(self, options: dict) -> None:
        """Raises the composite's own ValueError for options it refuses (on a tiny retina of
        this scene's dimension: the same checks for every dimension), and the memory guard's
        for a picture that would not fit."""
        shape = (2,) * (self.dim - 1)
        probe = Retina(dim=self.dim, rgba=np.zeros(shape + (4,), np.float32),
                       depth=np.full(shape, np.inf, np.float32),
                       normal=np.zeros(shape + (self.dim,), np.float32),
                       object_id=np.full(shape, -1, np.int32), primitive_id=np.full(shape, -1, np.int64))
        composite(probe, **dict(options, size=(2, 2)))
        for key, value in options.items():
            if isinstance(value, float) and not math.isfinite(value):  # a reply must be JSON
                raise ValueError(f"{key}: must be finite, got {value}")

    def _on_slice(self, msg: dict) -> str:
        """``{"type": "slice", "on": bool, "offset": number}``: slice mode on at that offset of
        the hyperplane x_{N−1} = offset (the last axis), or off."""
        if self.dim < 4:
            raise ValueError(f"slice: slice mode needs dim ≥ 4 (a 3D slice or more), got {self.dim}")
        on = msg.get("on", True)
        if not isinstance(on, bool):
            raise ValueError(f"slice.on: expected true or false, got {on!r}")
        self.slice = self._number(msg, "offset") if on else None
        return "now"

    def _on_rotation(self, msg: dict) -> str:
        self.rotation = controls.check_rotation(msg.get("matrix"), self.dim)
        return "now"

    def _on_snap(self, msg: dict) -> str:
        self.rotation = controls.snap(self.rotation)
        return "now"

    def _on_reset(self, msg: dict) -> str:
        self.rotation = np.eye(self.dim)
        self.options = dict(self.initial_options)
        self.slice = None
        return "now"

    def _on_release(self, msg: dict) -> str:
        return "release"

    def _on_toml(self, msg: dict) -> None:
        return None

    # -- frames --------------------------------------------------------------------------
    def frame_scene(self, rotation: np.ndarray, quality: str = FULL, options: dict | None = None) -> Scene:
        """The scene with the rotation applied to every object (and, for a draft, the draft
        resolution and one sample per cell); with ``options`` also as its ``[composite]``."""
        data = dict(self._desc)
        step = controls.transform_step(rotation, self.center)
        data["objects"] = [dict(o, transform=list(o.get("transform") or []) + [step])
                           for o in self._desc.get("objects", [])]
        if quality == DRAFT:
            data["camera"] = dict(data["camera"], resolution=self.draft)
            data["render"] = dict(data.get("render") or {}, samples=1)
        if options is not None:
            data["composite"] = options
        return load_dict(data, base=self.scene._base, name=f"{self.name} (view)")

    def render(self, snap: Snapshot, quality: str, cancelled: Callable[[], bool]) -> tuple[dict, bytes]:
        """Traces (unless the last retina shows this rotation already), composites and
        encodes a frame: draft frames as JPEG at ``draft_scale`` of the picture's size and a
        marching step of at least :data:`DRAFT_STEP`, full ones as PNG. Returns the frame's
        metadata and the encoded picture."""
        t0 = time.perf_counter()
        key = snap.rotation.tobytes() + repr(snap.slice).encode()
        cached = self._retina
        timings: dict[str, float] = {}
        if cached is not None and cached[0] == key and (cached[1] == FULL or quality == DRAFT):
            retina, traced = cached[2], cached[1]
        else:
            scene = self.frame_scene(snap.rotation, quality)
            if snap.slice is not None:
                # Slice mode: the (N−1)-D slice of the turned scene, a 3D one at the picture's
                # resolution (its retina is the picture).
                w, h = self.size
                if quality == DRAFT:
                    w, h = max(1, round(w * self.draft_scale)), max(1, round(h * self.draft_scale))
                scene = at_size(slice_scene(scene, self.slice_normal, snap.slice), (w, h))
            t1 = time.perf_counter()
            timings["build"] = (t1 - t0) * 1e3

            def progress(done: int, total: int) -> None:
                if cancelled():
                    raise Superseded

            retina = trace(scene, threads=self.threads, progress=progress)
            traced = quality
            self._retina = (key, quality, retina)
            timings["trace"] = (time.perf_counter() - t1) * 1e3
        if cancelled():  # the composite cannot stop midway: do not start a stale one
            raise Superseded
        t2 = time.perf_counter()
        options = dict(snap.options)
        if "axes_frame" in _parameters() and self.dim >= 3:  # the glyph turns with the object
            options["axes_frame"] = snap.rotation.tolist()
        if snap.slice is not None:
            options = slice_options(options, retina.dim)
        if quality == DRAFT:
            w, h = self.size
            options["size"] = (max(1, round(w * self.draft_scale)), max(1, round(h * self.draft_scale)))
            if "step" in _parameters():  # march drafts one sample per cell (opacity is step-independent)
                options["step"] = max(float(options.get("step", 0.5)), DRAFT_STEP)
            if "detail" in _parameters():  # drafts from the retina's cells alone (the grid path)
                options["detail"] = "retina"
        picture = composite(retina, threads=self.threads, **options)
        t3 = time.perf_counter()
        timings["composite"] = (t3 - t2) * 1e3
        pixels = to_srgb8(picture, opaque=True)
        from PIL import Image

        buf = io.BytesIO()
        image = Image.fromarray(pixels)
        if quality == DRAFT:
            image.save(buf, format="JPEG", quality=85)
        else:
            image.save(buf, format="PNG", compress_level=1)
        t4 = time.perf_counter()
        timings["encode"] = (t4 - t3) * 1e3
        meta = {
            "type": "frame", "seq": snap.seq, "quality": quality, "retina_quality": traced,
            "format": "jpeg" if quality == DRAFT else "png", "width": int(pixels.shape[1]),
            "height": int(pixels.shape[0]), "retina": list(retina.shape),
            "ms": (t4 - t0) * 1e3, "timings": timings,
        }
        return meta, buf.getvalue()

    # -- the view as a scene file ---------------------------------------------------------
    def composite_table(self) -> tuple[dict, dict]:
        """The composite options as a scene's ``[composite]`` table: (the keys the scene format
        of this ndtrace accepts, probed with the loader; the others). The picture's background
        is left to the scene's own ``background``."""
        table = {k: v for k, v in self.options.items() if k != "background" or v != self._desc.get("background")}
        if "axes_frame" in _parameters() and self.dim >= 3 and not np.array_equal(self.rotation, np.eye(self.dim)):
            table["axes_frame"] = self.rotation.tolist()  # the glyph as the page shows it
        accepted, refused = {}, {}
        probe = {"dim": self.dim, "camera": self._desc["camera"]}
        for key, value in table.items():
            try:
                load_dict(dict(probe, composite={key: value}))
            except ValueError:
                refused[key] = value
                continue
            accepted[key] = value
        return accepted, refused

    def view_toml(self) -> str:
        """The current view as a complete TOML scene: the objects turned by the rotation (a
        ``{ matrix = … }`` step appended to each ``transform``) and the ``[composite]`` table of
        the page's options. ``ndtrace FILE -o out.png`` renders what the page shows (options
        that this ndtrace's ``[composite]`` table cannot hold are listed in a comment)."""
        # The text is about 25 bytes per number of the objects' arrays, made once as TOML and
        # once more as the JSON of the reply.
        check_memory(_numbers(self._desc.get("objects", [])) * 25.0 * 3 + (1 << 20),
                     "the view as TOML")
        table, refused = self.composite_table()
        scene = self.frame_scene(self.rotation, FULL, options=table)
        center = [float(c) for c in self.center]
        header = (f"# The view of {self.name} in `ndtrace view`: every object turned by the {self.dim}×{self.dim} "
                  f"rotation about {center}\n# (the last transform step), composited as on the page.\n")
        if refused:
            items = ", ".join(f"{k} = {v!r}" for k, v in refused.items())
            header += f"# Composite options of the page that [composite] does not take here: {items}\n"
        return header + scene.to_toml()

    def close(self) -> None:
        self._retina = None

