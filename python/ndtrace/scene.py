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
import warnings
from collections.abc import Callable, Iterable
from typing import Any, ClassVar

import numpy as np

from . import _ndtrace
from ._description import MAX_DEPTH as MAX_DEPTH, freeze_arrays, plain, plain_scene, scene_reader
from .mesh import from_object

__all__ = ["Scene", "load_file", "load_dict", "load_toml", "slice_scene"]


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
            self._data["background"] = plain(background)
        if ambient is not None:
            self._data["ambient"] = plain(ambient)
        self._base: str | None = None
        self._compiled: _ndtrace.CompiledScene | None = None

    # -- construction -------------------------------------------------------------------
    @classmethod
    def _from_compiled(cls, compiled: _ndtrace.CompiledScene, base: str | None) -> Scene:
        self = cls.__new__(cls)
        _warn(compiled)
        self._data = freeze_arrays(compiled.to_dict())
        self._base = base
        self._compiled = compiled
        return self

    def _changed(self) -> Scene:
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
    ) -> Scene:
        """Sets the camera (see ``docs/scene-format.md``, ``[camera]``)."""
        cam: dict[str, Any] = {"position": plain(position), "projection": projection,
                               "resolution": plain(resolution)}
        for key, value in (("look_at", look_at), ("up", up), ("orientation", orientation),
                           ("fov", fov), ("extent", extent)):
            if value is not None:
                cam[key] = plain(value)
        self._data["camera"] = cam
        return self._changed()

    def add_light(self, type: str, **keys) -> Scene:
        """Adds a light: ``add_light("directional", direction=[...], color=[...])`` or
        ``add_light("point", position=[...], color=[...], falloff=...)``."""
        self._data.setdefault("lights", []).append({"type": type, **plain(keys)})
        return self._changed()

    def add_object(self, shape: str, *, material: dict | None = None,
                   transform: Iterable[dict] | None = None, **shape_keys) -> Scene:
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
                               **plain(shape_keys, f"objects[{len(self._data['objects'])}]")}
        if material is not None:
            obj["material"] = plain(material)
        if transform is not None:
            obj["transform"] = plain(list(transform))
        self._data["objects"].append(obj)
        return self._changed()

    def set_render(self, **options) -> Scene:
        """Sets ``[render]`` options: samples, seed, shadows, cull_backfaces, two_sided, mode."""
        self._data.setdefault("render", {}).update(plain(options))
        return self._changed()

    def set_slice(self, normal, offset: float) -> Scene:
        """Sets ``[slice]``: the hyperplane ``n̂·x = offset`` the command line and
        :func:`ndtrace.animate` cut the scene with (see :func:`slice_scene`)."""
        self._data["slice"] = {"normal": plain(normal), "offset": plain(offset)}
        return self._changed()

    def set_composite(self, **options) -> Scene:
        """Sets ``[composite]`` options (how the retina becomes a picture: mode, crease_angle,
        depth_cue, …; see ``docs/scene-format.md``), checked by the core when the scene is
        rendered."""
        self._data.setdefault("composite", {}).update(plain(options))
        return self._changed()

    # -- the built scene ----------------------------------------------------------------
    def compiled(self) -> _ndtrace.CompiledScene:
        """The validated, built scene (raises ValueError on a bad description)."""
        if self._compiled is None:
            self._compiled = _ndtrace.load_dict(plain_scene(self._data, "<scene>"), "<scene>",
                                                self._base, scene_reader)
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

    def copy(self) -> Scene:
        """An independent copy: its own description (dicts and lists copied, read-only field
        arrays shared) and, until either is changed, the same built scene."""
        other = type(self).__new__(type(self))
        other._data = _copy_tree(self._data)
        other._base = self._base
        other._compiled = self._compiled
        return other

    def __deepcopy__(self, memo: dict) -> Scene:
        return self.copy()

    __copy__ = copy

    def __getstate__(self) -> dict:
        """Pickles the description (and the folder its files resolve against); the built scene
        is rebuilt, on first use, where it is unpickled (for Dask, multiprocessing, Ray)."""
        return {"data": self._data, "base": self._base}

    def __setstate__(self, state: dict) -> None:
        self._data = freeze_arrays(state["data"])
        self._base = state["base"]
        self._compiled = None

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Scene):
            return NotImplemented
        return self.compiled().same_description(other.compiled())

    __hash__ = None  # type: ignore[assignment]

    #: The notebook picture (Jupyter's ``_repr_png_``): a preview, the scene traced at a small
    #: resolution and composited with its own ``[composite]`` options, as PNG. Tracing and
    #: compositing are layers above this module, so :mod:`ndtrace.display`, which ``import
    #: ndtrace`` loads, sets it (:func:`ndtrace.display.scene_png`).
    _repr_png_: ClassVar[Callable[[Scene], bytes]]

    def __repr__(self) -> str:
        return f"<ndtrace.Scene dim={self.dim} objects={len(self._data.get('objects', []))}>"


def load_file(path: str | os.PathLike) -> Scene:
    """Loads a TOML scene file; mesh ``file`` paths are relative to its folder. Raises
    FileNotFoundError when there is no such file, ValueError (file:line:column: field) for a
    bad scene."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(errno.ENOENT, "no such scene file", path)
    return Scene._from_compiled(_ndtrace.load_file(path, scene_reader),
                                os.path.dirname(os.path.abspath(path)))


def load_toml(text: str, *, name: str = "<string>", base: str | None = None) -> Scene:
    """Loads a scene from TOML text (``name`` appears in error messages)."""
    return Scene._from_compiled(_ndtrace.load_toml(text, name, base, scene_reader), base)


def load_dict(data: dict, *, base: str | None = None, name: str = "<dict>") -> Scene:
    """Loads a scene from a dict shaped like the TOML format; arrays may be numpy arrays.
    Relative mesh files resolve against ``base`` (default: the current directory); errors are
    prefixed with ``name``."""
    return Scene._from_compiled(_ndtrace.load_dict(plain_scene(data, name), name, base, scene_reader),
                                base)


def slice_scene(scene: Scene, normal=None, offset=None) -> Scene:
    """The (N−1)-dimensional scene that the hyperplane ``n̂·x = offset`` cuts from ``scene``:
    the view of 4D Toys, an N-D object passing through our space, traced and composited like
    any scene (a 4D scene's slice is an ordinary 3D picture).

    ``normal`` (N numbers) need not be unit length; ``offset`` is the hyperplane's signed
    distance from the origin along it. Without them the scene's ``[slice]`` table is used.
    Coordinates in the slice are those of :func:`ndtrace.mesh.slice` (for an axis normal, the
    other axes in order). The slice scene holds each object's world-space mesh sliced (its
    material kept, its per-vertex ``values`` interpolated; surfaces and objects the hyperplane
    misses are left out), the lights projected into the hyperplane (a directional light along
    the normal shines from the camera), a camera looking at the sliced objects from the N-D
    camera's distance along its viewing direction projected into the hyperplane, and the
    scene's background, ambient light and ``[render]`` options. Raises ValueError naming
    ``normal`` or ``offset``.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected an ndtrace.Scene, got {type(scene).__name__}")
    if (normal is None) != (offset is None):
        raise ValueError("normal, offset: give both, or neither to use the scene's [slice]")
    if normal is None:
        compiled = scene.compiled().slice(None, 0.0)
    else:
        n = np.asarray(normal)
        if n.dtype.kind not in "biuf" or n.shape != (scene.dim,):
            raise ValueError(f"normal: expected {scene.dim} real numbers (dim = {scene.dim}), "
                             f"got {np.asarray(normal).tolist()!r}")
        if not np.all(np.isfinite(n)) or not np.any(n != 0):
            raise ValueError(f"normal: must be a finite non-zero vector, got {n.tolist()}")
        if isinstance(offset, bool) or not isinstance(offset, (int, float, np.integer,
                                                              np.floating)):
            raise ValueError(f"offset: expected a real number, got {offset!r}")
        if not np.isfinite(offset):
            raise ValueError(f"offset: must be finite, got {offset}")
        compiled = scene.compiled().slice([float(x) for x in n], float(offset))
    return Scene._from_compiled(compiled, scene._base)
