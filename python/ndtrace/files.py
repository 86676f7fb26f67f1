"""Pictures and retinas on disk: OpenEXR (floats, retinas) and 8-bit sRGB PNG, JPEG, WebP and
TIFF through Pillow (format: docs/retina-format.md).

Every file is written to a temporary file and renamed into place: an interrupted or failed
write never leaves a broken file where a good one was. A new file gets the mode the umask gives
(0644 under umask 022), a file replaced keeps its own.
"""

from __future__ import annotations

import numbers
import os

import numpy as np

from . import _ndtrace
from ._util import c_array, output_done, output_temp, picture_array, picture_pixels
from .retina import Retina

__all__ = ["write_exr", "read_exr", "write_png", "write_image", "IMAGE_FORMATS"]

#: The 8-bit picture formats by extension (Pillow's format names).
IMAGE_FORMATS: dict[str, str] = {".png": "PNG", ".jpg": "JPEG", ".jpeg": "JPEG",
                                 ".webp": "WEBP", ".tif": "TIFF", ".tiff": "TIFF"}

_EXTS = (".exr",)


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
        if isinstance(r.dim, bool) or not isinstance(r.dim, numbers.Integral) or not (
                _ndtrace.MIN_DIM <= r.dim <= _ndtrace.MAX_DIM):
            raise ValueError(f"retina.dim: expected an integer in {_ndtrace.MIN_DIM}..{_ndtrace.MAX_DIM}, "
                             f"got {r.dim!r}")
        c = c_array
        _ndtrace.write_retina_exr(
            path, r.dim, list(r.shape), c(r.rgba, np.float32), c(r.depth, np.float32),
            c(r.normal, np.float32), c(r.object_id, np.int32), c(r.primitive_id, np.int64),
            r.camera,
        )
        return
    img = picture_array("image", image_or_retina)
    if depth is not None:
        depth = c_array(depth, np.float32)
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


def write_image(path: str | os.PathLike, image, *, transparent: bool = False,
                quality: int = 95) -> None:
    """Writes a picture as an 8-bit sRGB image whose format follows the extension: ``.png``,
    ``.jpg``/``.jpeg``, ``.webp`` or ``.tif``/``.tiff`` (:data:`IMAGE_FORMATS`, Pillow).

    ``image`` is a picture of :func:`ndtrace.composite`: float ``(H, W, 4)``, linear, RGB
    composited over the background and A the content's opacity. By default the file is
    **opaque**, that colour as it is (as GIF and MP4 frames show it); ``transparent=True``
    keeps alpha, un-premultiplying the colour (straight alpha), which is right for a picture
    composited over black (``ndtrace.composite``'s default background). Float ``(H, W)`` grey
    and ``(H, W, 3)`` RGB pictures are linear and opaque. ``uint8`` images ``(H, W)``,
    ``(H, W, 3)`` or ``(H, W, 4)`` are taken as encoded already and written unchanged (L, RGB
    or RGBA). JPEG has no alpha channel; ``quality`` is that of JPEG and WebP.
    """
    path = os.fspath(path)
    ext = os.path.splitext(path)[1].lower()
    if ext not in IMAGE_FORMATS:
        raise ValueError(f"{path}: unknown extension for a picture: expected "
                         f"{', '.join(IMAGE_FORMATS)}")
    kind = IMAGE_FORMATS[ext]
    pixels = picture_pixels("image", image, transparent)
    if kind == "JPEG" and pixels.ndim == 3 and pixels.shape[2] == 4:
        raise ValueError(f"{path}: JPEG has no alpha channel: write .png, .webp or .tif for "
                         "transparency")
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise OSError(f"{path}: cannot write: folder {folder} does not exist")
    from PIL import Image

    options = {"quality": int(quality)} if kind in ("JPEG", "WEBP") else {}
    tmp = output_temp(path, ext)
    try:
        Image.fromarray(pixels).save(tmp, format=kind, **options)
        output_done(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_png(path: str | os.PathLike, image, *, transparent: bool = False) -> None:
    """Writes a picture as an 8-bit sRGB PNG: opaque by default (the picture's colour over its
    background, as ndtrace.composite made it), straight alpha with ``transparent=True``;
    ``uint8`` images are written unchanged (see :func:`write_image`)."""
    path = os.fspath(path)
    _check_ext(path, (".png",), "a PNG file")
    write_image(path, image, transparent=transparent)


def to_srgb8(image, *, opaque: bool = False) -> np.ndarray:
    """A picture ``(H, W, 4)`` (premultiplied linear RGBA) as 8-bit sRGB: ``(H, W, 4)`` with
    straight alpha (what :func:`write_png` stores), or with ``opaque`` ``(H, W, 3)`` of the
    colour as it is (the composite over its background: what GIF and MP4 frames show)."""
    return _ndtrace.to_srgb8(picture_array("image", image), opaque)
