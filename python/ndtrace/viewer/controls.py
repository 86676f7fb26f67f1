"""The viewer's controllers as functions of the mouse: the rolling ball, the 4D arcball, the
compositing camera's orbit, snapping to axis views, and the object rotation as a scene step.

Every rotation is an N×N matrix acting on column vectors; the current object rotation R turns
every object about the view's centre c (``x ↦ R(x − c) + c``, after each object's own
``transform`` steps). Mouse displacements are in **picture pixels** (the composite's pixels,
whatever size the page shows them at), x to the right and y down the picture.

* **Rolling ball** (course notes, Part I(B), eq. 5; :func:`ndtrace.rotation.rolling_ball`): a
  drag step (dx, dy) is the controller displacement ``d = (dx, −dy, 0, …, 0)`` in the first
  N − 1 axes with the ball's radius R in pixels, so the hidden last axis turns toward the drag:
  a drag along the picture's x turns the object in the (x, N−1) plane, along y in the
  (y, N−1) plane (x–w and y–w for N = 4). Each step's M is composed after the rotation so far,
  ``R ← M R``, so a drag of steps M_1 … M_k gives ``M_k ⋯ M_1 R`` and small loops show the
  commutator: a small counterclockwise loop on the screen turns the object clockwise in its
  (x, y) plane (the course: controller loops produce counter-rotations).
* **4D arcball** (Shoemake's arcball on S³, eq. 10; :func:`ndtrace.rotation.arcball_4d`): the
  picture's disk of radius ``min(W, H)/2`` is a ball; a mouse point maps to Shoemake's point s
  on its unit sphere (x right, y up, z toward the viewer; outside the disk, on the rim), read
  as the pure quaternion ``(0, s)``. Quaternion coordinates are ``(w, x, y, z)`` of the world
  (the scalar part is the hidden axis w, :data:`QUATERNION_FROM_WORLD`). A drag from press point
  a0 to a1 is ``arcball_4d(a0, a1, 1, 1)`` (the left factor q = a1 ā0, a left-isoclinic
  rotation); with ctrl (or the right button) it is ``arcball_4d(1, 1, a0, a1)`` (the right
  factor). The same drag done both ways composes to Shoemake's 3D arcball of x, y, z with w
  fixed. Within one drag the rotation is absolute: ``R = A(press, now) R_press``.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from .. import rotation

__all__ = [
    "ORBIT_DEGREES_PER_PIXEL", "QUATERNION_FROM_WORLD", "roll", "roll_displacement",
    "arcball_point", "arcball", "orbit", "snap", "transform_step", "check_rotation",
]

#: Degrees of azimuth (elevation) per picture pixel of a shift-drag along x (y).
ORBIT_DEGREES_PER_PIXEL: float = 0.4

#: The permutation taking world (x, y, z, w) to quaternion coordinates (w, x, y, z): the
#: arcball's quaternions have the hidden axis w as their scalar part.
QUATERNION_FROM_WORLD: np.ndarray = np.array(
    [[0, 0, 0, 1], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], dtype=float)

_ONE = np.array([1.0, 0.0, 0.0, 0.0])


def roll_displacement(dim: int, dx: float, dy: float) -> np.ndarray:
    """The rolling ball's controller displacement ``(dx, −dy, 0, …)`` (N − 1 numbers) of a
    drag step of (dx, dy) picture pixels."""
    d = np.zeros(dim - 1)
    d[0] = dx
    if dim > 2:
        d[1] = -dy
    return d


def roll(current: np.ndarray, steps, radius: float) -> np.ndarray:
    """The rotation after the drag ``steps`` [(dx, dy), …] (picture pixels) of the rolling ball
    of ``radius`` pixels: ``M_k ⋯ M_1 current`` with ``M_i = rolling_ball(d_i, radius)``."""
    dim = current.shape[0]
    steps = [(float(dx), float(dy)) for dx, dy in steps]
    if not steps:
        return current
    ms = rotation.rolling_ball(np.array([roll_displacement(dim, dx, dy) for dx, dy in steps]),
                               radius=radius)
    return rotation.compose(np.concatenate([current[None], ms]))


def arcball_point(x: float, y: float, width: int, height: int) -> np.ndarray:
    """Shoemake's point of picture pixel (x, y) on the arcball of the picture's disk, as the
    pure unit quaternion ``(0, s_x, s_y, s_z)``."""
    r = min(width, height) / 2.0
    u = np.array([(x - width / 2.0) / r, (height / 2.0 - y) / r])
    n2 = float(u @ u)
    if n2 <= 1.0:
        s = np.array([u[0], u[1], math.sqrt(1.0 - n2)])
    else:
        s = np.array([u[0], u[1], 0.0]) / math.sqrt(n2)
    return np.concatenate([[0.0], s])


def arcball(press_rotation: np.ndarray, a0: np.ndarray, a1: np.ndarray, right: bool = False) -> np.ndarray:
    """The 4D arcball's rotation after a drag from quaternion point ``a0`` to ``a1`` (see the
    module doc): ``Pᵀ arcball_4d(a0, a1, 1, 1) P · press_rotation`` (the right factor
    ``arcball_4d(1, 1, a0, a1)`` when ``right``), P = :data:`QUATERNION_FROM_WORLD`."""
    a = rotation.arcball_4d(_ONE, _ONE, a0, a1) if right else rotation.arcball_4d(a0, a1, _ONE, _ONE)
    p = QUATERNION_FROM_WORLD
    return rotation.compose(np.stack([press_rotation, p.T @ a @ p]))


def orbit(azimuth: float, elevation: float, dx: float, dy: float) -> tuple[float, float]:
    """The compositing camera's angles after a shift-drag of (dx, dy) pixels: dragging right
    swings the eye right (azimuth up), dragging down raises it (elevation up, kept in
    [−90°, 90°])."""
    az = (azimuth + dx * ORBIT_DEGREES_PER_PIXEL + 180.0) % 360.0 - 180.0
    el = min(90.0, max(-90.0, elevation + dy * ORBIT_DEGREES_PER_PIXEL))
    return az, el


def snap(current: np.ndarray) -> np.ndarray:
    """The axis view nearest to ``current``: the signed permutation matrix with det +1 that
    maximizes trace(Sᵀ R), i.e. is nearest in the Frobenius norm (every permutation tried)."""
    n = current.shape[0]
    perms = np.array(list(itertools.permutations(range(n))))
    rows = np.arange(n)
    picked = current[rows[None, :], perms]  # picked[k, i] = R[i, π_k(i)]
    mags = np.abs(picked)
    signs = np.where(picked < 0, -1.0, 1.0)
    # det of the signed permutation: parity of π times the product of the signs.
    inversions = (perms[:, :, None] > perms[:, None, :]) & (rows[:, None] < rows[None, :])[None]
    parity = np.where(inversions.sum(axis=(1, 2)) % 2 == 0, 1.0, -1.0)
    det = parity * signs.prod(axis=1)
    score = mags.sum(axis=1) - np.where(det < 0, 2.0 * mags.min(axis=1), 0.0)
    k = int(np.argmax(score))
    s = signs[k].copy()
    if det[k] < 0:
        s[int(np.argmin(mags[k]))] *= -1.0
    out = np.zeros((n, n))
    out[rows, perms[k]] = s
    return out


def transform_step(current: np.ndarray, center: np.ndarray) -> dict:
    """The scene ``transform`` step of the rotation ``current`` about ``center``:
    ``{matrix = R}`` (N×N) about the origin, else the affine ``x ↦ R(x − c) + c``
    ((N+1)×(N+1), last row [0, …, 0, 1])."""
    if not np.any(center):
        return {"matrix": current.tolist()}
    n = current.shape[0]
    affine = np.eye(n + 1)
    affine[:n, :n] = current
    affine[:n, n] = center - current @ center
    return {"matrix": affine.tolist()}


def check_rotation(value, dim: int) -> np.ndarray:
    """``value`` (a matrix typed into the page: entries rounded to a few digits) as a dim×dim
    rotation: it must be orthonormal to :data:`ndtrace.rotation.SCENE_UNIT_TOLERANCE` (1e-3,
    the tolerance of hand-typed scene quaternions) with det +1, and is then replaced by the
    nearest exact rotation (the orthogonal factor of its polar decomposition). Else ValueError
    naming ``rotation``."""
    try:
        m = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"rotation: expected {dim} rows of {dim} numbers") from None
    if m.shape != (dim, dim):
        raise ValueError(f"rotation: expected a {dim}×{dim} matrix, got shape {m.shape}")
    if not np.all(np.isfinite(m)):
        raise ValueError("rotation: the matrix holds NaN or infinite entries")
    error = float(np.max(np.abs(m.T @ m - np.eye(dim))))
    if error > rotation.SCENE_UNIT_TOLERANCE:
        raise ValueError(f"rotation: not orthonormal: RᵀR differs from I by {error:.3g} "
                         f"(tolerance {rotation.SCENE_UNIT_TOLERANCE:g})")
    if np.linalg.det(m) < 0:
        raise ValueError("rotation: det −1: a reflection, not a rotation")
    u, _, vt = np.linalg.svd(m)
    return rotation.compose((u @ vt)[None])
