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


try:
    from . import _ndtrace
    from . import geometry
    from . import rotation
    from . import frames
    from . import mesh
    from . import surfaces
    from .retina import Retina, trace
    from ._ndtrace import InternalError, release_buffers
    from .composite import composite
    from .edges import edge_segments, visible_edges
    from .files import read_exr, write_exr, write_image, write_png
    from .svg import write_svg
    from .scene import Scene, load_dict, load_file, load_toml
    from . import animation
    from .animation import animate
    from . import display
    from .display import show
    from . import viewer
    from .viewer import widget
except KeyboardInterrupt:
    # Ctrl-C while the command is still importing (numpy, the extension): exit as the command
    # does when interrupted, without a traceback of the import machinery.
    if not _started_as_command():
        raise
    _sys.stderr.write("\nndtrace: interrupted\n")
    _sys.exit(130)

__version__: str = _ndtrace.__version__
MIN_DIM: int = _ndtrace.MIN_DIM
MAX_DIM: int = _ndtrace.MAX_DIM

__all__ = [
    "geometry", "rotation", "frames", "mesh", "surfaces", "visible_edges", "edge_segments", "Scene", "Retina", "trace", "release_buffers", "InternalError", "composite", "read_exr", "write_exr", "write_image", "write_png", "write_svg", "load_file", "load_dict", "load_toml", "animation", "animate",
    "display", "show", "viewer", "widget",
    "MIN_DIM", "MAX_DIM", "__version__",
]
