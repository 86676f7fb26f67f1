"""Pictures in notebooks: ``ndtrace.show`` and the PNG representations of retinas and scenes.

In Jupyter (or anything that calls ``_repr_png_``) a :class:`~ndtrace.Retina` shows its default
composite, a :class:`~ndtrace.Scene` a small trace of itself, and ``ndtrace.show(x)`` any
picture::

    retina = ndtrace.trace(scene)
    retina                                            # the default composite, as PNG
    ndtrace.show(ndtrace.composite(retina, mode="mip"))
    ndtrace.show(retina, mode="slices")               # composite keywords go to composite
"""

from __future__ import annotations

import io
import math

import numpy as np

from ._util import picture_pixels
from .composite import composite, scene_options
from .files import write_image
from .retina import Retina, trace
from .scene import Scene, load_dict

__all__ = ["show", "Picture", "PREVIEW_CELLS", "PREVIEW_SIZE"]

#: Retina cells of a scene's preview (``Scene._repr_png_``): 48³ for a 4D scene.
PREVIEW_CELLS: int = 48 ** 3
#: The preview picture's longer side in pixels.
PREVIEW_SIZE: int = 384


def _png(pixels: np.ndarray) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(pixels).save(buf, format="PNG")
    return buf.getvalue()


class Picture:
    """A picture that displays itself: ``_repr_png_`` in Jupyter, :meth:`save` to a file.
    ``pixels`` holds the 8-bit sRGB image, ``(H, W)``, ``(H, W, 3)`` or ``(H, W, 4)`` uint8."""

    def __init__(self, pixels: np.ndarray) -> None:
        self.pixels = pixels

    @property
    def shape(self) -> tuple[int, ...]:
        return self.pixels.shape

    def _repr_png_(self) -> bytes:
        return _png(self.pixels)

    def save(self, path) -> None:
        """Writes the picture (any format of :func:`ndtrace.write_image`)."""
        write_image(path, self.pixels)

    def __repr__(self) -> str:
        h, w = self.pixels.shape[:2]
        return f"<ndtrace picture {w}×{h}>"


def show(image_or_retina, *, transparent: bool = False, **composite_options) -> Picture:
    """An object that displays as PNG in a notebook: a picture of :func:`ndtrace.composite`
    (float ``(H, W, 4)`` linear RGBA, opaque over its background unless ``transparent``),
    float ``(H, W)`` grey or ``(H, W, 3)`` RGB (linear), a uint8 image ``(H, W)``,
    ``(H, W, 3)``, ``(H, W, 4)`` (shown unchanged), an :class:`ndtrace.Retina` (composited with
    ``composite_options``, e.g. ``mode="mip"``) or an :class:`ndtrace.Scene` (traced and
    composited with its own options). Bad input raises ValueError naming the argument."""
    if isinstance(image_or_retina, Scene):
        options = dict(scene_options(image_or_retina.to_dict()), **composite_options)
        image_or_retina = trace(image_or_retina)
        picture = _composite(image_or_retina, options)
    elif isinstance(image_or_retina, Retina):
        picture = _composite(image_or_retina, composite_options)
    else:
        if composite_options:
            raise ValueError(f"{', '.join(composite_options)}: composite keywords go with a Retina "
                             "or a Scene, not with a picture")
        if isinstance(image_or_retina, (str, bytes)) or image_or_retina is None:
            raise ValueError(f"image_or_retina: expected a picture array, an ndtrace.Retina or an "
                             f"ndtrace.Scene, got {type(image_or_retina).__name__}")
        picture = image_or_retina
    return Picture(picture_pixels("image_or_retina", picture, transparent))


def _composite(retina, options: dict) -> np.ndarray:
    return composite(retina, **options)


def retina_png(retina) -> bytes:
    """``Retina._repr_png_``: the default composite as PNG."""
    return show(retina)._repr_png_()


def retina_repr(retina) -> str:
    """``Retina.__repr__``: dimension, shape, hit fraction and depth range in one line."""
    return Retina.__repr__(retina)


def camera_resolution(camera: dict, dim: int) -> list[int]:
    """A scene description's ``camera.resolution`` as R_1 … R_{N−1}."""
    res = camera["resolution"]
    return [int(res)] * (dim - 1) if isinstance(res, (int, np.integer)) else [int(r) for r in res]


def reduced_resolution(resolution: list[int], cells: int) -> list[int]:
    """A retina resolution with about ``cells`` cells: every axis scaled by the same factor
    (never up), at least 2 cells per axis."""
    total = math.prod(resolution)
    if total <= cells:
        return list(resolution)
    f = (cells / total) ** (1.0 / len(resolution))
    return [max(2, round(r * f)) for r in resolution]


def scene_png(scene) -> bytes:
    """``Scene._repr_png_``: the scene traced at a small resolution (about
    :data:`PREVIEW_CELLS` cells, one sample each) and composited with its own options at about
    :data:`PREVIEW_SIZE` pixels."""
    data = scene.to_dict()
    data.pop("animation", None)
    camera = data["camera"]
    dim = int(data["dim"])
    res = reduced_resolution(camera_resolution(camera, dim), PREVIEW_CELLS)
    data["camera"] = dict(camera, resolution=res)
    data["render"] = dict(data.get("render") or {}, samples=1)
    small = load_dict(data, base=scene._base, name="<preview>")
    options = scene_options(data)
    w, h = options.get("size") or (512, 512)
    scale = PREVIEW_SIZE / max(w, h)
    if dim >= 4:
        options["size"] = (max(1, round(w * scale)), max(1, round(h * scale)))
    elif dim == 3:
        options["size"] = None if max(res) >= PREVIEW_SIZE // 2 else (PREVIEW_SIZE, round(PREVIEW_SIZE * res[1] / res[0]))
    return show(_composite(trace(small), options))._repr_png_()


# Scenes and retinas show these pictures in notebooks. Drawing them takes the tracer and the
# compositor, which sit above the two classes, so this module gives the classes their
# ``_repr_png_`` (declared there); ``import ndtrace`` imports it.
Scene._repr_png_ = scene_png
Retina._repr_png_ = retina_png
