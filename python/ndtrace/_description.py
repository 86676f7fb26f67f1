"""A scene description as the core's loaders take it, from the Python values of a dict or the
builder: nested lists and plain numbers, except the mesh and field arrays of objects, which stay
one array each, a read-only snapshot in ``bytes`` that the loader reads in place; and the
reader of the files the core does not read itself (meshio formats, NIfTI fields).

:mod:`ndtrace.scene` builds scenes with these; :func:`plain` is also how the compositor's
options reach the core (:mod:`ndtrace.composite`, :mod:`ndtrace.svg`).
"""

from __future__ import annotations

import re
from typing import Any

import numpy as np

from . import _ndtrace
from ._util import field_array
from .mesh import read, read_field

__all__ = ["ARRAY_KEYS", "MAX_DEPTH", "plain", "plain_scene", "in_bytes", "snapshot", "freeze_arrays",
           "SceneReader", "scene_reader"]


#: Where an array stays one array (see :func:`plain`): an object's key and its dimensions and
#: dtype (an elevation ``field``; a mesh's or surface's ``vertices``, ``simplices``,
#: ``triangles`` and per-vertex ``values``).
ARRAY_KEYS = {"field": (3, np.float64), "vertices": (2, np.float64), "simplices": (2, np.int64),
              "triangles": (2, np.int64), "values": (1, np.float64)}
_ARRAY_PATH = re.compile(r"objects\[\d+\]\.(" + "|".join(ARRAY_KEYS) + ")")


def snapshot(path: str, key: str, value: np.ndarray) -> np.ndarray | None:
    """The array at an object's ``key`` as the one C-ordered array the loader takes (a
    snapshot in ``bytes``: the scene must not change when the caller's array does, copies of
    the scene can then share it, and the loader reads it in place), or None when it is not one
    (lists then, and the loader says what is wrong, as for the equal lists). An array whose
    numbers already lie in ``bytes`` (a snapshot, or ``np.frombuffer`` of bytes) is its own
    snapshot: no copy is made. Masked entries of a float array are NaN (refused, located, by
    the loader); masked indices and rows of no numbers go as lists."""
    ndim, dtype = ARRAY_KEYS[key]
    if key == "field":
        a = field_array(path, value)
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
            a = np.ascontiguousarray(np.ma.filled(value.astype(np.float64), np.nan))
        else:
            a = np.ascontiguousarray(value, dtype=dtype)
    return in_bytes(a)


def in_bytes(a: np.ndarray) -> np.ndarray:
    """``a`` (C-ordered) as a read-only array whose numbers lie in a ``bytes`` object, which
    nothing can change: ``a`` itself when they already do (:func:`_ndtrace.lendable`), else
    one copy. The loader reads such an array in place, without a copy of its own."""
    if _ndtrace.lendable(a):
        return a
    return np.frombuffer(a.tobytes(), dtype=a.dtype).reshape(a.shape)


#: Deeper nesting than any scene has (a list of rows of numbers is three levels).
MAX_DEPTH = 32


def plain(value: Any, path: str = "", depth: int = 0) -> Any:
    """Nested numpy arrays and scalars → lists and Python numbers (for the Rust loader), except
    the mesh and field arrays of objects (:data:`ARRAY_KEYS`), which stay one C-ordered array
    each, a snapshot in ``bytes`` the loader reads in place (a million numbers as lists would
    cost about 100 bytes each). A container nested deeper than :data:`MAX_DEPTH` (one that
    contains itself, say) is a ValueError naming where."""
    if depth > MAX_DEPTH:
        raise ValueError(f"{path or 'the scene'}: nested more than {MAX_DEPTH} levels deep "
                         "(a list or dict that contains itself?)")
    if isinstance(value, np.ndarray):
        if _ARRAY_PATH.fullmatch(path):
            a = snapshot(path, path.rsplit(".", 1)[1], value)
            if a is not None:
                return a
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {k: plain(v, f"{path}.{k}" if path else str(k), depth + 1) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(v, f"{path}[{i}]", depth + 1) for i, v in enumerate(value)]
    return value


def freeze_arrays(data: dict) -> dict:
    """Makes the arrays of a description's objects read-only snapshots in ``bytes`` (as
    :func:`plain` makes them), so that copies share them and the loader reads them in place."""
    for o in data.get("objects", []):
        if isinstance(o, dict):
            for key in ARRAY_KEYS:
                if isinstance(o.get(key), np.ndarray):
                    o[key] = in_bytes(np.ascontiguousarray(o[key]))
    return data


def plain_scene(data: Any, name: str) -> Any:
    """:func:`plain` of a whole description, its errors prefixed with the scene's name."""
    try:
        return plain(data)
    except ValueError as e:
        raise ValueError(f"{name}: {e}") from None


class SceneReader:
    """What the scene loaders call for a file the core does not read itself: ``reader(path,
    dim)`` for a mesh (meshio formats) and ``reader.field(path)`` for an elevation map's NIfTI
    field. Errors become scene errors naming the field and the file."""

    @staticmethod
    def _strip(path: str, e: Exception) -> str:
        message = str(e)
        return message[len(path) + 2:] if message.startswith(path + ": ") else message

    def __call__(self, path: str, dim: int) -> tuple[np.ndarray, np.ndarray]:
        try:
            return read(path, dim)
        except ValueError as e:
            raise ValueError(self._strip(path, e)) from None

    def field(self, path: str) -> np.ndarray:
        try:
            return read_field(path)
        except ValueError as e:
            raise ValueError(self._strip(path, e)) from None


#: The reader the loaders are given.
scene_reader = SceneReader()
