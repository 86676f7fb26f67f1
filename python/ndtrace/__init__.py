"""ndtrace — N-dimensional ray tracing after Hanson's SIGGRAPH '98 course
"Computer Graphics beyond the Third Dimension".

``import ndtrace`` makes every submodule available, e.g. ``ndtrace.geometry``. It loads the
core (scenes, tracing, compositing, files, notebook pictures); the other submodules and their
names (``ndtrace.viewer``, ``ndtrace.animate``, ``ndtrace.frames`` …) load on first use.
"""

import importlib as _importlib
import os as _os
import sys as _sys
import typing as _typing


def _started_as_command() -> bool:
    """Whether this import is the start-up of the ``ndtrace`` command (or ``python -m ndtrace``)."""
    argv = getattr(_sys, "orig_argv", [])
    return _os.path.basename(_sys.argv[0] if _sys.argv else "") == "ndtrace" or any(
        argv[i : i + 2] == ["-m", "ndtrace"] for i in range(len(argv)))


def _interrupted_at_start_up(signum, frame) -> None:
    """Ctrl-C while the command is still starting (importing numpy, the extension, the command
    line's modules): exit as the command does when interrupted, without a traceback of the
    import machinery. ``ndtrace.cli.main`` hands SIGINT back to Python once its own handling
    is in place, so the whole start-up is covered, not only this module's imports.

    It exits at once (``os._exit``): nothing has been written yet, and an exception raised
    here could be turned into another one by the code it lands in (numpy's C import of
    ``datetime`` reports any failure as an ``ImportError``, traceback and all)."""
    _sys.stderr.write("\nndtrace: interrupted\n")
    _sys.stderr.flush()
    _os._exit(130)


if _started_as_command():
    import signal as _signal

    try:
        _signal.signal(_signal.SIGINT, _interrupted_at_start_up)
    except ValueError:  # not the main thread: leave the signal alone
        pass

try:
    from . import _ndtrace, geometry, mesh
    from ._ndtrace import InternalError, release_buffers
    from .composite import composite

    # display gives scenes and retinas their notebook pictures (Scene._repr_png_).
    from .display import show
    from .files import read_exr, write_exr, write_image, write_png
    from .retina import Retina, trace
    from .scene import Scene, load_dict, load_file, load_toml, slice_scene
except KeyboardInterrupt:
    # Ctrl-C before the handler above was installed.
    if not _started_as_command():
        raise
    _interrupted_at_start_up(None, None)

__version__: str = _ndtrace.__version__
MIN_DIM: int = _ndtrace.MIN_DIM
MAX_DIM: int = _ndtrace.MAX_DIM

__all__ = [
    "geometry", "rotation", "frames", "mesh", "surfaces", "visible_edges", "edge_segments", "Scene",
    "Retina", "trace", "release_buffers", "InternalError", "composite", "read_exr", "write_exr",
    "write_image", "write_png", "write_svg", "load_file", "load_dict", "load_toml", "slice_scene",
    "animation",
    "animate", "display", "show", "viewer", "widget", "MIN_DIM", "MAX_DIM", "__version__",
]

#: The names loaded on first use (PEP 562): name → (submodule, its attribute; None: the module).
_LAZY: dict[str, tuple[str, str | None]] = {
    **{m: (m, None) for m in ("animation", "edges", "frames", "rotation", "slicing", "surfaces", "svg",
                              "viewer")},
    "animate": ("animation", "animate"),
    "edge_segments": ("edges", "edge_segments"),
    "visible_edges": ("edges", "visible_edges"),
    "write_svg": ("svg", "write_svg"),
    "widget": ("viewer", "widget"),
}

if _typing.TYPE_CHECKING:  # the same names, for type checkers
    from . import animation, edges, frames, rotation, slicing, surfaces, svg, viewer  # noqa: F401 - not all in __all__
    from .animation import animate
    from .edges import edge_segments, visible_edges
    from .svg import write_svg
    widget = viewer.widget  # (mypy reads `from .viewer import widget` as a second definition)


def __getattr__(name: str):
    try:
        module, attribute = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    value = _importlib.import_module(f"{__name__}.{module}")
    if attribute is not None:
        value = getattr(value, attribute)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
