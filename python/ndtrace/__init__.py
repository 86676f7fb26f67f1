"""ndtrace — N-dimensional ray tracing after Hanson's SIGGRAPH '98 course
"Computer Graphics beyond the Third Dimension".

``import ndtrace`` makes every submodule available, e.g. ``ndtrace.geometry``.
"""

from . import _ndtrace
from . import geometry

__version__: str = _ndtrace.__version__
MIN_DIM: int = _ndtrace.MIN_DIM
MAX_DIM: int = _ndtrace.MAX_DIM

__all__ = ["geometry", "MIN_DIM", "MAX_DIM", "__version__"]
