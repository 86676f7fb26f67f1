"""Retinas: the (N−1)-dimensional images an N-D camera records, and ``trace``."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from . import _ndtrace
from ._dask import trace_slabs
from .scene import Scene, load_toml

__all__ = ["Retina", "trace"]


@dataclass(frozen=True, eq=False)
class Retina:
    """A traced retina. Arrays are indexed ``[i_{N−1}, …, i_2, i_1]`` (a 3D retina is
    (slices, rows, columns)):

    * ``rgba`` (…, 4) float32: linear colour premultiplied by alpha, the covered fraction;
    * ``depth`` float32: distance from the camera position (perspective) or the image plane
      (orthographic) to the nearest hit, inf on a miss;
    * ``normal`` (…, N) float32: unit shading normal of the nearest hit, 0 on a miss;
    * ``object_id`` int32: index into the scene's objects, −1 on a miss;
    * ``primitive_id`` int64: index into that object's simplices, −1 on a miss.
    """

    dim: int
    rgba: np.ndarray
    depth: np.ndarray
    normal: np.ndarray
    object_id: np.ndarray
    primitive_id: np.ndarray
    camera: str | None = None
    """The scene's ``[camera]`` section as TOML (stored in retina files)."""
    _source: _ndtrace.CompiledScene | None = field(default=None, repr=False, compare=False)
    """The compiled scene this retina was traced from (its edges and camera), if any."""
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def _camera_info(self) -> dict | None:
        """The camera as the compositor needs it (orientation, cell size, projection): from the
        scene it was traced from, or rebuilt from :attr:`camera` (a retina read from a file)."""
        if "camera" not in self._cache:
            info = None
            if self._source is not None:
                info = self._source.retina_camera()
            elif self.camera:
                try:
                    info = load_toml(f"dim = {self.dim}\n{self.camera}\n").compiled().retina_camera()
                except ValueError:
                    info = None
            self._cache["camera"] = info
        return self._cache["camera"]

    def _edges(self, angle: float) -> np.ndarray | None:
        """The scene's feature-edge pieces in retina coordinates (rows ``[a, b, depth_a,
        depth_b, visible]``) for crease angle ``angle``, or None without a scene."""
        if self._source is None:
            return None
        key = ("edges", float(angle))
        if key not in self._cache:
            self._cache[key] = np.asarray(self._source.retina_edges(float(angle)))
        return self._cache[key]

    @property
    def shape(self) -> tuple[int, ...]:
        """Retina shape (numpy order)."""
        return self.depth.shape

    @property
    def hit(self) -> np.ndarray:
        """Boolean mask of cells whose nearest sample hit something."""
        return self.object_id >= 0

    def __repr__(self) -> str:
        """One line: dimension, shape, hit fraction and depth range (not the arrays)."""
        hit = self.hit
        count = int(hit.sum())
        frac = count / hit.size if hit.size else 0.0
        if count:
            d = self.depth[hit]
            depth = f"depth {float(d.min()):.4g}…{float(d.max()):.4g}"
        else:
            depth = "no hits"
        shape = "×".join(map(str, self.shape))
        return f"<ndtrace.Retina dim={self.dim} shape={shape} hit={frac:.1%} {depth}>"

    #: The notebook picture (Jupyter's ``_repr_png_``): the default composite
    #: (``ndtrace.composite(retina)``) as PNG. Compositing is a layer above this module, so
    #: :mod:`ndtrace.display`, which ``import ndtrace`` loads, sets it
    #: (:func:`ndtrace.display.retina_png`).
    _repr_png_: ClassVar[Callable[[Retina], bytes]]


def trace(
    scene: Scene,
    threads: int | None = None,
    progress: Callable[[int, int], object] | None = None,
    *,
    client=None,
) -> Retina:
    """Traces ``scene`` onto its retina with ``threads`` threads (None: every core).

    ``progress(done, total)`` is called about ten times a second with the number of cells
    traced. Ctrl-C cancels within a fraction of a second (KeyboardInterrupt). The result is
    bit-identical whatever the thread count.

    The arrays own their memory. When numpy frees them, the buffers are kept (up to 256 MiB)
    and reused by the next trace, which overwrites every element: writing to fresh memory
    costs page faults, a fifth of a 4D trace at 128³. ``ndtrace.release_buffers()`` frees the
    kept buffers.

    ``client`` (a ``dask.distributed.Client``) traces the retina in slabs on its workers
    (each slab with ``threads`` threads, default 1: one per worker thread): the same retina, bit for bit
    (:mod:`ndtrace.cluster`); progress then counts the cells of finished slabs.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected an ndtrace.Scene, got {type(scene).__name__}")
    if threads is not None and (not isinstance(threads, int) or threads < 1):
        raise ValueError(f"threads: expected a positive integer or None, got {threads!r}")
    compiled = scene.compiled()
    if client is not None:
        out = trace_slabs(scene, client, threads, progress)
    else:
        out = compiled.trace(threads, progress)
    return Retina(**out, camera=compiled.camera_toml(), _source=compiled)
