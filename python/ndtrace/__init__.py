"""ndtrace — N-dimensional ray tracing after Hanson's SIGGRAPH '98 course
"Computer Graphics beyond the Third Dimension".

``import ndtrace`` makes every submodule available, e.g. ``ndtrace.geometry``.
"""

import os as _os
import sys as _sys


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
    from . import (
        _ndtrace,
        animation,
        display,
        frames,
        geometry,
        mesh,
        rotation,
        surfaces,
        viewer,
    )
    from ._ndtrace import InternalError, release_buffers
    from .animation import animate
    from .composite import composite
    from .display import show
    from .edges import edge_segments, visible_edges
    from .files import read_exr, write_exr, write_image, write_png
    from .retina import Retina, trace
    from .scene import Scene, load_dict, load_file, load_toml
    from .svg import write_svg
    from .viewer import widget
except KeyboardInterrupt:
    # Ctrl-C before the handler above was installed.
    if not _started_as_command():
        raise
    _interrupted_at_start_up(None, None)

__version__: str = _ndtrace.__version__
MIN_DIM: int = _ndtrace.MIN_DIM
MAX_DIM: int = _ndtrace.MAX_DIM

__all__ = [
    "geometry", "rotation", "frames", "mesh", "surfaces", "visible_edges", "edge_segments", "Scene", "Retina", "trace", "release_buffers", "InternalError", "composite", "read_exr", "write_exr", "write_image", "write_png", "write_svg", "load_file", "load_dict", "load_toml", "animation", "animate",
    "display", "show", "viewer", "widget",
    "MIN_DIM", "MAX_DIM", "__version__",
]
