"""Scenes: one description shared by TOML files, Python dicts and the builder API.

These three produce the same scene::

    ndtrace.load_file("scenes/tesseract.toml")

    ndtrace.load_dict({"dim": 4, "camera": {...}, "objects": [{"shape": "hypercube"}]})

    (ndtrace.Scene(4)
        .set_camera(position=[0, 0, 0, 5], look_at=[0, 0, 0, 0],
                    up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=40, resolution=64)
        .add_object("hypercube"))

Every key is documented in ``docs/scene-format.md``. A scene is validated completely when it
is built (on loading, or on first use after the builder changed it); errors are ValueErrors
naming the source, line and column (for files) and the field path, e.g.
``scene.toml:14:10: objects[2].material.color: expected 3 numbers, got 2``.
"""

from __future__ import annotations

import errno
import os
import re
import warnings
from typing import Any, Callable, Iterable

import numpy as np

from . import _ndtrace
from .mesh import _field, _scene_reader, from_object

__all__ = ["Scene", "load_file", "load_dict", "load_toml"]


#: Where an array stays one array (see :func:`_plain`): an object's key and its dimensions and
#: dtype (an elevation ``field``; a mesh's or surface's ``vertices``, ``simplices``,
#: ``triangles`` and per-vertex ``values``).
_ARRAY_KEYS = {"field": (3, np.float64), "vertices": (2, np.float64), "simplices": (2, np.int64),
               "triangles": (2, np.int64), "values": (1, np.float64)}
_ARRAY_PATH = re.compile(r"objects\[\d+\]\.(" + "|".join(_ARRAY_KEYS) + ")")


def _snapshot(path: str, key: str, value: np.ndarray) -> np.ndarray | None:
    """The array at an object's ``key`` as the one C-ordered array the loader takes (a
    snapshot in ``bytes``: the scene must not change when the caller's array does, copies of
    the scene can then share it, and the loader reads it in place), or None when it is not one
    (lists then, and the loader says what is wrong, as for the equal lists). An array whose
    numbers already lie in ``bytes`` (a snapshot, or ``np.frombuffer`` of bytes) is its own
    snapshot: no copy is made. Masked entries of a float array are NaN (refused, located, by
    the loader); masked indices and rows of no numbers go as lists."""
    ndim, dtype = _ARRAY_KEYS[key]
    if key == "field":
        a = _field(path, value)
    else:
        kinds = "iu" if dtype == np.int64 else "iuf"
        if value.ndim != ndim or value.dtype.kind not in kinds \
                or (ndim == 2 and value.shape[1] == 0 and value.shape[0] > 0) \
                or (value.dtype.kind == "u" and value.dtype.itemsize == 8 and value.size
                    and value.max() > np.iinfo(np.int64).max):
            return None
        if isinstance(value, np.ma.MaskedArray):
            if dtype == np.int64:
                return None
            a = np.ascontiguousarray(value.astype(np.float64).filled(np.nan))
        else:
            a = np.ascontiguousarray(value, dtype=dtype)
    return _in_bytes(a)


def _in_bytes(a: np.ndarray) -> np.ndarray:
    """``a`` (C-ordered) as a read-only array whose numbers lie in a ``bytes`` object, which
    nothing can change: ``a`` itself when they already do (:func:`_ndtrace.lendable`), else
    one copy. The loader reads such an array in place, without a copy of its own."""
    if _ndtrace.lendable(a):
        return a
    return np.frombuffer(a.tobytes(), dtype=a.dtype).reshape(a.shape)


#: Deeper nesting than any scene has (a list of rows of numbers is three levels).
MAX_DEPTH = 32


def _plain(value: Any, path: str = "", depth: int = 0) -> Any:
    """Nested numpy arrays and scalars → lists and Python numbers (for the Rust loader), except
    the mesh and field arrays of objects (:data:`_ARRAY_KEYS`), which stay one C-ordered array
    each, a snapshot in ``bytes`` the loader reads in place (a million numbers as lists would
    cost about 100 bytes each). A container nested deeper than :data:`MAX_DEPTH` (one that
    contains itself, say) is a ValueError naming where."""
    if depth > MAX_DEPTH:
        raise ValueError(f"{path or 'the scene'}: nested more than {MAX_DEPTH} levels deep "
                         "(a list or dict that contains itself?)")
    if isinstance(value, np.ndarray):
        if _ARRAY_PATH.fullmatch(path):
            a = _snapshot(path, path.rsplit(".", 1)[1], value)
            if a is not None:
                return a
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {k: _plain(v, f"{path}.{k}" if path else str(k), depth + 1) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v, f"{path}[{i}]", depth + 1) for i, v in enumerate(value)]
    return value


def _copy_tree(value: Any) -> Any:
    """``value`` with its dicts and lists copied all the way down and everything else (numbers,
    strings, read-only arrays) shared."""
    if isinstance(value, dict):
        return {k: _copy_tree(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_copy_tree(v) for v in value]
    if isinstance(value, np.ndarray) and value.flags.writeable:
        return value.copy()
    return value


def _freeze_arrays(data: dict) -> dict:
    """Makes the arrays of a description's objects read-only snapshots in ``bytes`` (as
    :func:`_plain` makes them), so that copies share them and the loader reads them in place."""
    for o in data.get("objects", []):
        if isinstance(o, dict):
            for key in _ARRAY_KEYS:
                if isinstance(o.get(key), np.ndarray):
                    o[key] = _in_bytes(np.ascontiguousarray(o[key]))
    return data


def _plain_scene(data: Any, name: str) -> Any:
    """:func:`_plain` of a whole description, its errors prefixed with the scene's name."""
    try:
        return _plain(data)
    except ValueError as e:
        raise ValueError(f"{name}: {e}") from None


def _warn(compiled: _ndtrace.CompiledScene) -> None:
    for message in compiled.warnings:
        warnings.warn(message, stacklevel=3)


class Scene:
    """An N-dimensional scene: build it with the methods below, or load it with
    :func:`load_file` / :func:`load_dict`. The BVH is built once and reused by every trace
    until the scene is changed."""

    def __init__(self, dim: int, *, background=None, ambient=None) -> None:
        self._data: dict[str, Any] = {"dim": dim, "objects": []}
        if background is not None:
            self._data["background"] = _plain(background)
        if ambient is not None:
            self._data["ambient"] = _plain(ambient)
        self._base: str | None = None
        self._compiled: _ndtrace.CompiledScene | None = None

    # -- construction -------------------------------------------------------------------
    @classmethod
    def _from_compiled(cls, compiled: _ndtrace.CompiledScene, base: str | None) -> "Scene":
        self = cls.__new__(cls)
        _warn(compiled)
        self._data = _freeze_arrays(compiled.to_dict())
        self._base = base
        self._compiled = compiled
        return self

    def _changed(self) -> "Scene":
        self._compiled = None
        return self

    def set_camera(
        self,
        position,
        *,
        look_at=None,
        up=None,
        orientation=None,
        projection: str = "perspective",
        fov: float | None = None,
        extent: float | None = None,
        resolution,
    ) -> "Scene":
        """Sets the camera (see ``docs/scene-format.md``, ``[camera]``)."""
        cam: dict[str, Any] = {"position": _plain(position), "projection": projection,
                               "resolution": _plain(resolution)}
        for key, value in (("look_at", look_at), ("up", up), ("orientation", orientation),
                           ("fov", fov), ("extent", extent)):
            if value is not None:
                cam[key] = _plain(value)
        self._data["camera"] = cam
        return self._changed()

    def add_light(self, type: str, **keys) -> "Scene":
        """Adds a light: ``add_light("directional", direction=[...], color=[...])`` or
        ``add_light("point", position=[...], color=[...], falloff=...)``."""
        self._data.setdefault("lights", []).append({"type": type, **_plain(keys)})
        return self._changed()

    def add_object(self, shape: str, *, material: dict | None = None,
                   transform: Iterable[dict] | None = None, **shape_keys) -> "Scene":
        """Adds an object: a generated shape (``"simplex"``, ``"hypercube"``,
        ``"cross_polytope"``, ``"sphere"`` with ``subdivisions``), ``"surface"`` (dim 4: a
        2-surface drawn directly, "bear hair", with ``vertices`` (V, 4), ``triangles`` (T, 3)
        and ``width`` in retina cells; see ``docs/scene-format.md``) or ``"mesh"`` with
        ``vertices`` (V, N) and ``simplices`` (S, N), a ``file``, or a ``mesh`` object: anything
        with ``.vertices`` and ``.faces`` (trimesh), ``.points`` and ``.cells`` (meshio), or a
        pair ``(vertices, simplices)`` (see :func:`ndtrace.mesh.from_object`)."""
        if "mesh" in shape_keys:
            given = [k for k in ("vertices", "simplices", "file") if k in shape_keys]
            if shape != "mesh" or given:
                raise ValueError(f"mesh: goes with shape \"mesh\" and without "
                                 f"{'/'.join(given) or 'vertices, simplices or file'}, "
                                 f"got shape {shape!r}")
            vertices, simplices = from_object(shape_keys.pop("mesh"), dim=self.dim)
            shape_keys = {"vertices": vertices, "simplices": simplices, **shape_keys}
        obj: dict[str, Any] = {"shape": shape,
                               **_plain(shape_keys, f"objects[{len(self._data['objects'])}]")}
        if material is not None:
            obj["material"] = _plain(material)
        if transform is not None:
            obj["transform"] = _plain(list(transform))
        self._data["objects"].append(obj)
        return self._changed()

    def set_render(self, **options) -> "Scene":
        """Sets ``[render]`` options: samples, seed, shadows, cull_backfaces, two_sided, mode."""
        self._data.setdefault("render", {}).update(_plain(options))
        return self._changed()

    def set_composite(self, **options) -> "Scene":
        """Sets ``[composite]`` options (how the retina becomes a picture: mode, crease_angle,
        depth_cue, …; see ``docs/scene-format.md``), checked by the core when the scene is
        rendered."""
        self._data.setdefault("composite", {}).update(_plain(options))
        return self._changed()

    # -- the built scene ----------------------------------------------------------------
    def compiled(self) -> _ndtrace.CompiledScene:
        """The validated, built scene (raises ValueError on a bad description)."""
        if self._compiled is None:
            self._compiled = _ndtrace.load_dict(_plain_scene(self._data, "<scene>"), "<scene>",
                                                self._base, _scene_reader)
            _warn(self._compiled)
        return self._compiled

    @property
    def dim(self) -> int:
        return int(self._data["dim"])

    @property
    def warnings(self) -> list[str]:
        return list(self.compiled().warnings)

    @property
    def retina_shape(self) -> tuple[int, ...]:
        return tuple(self.compiled().retina_shape)

    def to_dict(self, *, lists: bool = False) -> dict:
        """The full description with every default filled in. Mesh and field arrays given as
        numpy arrays come back as numpy arrays (copies), without a trip through lists;
        ``lists=True`` gives nested lists instead (plain data, e.g. for JSON)."""
        return self.compiled().to_dict(lists)

    def to_toml(self) -> str:
        """The description as TOML; ``load_toml(scene.to_toml())`` gives an equal scene."""
        return self.compiled().to_toml()

    def copy(self) -> "Scene":
        """An independent copy: its own description (dicts and lists copied, read-only field
        arrays shared) and, until either is changed, the same built scene."""
        other = type(self).__new__(type(self))
        other._data = _copy_tree(self._data)
        other._base = self._base
        other._compiled = self._compiled
        return other

    def __deepcopy__(self, memo: dict) -> "Scene":
        return self.copy()

    __copy__ = copy

    def __getstate__(self) -> dict:
        """Pickles the description (and the folder its files resolve against); the built scene
        is rebuilt, on first use, where it is unpickled (for Dask, multiprocessing, Ray)."""
        return {"data": self._data, "base": self._base}

    def __setstate__(self, state: dict) -> None:
        self._data = _freeze_arrays(state["data"])
        self._base = state["base"]
        self._compiled = None

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Scene):
            return NotImplemented
        return self.compiled().same_description(other.compiled())

    __hash__ = None  # type: ignore[assignment]

    def _repr_png_(self) -> bytes:
        """A preview for notebooks: the scene traced at a small resolution and composited with
        its own ``[composite]`` options, as PNG (see :func:`ndtrace.display.scene_png`)."""
        from .display import scene_png

        return scene_png(self)

    def __repr__(self) -> str:
        return f"<ndtrace.Scene dim={self.dim} objects={len(self._data.get('objects', []))}>"


def load_file(path: str | os.PathLike) -> Scene:
    """Loads a TOML scene file; mesh ``file`` paths are relative to its folder. Raises
    FileNotFoundError when there is no such file, ValueError (file:line:column: field) for a
    bad scene."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(errno.ENOENT, "no such scene file", path)
    return Scene._from_compiled(_ndtrace.load_file(path, _scene_reader),
                                os.path.dirname(os.path.abspath(path)))


def load_toml(text: str, *, name: str = "<string>", base: str | None = None) -> Scene:
    """Loads a scene from TOML text (``name`` appears in error messages)."""
    return Scene._from_compiled(_ndtrace.load_toml(text, name, base, _scene_reader), base)


def _reanimated(scene: Scene, data: dict) -> Scene:
    """``data`` — ``scene``'s description with another ``[animation]`` table — as a scene that
    shares ``scene``'s build when nothing else differs (else built anew, as :func:`load_dict`)."""
    compiled = _ndtrace.load_dict(_plain_scene(data, "<dict>"), "<dict>", scene._base, _scene_reader,
                                  scene.compiled())
    return Scene._from_compiled(compiled, scene._base)


def load_dict(data: dict, *, base: str | None = None, name: str = "<dict>") -> Scene:
    """Loads a scene from a dict shaped like the TOML format; arrays may be numpy arrays.
    Relative mesh files resolve against ``base`` (default: the current directory); errors are
    prefixed with ``name``."""
    return Scene._from_compiled(_ndtrace.load_dict(_plain_scene(data, name), name, base, _scene_reader),
                                base)
