"""Type stubs of the compiled extension. Use the ``ndtrace`` package, not this module."""

from types import ModuleType
from typing import Callable

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

# -- scenes and tracing ---------------------------------------------------------------

class CompiledScene:
    """A validated scene with its BVH, built once and reused by every trace."""

    @property
    def dim(self) -> int: ...
    @property
    def warnings(self) -> list[str]: ...
    @property
    def retina_shape(self) -> list[int]: ...
    @property
    def camera_orientation(self) -> list[list[float]]: ...
    def bvh_stats(self) -> tuple[int, int, int]: ...
    def camera_toml(self) -> str: ...
    def to_toml(self) -> str: ...
    def to_dict(self) -> dict: ...
    def same_description(self, other: CompiledScene) -> bool: ...
    def trace(
        self, threads: int | None = None, callback: Callable[[int, int], object] | None = None
    ) -> dict[str, object]: ...

def load_file(path: str) -> CompiledScene: ...
def load_toml(text: str, name: str = "<string>", base: str | None = None) -> CompiledScene: ...
def load_dict(data: object, name: str = "<dict>", base: str | None = None) -> CompiledScene: ...

# -- files ----------------------------------------------------------------------------

def write_retina_exr(
    path: str,
    dim: int,
    shape: list[int],
    rgba: npt.NDArray[np.float32],
    depth: npt.NDArray[np.float32],
    normal: npt.NDArray[np.float32],
    object_id: npt.NDArray[np.int32],
    primitive_id: npt.NDArray[np.int64],
    camera: str | None = None,
) -> None: ...
def write_picture_exr(
    path: str, rgba: npt.NDArray[np.float32], depth: npt.NDArray[np.float32] | None = None
) -> None: ...
def write_png(path: str, rgba: npt.NDArray[np.float32]) -> None: ...
def read_exr(path: str) -> dict[str, object]: ...

# -- compositing ----------------------------------------------------------------------

def composite(
    rgba: npt.NDArray[np.float32],
    depth: npt.NDArray[np.float32] | None = None,
    *,
    mode: str = "volume",
    azimuth: float = 30.0,
    elevation: float = 20.0,
    distance: float = ...,
    zoom: float = 1.0,
    projection: str = "perspective",
    size: tuple[int, int] = (512, 512),
    opacity: float = 1.0,
    step: float = 0.5,
    depth_cue: float = 0.0,
    axis: int = 0,
    background: tuple[float, float, float] = (0.0, 0.0, 0.0),
    stages: list[tuple[float, float]] | None = None,
    strip_height: int = 32,
    labels: bool = True,
    threads: int | None = None,
) -> npt.NDArray[np.float32]: ...
