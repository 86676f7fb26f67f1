"""Type stubs of the compiled extension. Use the ``ndtrace`` package, not this module."""

from types import ModuleType

import numpy as np
import numpy.typing as npt

__version__: str
MIN_DIM: int
MAX_DIM: int

_F = npt.NDArray[np.float64]

class _GeometryKernels(ModuleType):
    """Flat C-contiguous float64 kernels behind ``ndtrace.geometry``."""

    def generalized_cross(self, dim: int, batch: int, edges: _F) -> _F: ...
    def signed_volume(self, dim: int, batch: int, points: _F) -> _F: ...
    def gram_volume(self, dim: int, k: int, batch: int, points: _F) -> _F: ...
    def hyperplane(self, dim: int, batch: int, points: _F, raise_degenerate: bool) -> _F: ...
    def point_hyperplane_distance(
        self, dim: int, batch: int, x: _F, points: _F, raise_degenerate: bool
    ) -> _F: ...
    def barycentric(
        self, dim: int, k: int, batch: int, x: _F, points: _F, raise_degenerate: bool
    ) -> _F: ...
    def side(self, dim: int, batch: int, x: _F, points: _F) -> _F: ...
    def clip_segment(
        self, dim: int, batch: int, a: _F, b: _F, points: _F, raise_degenerate: bool
    ) -> _F: ...
    def ray_hyperplane(
        self, dim: int, batch: int, origin: _F, direction: _F, points: _F, raise_degenerate: bool
    ) -> _F: ...
    def transform_normal(self, dim: int, batch: int, matrix: _F, normal: _F) -> _F: ...

geometry: _GeometryKernels
