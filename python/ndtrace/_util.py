"""Array checks and conversions shared by the modules: arrays as the core reads them (C-ordered,
aligned, one dtype), with errors that name the argument at fault.

Each helper has one meaning, said by its name: :func:`finite_float64` is the input check of the
geometry and rotation kernels, :func:`float32_array` the compositor's (which takes inf and NaN),
:func:`picture_array` and :func:`picture_pixels` those of pictures, :func:`field_array` that of
a scalar field, :func:`check_memory` the memory guard's check of an allocation before it is
made. :func:`output_temp` and :func:`output_done` are how every output file is written: to a
temporary file beside it, renamed into place with the mode a new file gets from the umask (or
the mode of the file it replaces).
"""

from __future__ import annotations

import numbers
import os
import stat
import tempfile

import numpy as np

from . import _ndtrace

__all__ = ["c_array", "finite_float64", "broadcast_batch", "batch_size", "float32_array",
           "picture_array", "picture_pixels", "field_array", "angle_degrees", "check_memory",
           "output_temp", "output_done", "output_mode"]


def check_memory(nbytes: float, what: str) -> None:
    """Refuses, before it is made, an allocation of about ``nbytes`` whose size comes from the
    input: a ValueError of one line naming ``what`` and the limit (the core's memory guard,
    ``NDTRACE_MEMORY_LIMIT``, ``ulimit -v``, the cgroup, free memory) instead of numpy's
    MemoryError or the kernel's OOM killer."""
    _ndtrace.check_memory(float(nbytes), what)


def _umask() -> int:
    try:  # Linux ≥ 4.7 shows it without changing it
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def output_mode(path: str) -> int:
    """The permission bits an output written to ``path`` gets: those of the file it replaces,
    else what the umask leaves of 0666 (as any program's new file)."""
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        return 0o666 & ~_umask()


def output_temp(path: str, suffix: str) -> str:
    """A new empty temporary file beside ``path`` (a short name, whatever the length of
    ``path``'s, ending in ``suffix``: writers choose the format from it), to write and then
    hand to :func:`output_done`. A folder at ``path`` is an OSError, before any work."""
    if os.path.isdir(path):
        raise IsADirectoryError(f"{path}: cannot write: it is a folder")
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(prefix=".ndtrace-", suffix=suffix, dir=folder)
    os.close(fd)
    return tmp


def output_done(tmp: str, path: str) -> None:
    """Renames the written temporary file ``tmp`` over ``path``, with :func:`output_mode`."""
    os.chmod(tmp, output_mode(path))
    os.replace(tmp, path)


def c_array(a, dtype=None) -> np.ndarray:
    """``a`` as a C-ordered, aligned array of ``dtype`` (a copy only if needed), as the core
    reads arrays: pickled arrays (Dask, multiprocessing) can come back unaligned."""
    return np.require(a, dtype=dtype, requirements=["C_CONTIGUOUS", "ALIGNED"])


def finite_float64(name: str, value, min_ndim: int, shape_text: str) -> np.ndarray:
    """``value`` as a float64 array with at least ``min_ndim`` axes and finite entries."""
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name}: expected a float array of shape {shape_text}: {e}") from None
    if raw.dtype.kind not in "biuf":
        raise ValueError(
            f"{name}: expected real numbers (a float array of shape {shape_text}),"
            f" got dtype {raw.dtype}"
        )
    a = raw.astype(np.float64, copy=False)
    if a.ndim < min_ndim:
        raise ValueError(f"{name}: expected shape {shape_text}, got {a.shape}")
    if not np.all(np.isfinite(a)):
        bad = tuple(int(i) for i in np.argwhere(~np.isfinite(a))[0])
        raise ValueError(f"{name}: non-finite value {a[bad]} at index {bad}")
    return a


def broadcast_batch(args: list[tuple[str, np.ndarray, int]]) -> tuple[tuple, list[np.ndarray]]:
    """Broadcasts the leading (batch) axes; each entry is (name, array, number of core axes)."""
    leads = [a.shape[: a.ndim - core] for _, a, core in args]
    try:
        batch = np.broadcast_shapes(*leads)
    except ValueError:
        desc = ", ".join(f"{n} {a.shape}" for n, a, _ in args)
        raise ValueError(f"batch axes do not broadcast: {desc}") from None
    out = [
        np.ascontiguousarray(np.broadcast_to(a, batch + a.shape[a.ndim - core :]))
        for _, a, core in args
    ]
    return batch, out


def batch_size(batch: tuple) -> int:
    """The number of items of a batch shape (1 for ``()``)."""
    return int(np.prod(batch, dtype=np.int64))


def float32_array(name: str, value) -> np.ndarray:
    """``value`` (real numbers or booleans; NaN and inf allowed, as in a retina's depth) as a
    C-ordered float32 array for the compositor; a float64 value beyond float32's range is a
    ValueError (the cast would make it inf)."""
    a = np.asarray(value)
    if a.dtype == object or not (np.issubdtype(a.dtype, np.floating) or np.issubdtype(a.dtype, np.integer)
                                 or a.dtype == np.bool_):
        raise ValueError(f"{name}: expected a real numeric array, got dtype {a.dtype}")
    if a.dtype.kind == "f" and a.dtype.itemsize > 4:
        # Values beyond float32's range would become inf in the cast (NaN pictures).
        big = np.flatnonzero(np.isfinite(a) & (np.abs(a.astype(np.float64)) > np.finfo(np.float32).max))
        if big.size:
            raise ValueError(f"{name}: value {a.flat[big[0]]} at index {big[0]} overflows float32")
    return c_array(a, np.float32)


def picture_array(name: str, image) -> np.ndarray:
    """A picture ``(H, W, 4)`` of real numbers as a C-ordered float32 array with finite values."""
    a = np.asarray(image)
    if a.ndim != 3 or a.shape[2] != 4 or a.shape[0] == 0 or a.shape[1] == 0:
        raise ValueError(f"{name}: expected an image of shape (H, W, 4), got {a.shape}")
    if a.dtype.kind not in "biuf":
        raise ValueError(f"{name}: expected real numbers, got dtype {a.dtype}")
    # A float32 copy, the finiteness mask and the 8-bit pixels made from it.
    check_memory(a.shape[0] * a.shape[1] * 4 * (4 + 1 + 1 + 4.0),
                 f"{name}: a picture of {a.shape[1]} × {a.shape[0]} pixels")
    a = c_array(a, np.float32)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: the image holds NaN or infinite values")
    return a


def picture_pixels(name: str, image, transparent: bool) -> np.ndarray:
    """The 8-bit pixels of a picture: uint8 arrays as they are; real arrays are linear, as
    (H, W) grey, (H, W, 3) RGB or (H, W, 4) premultiplied RGBA, encoded as sRGB, RGBA as its
    colour over its background (opaque RGB) or, when ``transparent``, with straight alpha."""
    a = np.asarray(image)
    if not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] in (3, 4))) or 0 in a.shape[:2]:
        raise ValueError(f"{name}: expected an image of shape (H, W), (H, W, 3) or (H, W, 4), "
                         f"got {a.shape}")
    if a.dtype == np.uint8:
        return c_array(a)
    if a.ndim == 3 and a.shape[2] == 4:
        return _ndtrace.to_srgb8(picture_array(name, a), not transparent)
    if a.dtype.kind not in "biuf":
        raise ValueError(f"{name}: expected real numbers, got dtype {a.dtype}")
    rgb = a[..., None].repeat(3, axis=-1) if a.ndim == 2 else a
    rgba = np.concatenate([rgb, np.ones(rgb.shape[:2] + (1,), rgb.dtype)], axis=-1)
    out = _ndtrace.to_srgb8(picture_array(name, rgba), True)
    return np.ascontiguousarray(out[..., 0]) if a.ndim == 2 else out


def field_array(name: str, field) -> np.ndarray:
    """A 3D scalar field indexed ``[x, y, z]`` as a C-ordered float64 array (masked values
    NaN)."""
    f = np.asanyarray(field)
    if isinstance(f, np.ma.MaskedArray):
        f = np.ma.filled(f.astype(np.float64), np.nan)
    if f.dtype.kind not in "biuf":
        raise ValueError(f"{name}: expected a numeric 3D array, got dtype {f.dtype}")
    if f.ndim != 3:
        raise ValueError(f"{name}: expected a 3D array indexed [x, y, z], got {f.ndim} "
                         f"dimension{'s' if f.ndim != 1 else ''} (shape {f.shape})")
    return np.ascontiguousarray(f, dtype=np.float64)


def angle_degrees(angle) -> float:
    """An ``angle`` argument in degrees: a real number, not a bool."""
    if isinstance(angle, bool) or not isinstance(angle, numbers.Real):
        raise ValueError(f"angle: expected a number of degrees, got {angle!r}")
    return float(angle)
