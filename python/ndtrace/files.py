"""Pictures and retinas on disk: OpenEXR and 8-bit sRGB PNG (format: docs/retina-format.md).

Every file is written to a temporary file and renamed into place: an interrupted or failed
write never leaves a broken file where a good one was.
"""

from __future__ import annotations

import os

import numpy as np

from . import _ndtrace
from .retina import Retina

__all__ = ["write_exr", "read_exr", "write_png"]

_EXTS = (".exr",)


def _image(name: str, image) -> np.ndarray:
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] != 4 or a.shape[0] == 0 or a.shape[1] == 0:
        raise ValueError(f"{name}: expected an image of shape (H, W, 4), got {a.shape}")
    if a.dtype.kind not in "biuf":
        raise ValueError(f"{name}: expected real numbers, got dtype {a.dtype}")
    a = np.ascontiguousarray(a, dtype=np.float32)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: the image holds NaN or infinite values")
    return a


def _check_ext(path: str, exts: tuple[str, ...], what: str) -> None:
    if not path.lower().endswith(exts):
        raise ValueError(f"{path}: unknown extension for {what}: expected {' or '.join(exts)}")


def write_exr(path: str | os.PathLike, image_or_retina, *, depth=None) -> None:
    """Writes a 2D picture ``(H, W, 4)`` float RGBA (premultiplied, linear; optional
    ``depth`` (H, W) as channel Z) as one part, or a :class:`Retina` as one part per 2D slice
    (see docs/retina-format.md), with ZIP compression."""
    path = os.fspath(path)
    _check_ext(path, _EXTS, "an OpenEXR file")
    if isinstance(image_or_retina, Retina):
        r = image_or_retina
        c = np.ascontiguousarray
        _ndtrace.write_retina_exr(
            path, r.dim, list(r.shape), c(r.rgba, np.float32), c(r.depth, np.float32),
            c(r.normal, np.float32), c(r.object_id, np.int32), c(r.primitive_id, np.int64),
            r.camera,
        )
        return
    img = _image("image", image_or_retina)
    if depth is not None:
        depth = np.ascontiguousarray(depth, dtype=np.float32)
        if depth.shape != img.shape[:2]:
            raise ValueError(f"depth: expected shape {img.shape[:2]}, got {depth.shape}")
    _ndtrace.write_picture_exr(path, img, depth)


def read_exr(path: str | os.PathLike):
    """Reads an EXR: a :class:`Retina` (arrays of the full (N−1)-D shape) for a retina written
    by ndtrace, else the picture as an ``(H, W, 4)`` float32 array (premultiplied RGBA; a
    missing A channel reads as 1). Unreadable or non-EXR files raise OSError."""
    out = _ndtrace.read_exr(os.fspath(path))
    if out["kind"] == "retina":
        return Retina(dim=out["dim"], rgba=out["rgba"], depth=out["depth"], normal=out["normal"],
                      object_id=out["object_id"], primitive_id=out["primitive_id"],
                      camera=out["camera"])
    return out["rgba"]


def write_png(path: str | os.PathLike, image) -> None:
    """Writes a picture ``(H, W, 4)`` (premultiplied linear RGBA) as 8-bit sRGB PNG with
    straight alpha."""
    path = os.fspath(path)
    _check_ext(path, (".png",), "a PNG file")
    _ndtrace.write_png(path, _image("image", image))


def to_srgb8(image, *, opaque: bool = False) -> np.ndarray:
    """A picture ``(H, W, 4)`` (premultiplied linear RGBA) as 8-bit sRGB: ``(H, W, 4)`` with
    straight alpha (what :func:`write_png` stores), or with ``opaque`` ``(H, W, 3)`` of the
    colour as it is (the composite over its background: what GIF and MP4 frames show)."""
    return _ndtrace.to_srgb8(_image("image", image), opaque)
