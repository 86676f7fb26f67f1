"""ndtrace — N-dimensional ray tracing after Hanson's SIGGRAPH '98 course
"Computer Graphics beyond the Third Dimension".

``import ndtrace`` makes every submodule available, e.g. ``ndtrace.geometry``.
"""

from . import _ndtrace
from . import geometry
from . import rotation
from . import frames
from . import mesh
from .retina import Retina, trace
from ._ndtrace import release_buffers
from .composite import composite
from .edges import edge_segments, visible_edges
from .files import read_exr, write_exr, write_image, write_png
from .svg import write_svg
from .scene import Scene, load_dict, load_file, load_toml
from . import animation
from .animation import animate

__version__: str = _ndtrace.__version__
MIN_DIM: int = _ndtrace.MIN_DIM
MAX_DIM: int = _ndtrace.MAX_DIM

__all__ = [
    "geometry", "rotation", "frames", "mesh", "visible_edges", "edge_segments", "Scene", "Retina", "trace", "release_buffers", "composite", "read_exr", "write_exr", "write_image", "write_png", "write_svg", "load_file", "load_dict", "load_toml", "animation", "animate",
    "MIN_DIM", "MAX_DIM", "__version__",
]
