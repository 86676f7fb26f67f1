"""Curve frames, quaternion frames and tubes (course notes, Part II(A) "Quaternion Frames", and
Part II(B) "Extensions to 4D rendering": a wire is made visible by attaching a tube).

A frame along a sampled curve ``points`` (n, 3) is three (n, 3) arrays ``T, N, B``: unit tangent,
normal and binormal, right-handed (``B = T × N``). They obey the classical moving-frame equations
(notes, "3D Curves: Frenet and PT Frames")::

    T' =         k1 N + k2 B
    N' = −k1 T         + σ B
    B' = −k2 T − σ N

Frenet: ``k2 = 0, k1 = κ, σ = τ`` (local, undefined where κ = 0). Parallel transport (Bishop):
``σ = 0`` (an integral along the curve: it does not close on a closed curve). The frame as a
rotation matrix has columns ``[T N B]``; its quaternion ``q`` (``R(q)`` of eq. 9, columns T, N, B)
traces a curve on S³ obeying Tait's equation ``q' = ½ A(k1, k2, σ) q`` (:func:`tait`).

Conventions
-----------
* Curves are sampled; "open" (the default) or ``closed=True``: the last point joins the first,
  and the first point is *not* repeated at the end (that is an error).
* Derivatives are central differences treating samples as equally spaced in the parameter
  (second-order one-sided differences at the ends of an open curve); only directions are used,
  so the parameter speed does not matter for ``T``, ``N``, ``B``.
* Arclength ``s`` is the cumulative chord length (:func:`arclength`).
* Every function validates its input and raises ValueError naming the argument. Unit
  quaternions and orthonormal frames are checked with the tolerances of ``ndtrace.rotation``
  (``UNIT_TOLERANCE``, ``ORTHOGONALITY_TOLERANCE``, 1e-9: they are computed values).

Surface frames (notes, "3-Manifold of Frames for a Patch": "for surfaces, we simply replace a
curve's tangent by a surface's normal"): :func:`surface_frames` gives, for a sampled patch
(U, V, 3), unit quaternions (U, V, 4) of frames whose third axis is the surface normal, by
geodesic reference, parallel transport along one edge then across, or the course's "optimal
quaternion frame on a patch" (the quaternion patch of least area in S³);
:func:`quaternion_patch` turns them into a triangulated surface of R⁴ for ``shape =
"surface"``.

Example (the (3, 5) torus knot with its closed minimal-length quaternion frame, as a tube)::

    import ndtrace.frames as fr
    points = fr.torus_knot(3, 5, 400)
    T, N, B = fr.optimal_periodic(points)
    vertices, triangles = fr.tube_3d(points, T, N, B, radius=0.08, closed=True)
"""

from __future__ import annotations

import numbers
from collections.abc import Callable
from typing import Literal

import numpy as np

from . import _ndtrace, geometry
from ._util import finite_float64
from .rotation import (
    frame,
    matrix_to_quat,
    quat_conjugate,
    quat_multiply,
    quat_to_matrix,
    rotation_between,
    slerp,
)

_k = _ndtrace.rotation

__all__ = [
    "tangents", "arclength", "minimal_rotation",
    "frenet", "parallel_transport", "geodesic_reference", "optimal_periodic",
    "frame_quaternions", "quaternion_length", "quaternion_loop",
    "tait_matrix", "tait", "frame_curvatures", "twist_angles",
    "torus_knot", "icosphere", "tube_3d", "tube_4d",
    "surface_normals", "surface_frames", "quaternion_patch", "patch_area", "smooth_patch",
    "spherical_patch",
]

#: a unit tangent whose change over two samples is below this has zero curvature (Frenet)
CURVATURE_TOL = 1e-8
#: 1 + a·b below this: a and b are antiparallel, the minimal rotation is undefined
ANTIPARALLEL_TOL = 1e-10


# -- input checks -------------------------------------------------------------------------------
def _curve(name: str, points, dims: tuple[int, ...] | None = (3,), closed: bool = False) -> np.ndarray:
    """A finite float64 (n, N) array with n ≥ 3, N in dims, no repeated consecutive points."""
    try:
        p = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a real (n, N) array") from None
    shape_text = "(n, " + ("N" if dims is None else "|".join(map(str, dims))) + ")"
    if p.ndim != 2 or (dims is not None and p.shape[1] not in dims) or p.shape[1] < 2:
        raise ValueError(f"{name}: expected shape {shape_text}, got {p.shape}")
    if p.shape[0] < 3:
        raise ValueError(f"{name}: need at least 3 samples, got {p.shape[0]}")
    if not np.all(np.isfinite(p)):
        raise ValueError(f"{name}: sample {int(np.argwhere(~np.isfinite(p))[0, 0])} is not finite")
    step = np.linalg.norm(np.diff(p, axis=0), axis=1)
    scale = max(float(np.abs(p).max()), 1e-300)
    if np.any(step <= 1e-14 * scale):
        i = int(np.argmax(step <= 1e-14 * scale))
        raise ValueError(f"{name}: samples {i} and {i + 1} coincide")
    if closed and np.linalg.norm(p[-1] - p[0]) <= 1e-14 * scale:
        raise ValueError(f"{name}: a closed curve must not repeat its first point at the end "
                         f"(drop the last sample)")
    return p


def _frame(T, N, B) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Checks T, N, B are finite (n, 3) and that every [T_i N_i B_i] (columns) is a rotation —
    orthonormal and right-handed, B = T × N — with the check of ``ndtrace.rotation``."""
    arrays = []
    for name, a in (("T", T), ("N", N), ("B", B)):
        a = finite_float64(name, a, 2, "(n, 3)")
        if a.ndim != 2 or a.shape[1] != 3 or a.shape[0] < 2:
            raise ValueError(f"{name}: expected shape (n, 3) with n ≥ 2, got {a.shape}")
        arrays.append(a)
    T, N, B = arrays
    if not T.shape == N.shape == B.shape:
        raise ValueError(f"T, N, B: shapes differ: {T.shape}, {N.shape}, {B.shape}")
    R = np.ascontiguousarray(np.stack([T, N, B], axis=-1))
    try:
        _k.check_rotations("T, N, B", 3, R.reshape(-1))
    except ValueError as e:
        raise ValueError(f"{e} (each frame [T N B] must be orthonormal and right-handed, "
                         f"B = T × N)") from None
    return T, N, B


def _quaternions(name: str, q) -> np.ndarray:
    """A finite float64 (n, 4) array of unit quaternions (``rotation.UNIT_TOLERANCE``), n ≥ 2."""
    q = finite_float64(name, q, 2, "(n, 4)")
    if q.ndim != 2 or q.shape[1] != 4 or q.shape[0] < 2:
        raise ValueError(f"{name}: expected shape (n, 4) with n ≥ 2, got {q.shape}")
    _k.check_units(name, np.ascontiguousarray(q).reshape(-1), 4, "quaternion")
    return q


def _positive(name: str, value) -> float:
    # (np.isfinite refuses some Reals, e.g. a Fraction, with a TypeError; numpy's stubs say so.)
    if isinstance(value, bool) or not isinstance(value, numbers.Real) \
            or not np.isfinite(value) or value <= 0:  # type: ignore[call-overload]
        raise ValueError(f"{name}: expected a finite number > 0, got {value!r}")
    return float(value)


def _count(name: str, value, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or not low <= int(value) < 2**32:
        raise ValueError(f"{name}: expected an integer in {low}..{2**32 - 1}, got {value!r}")
    return int(value)


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


# -- tangents, arclength, the minimal rotation ---------------------------------------------------
def _difference(x: np.ndarray, closed: bool) -> np.ndarray:
    """Central differences x_{i+1} − x_{i−1} (wrapping when closed; second-order one-sided
    −3x_0 + 4x_1 − x_2 and its mirror at the ends of an open curve)."""
    if closed:
        return np.roll(x, -1, axis=0) - np.roll(x, 1, axis=0)
    d = np.empty_like(x)
    d[1:-1] = x[2:] - x[:-2]
    d[0] = -3 * x[0] + 4 * x[1] - x[2]
    d[-1] = 3 * x[-1] - 4 * x[-2] + x[-3]
    return d


def tangents(points, closed: bool = False) -> np.ndarray:
    """Unit tangents (n, N) of a sampled curve (n, N), any N ≥ 2: the central difference
    ``p_{i+1} − p_{i−1}`` normalized (see the module conventions). A zero difference (the curve
    doubles back on itself over two samples) is a ValueError naming the sample."""
    p = _curve("points", points, None, closed)
    d = _difference(p, closed)
    length = np.linalg.norm(d, axis=1)
    bad = length <= 1e-12 * np.abs(p).max()
    if np.any(bad):
        raise ValueError(f"points: the tangent at sample {int(np.argmax(bad))} is undefined "
                         f"(the curve doubles back)")
    return d / length[:, None]


def arclength(points, closed: bool = False) -> np.ndarray:
    """Cumulative chord length: (n,) with s_0 = 0 for an open curve; (n + 1,) for a closed one,
    whose last entry is the total length L (the return to the first point)."""
    p = _curve("points", points, None, closed)
    if closed:
        p = np.concatenate([p, p[:1]])
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])


def minimal_rotation(a, b, v) -> np.ndarray:
    """Applies the minimal rotation taking unit vector ``a`` to unit vector ``b`` (the rotation in
    the plane of a and b, fixing its orthogonal complement; any dimension N in 2..8) to ``v``:
    ``rotation.rotation_between(a, b) @ v``, i.e.::

        R v = v − (a + b)·((a + b)·v)/(1 + a·b) + 2 b (a·v)

    ``a``, ``b``, ``v`` are (..., N) with the same N; their leading axes broadcast. This is the
    discrete parallel-transport step ("rotate the previous frame by the rotation taking T_i to
    T_{i+1}") and, with a fixed ``a``, the course's geodesic reference ``R(ẑ·T̂, ẑ × T̂)``.
    Antiparallel a, b (``1 + a·b ≤ ANTIPARALLEL_TOL``), where the minimal rotation is not
    unique: ValueError."""
    a, b = finite_float64("a", a, 1, "(..., N)"), finite_float64("b", b, 1, "(..., N)")
    v = finite_float64("v", v, 1, "(..., N)")
    if not a.shape[-1] == b.shape[-1] == v.shape[-1]:
        raise ValueError(f"a, b, v: expected vectors of the same length N, got shapes "
                         f"{a.shape}, {b.shape}, {v.shape}")
    R = rotation_between(a, b)  # checks that a and b are unit vectors, names them
    bad = 1.0 + np.sum(a * b, axis=-1) <= ANTIPARALLEL_TOL
    if np.any(bad):
        where = "" if bad.ndim == 0 else f" at index {tuple(int(i) for i in np.argwhere(bad)[0])}"
        raise ValueError(f"a, b: antiparallel{where}; the minimal rotation is undefined")
    try:
        return np.matmul(R, v[..., None])[..., 0]
    except ValueError:
        raise ValueError(f"a, b, v: batch axes do not broadcast: a {a.shape}, b {b.shape}, "
                         f"v {v.shape}") from None


def _transport(T: np.ndarray, F0: np.ndarray) -> np.ndarray:
    """Parallel transport of the vectors F0 (K, N) (orthogonal to T_0) along unit tangents T
    (n, N): F_{i+1} = minimal_rotation(T_i, T_{i+1}, F_i), re-orthonormalized against T_{i+1}
    (Gram–Schmidt) so that round-off does not accumulate. Returns (n, K, N)."""
    n = len(T)
    nearly_opposite = 1.0 + np.sum(T[:-1] * T[1:], axis=1) <= ANTIPARALLEL_TOL
    if np.any(nearly_opposite):
        i = int(np.argmax(nearly_opposite))
        raise ValueError(f"points: tangents {i} and {i + 1} are antiparallel; "
                         f"parallel transport is undefined there")
    steps = rotation_between(T[:-1], T[1:])  # (n − 1, N, N), all at once
    F = np.empty((n,) + F0.shape)
    F[0] = F0
    for i in range(n - 1):
        f = F[i] @ steps[i].T  # rows F_i,k rotated
        for k in range(len(f)):  # Gram–Schmidt against T_{i+1} and the vectors before
            f[k] -= np.dot(f[k], T[i + 1]) * T[i + 1] + f[:k].T @ (f[:k] @ f[k])
            f[k] /= np.linalg.norm(f[k])
        F[i + 1] = f
    return F


# -- frames ----------------------------------------------------------------------------------------
def frenet(points, closed: bool = False, on_zero_curvature: Literal["raise", "nan"] = "raise"):
    """Serret–Frenet frame: T the unit tangent, N the unit part of dT/ds orthogonal to T (central
    differences of the unit tangents), B = T × N (course: k2 = 0, k1 = κ, σ = τ; LOCAL).

    Where the curvature vanishes — the tangent changes by less than ``CURVATURE_TOL`` over two
    samples, e.g. on a straight piece or at an inflection — N is undefined: ValueError naming the
    first such sample (``on_zero_curvature="raise"``), or NaN in N and B there (``"nan"``)."""
    if on_zero_curvature not in ("raise", "nan"):
        raise ValueError(f"on_zero_curvature: expected 'raise' or 'nan', got {on_zero_curvature!r}")
    p = _curve("points", points, (3,), closed)
    T = tangents(p, closed)
    dT = _difference(T, closed)
    dT -= np.sum(dT * T, axis=1, keepdims=True) * T
    size = np.linalg.norm(dT, axis=1)
    flat = size <= CURVATURE_TOL
    if np.any(flat) and on_zero_curvature == "raise":
        raise ValueError(f"frenet: the curvature vanishes at sample {int(np.argmax(flat))}; "
                         f"the Frenet normal is undefined there (use parallel_transport)")
    N = np.where(flat[:, None], np.nan, dT / np.where(flat, 1.0, size)[:, None])
    return T, N, np.cross(T, N)


def parallel_transport(points, closed: bool = False, normal=None):
    """Bishop's parallel-transport frame (σ = 0, "minimal turning"): N_{i+1} is N_i rotated by the
    minimal rotation taking T_i to T_{i+1}. ``normal`` (3,) is the starting normal, orthogonalized
    against T_0 (it must not be parallel to T_0); by default the coordinate axis least aligned
    with T_0. On a closed curve (tangents wrap) the frame is transported from sample 0 to n − 1
    and does not in general close: see :func:`optimal_periodic` and :func:`twist_angles`."""
    p = _curve("points", points, (3,), closed)
    T = tangents(p, closed)
    if normal is None:
        n0 = frame(T[:1])[:, 1]  # the coordinate axis least aligned with T_0, orthogonalized
    else:
        v = finite_float64("normal", normal, 1, "(3,)")
        if v.shape != (3,):
            raise ValueError(f"normal: expected 3 finite numbers, got shape {v.shape}")
        w = v - np.dot(v, T[0]) * T[0]
        if np.linalg.norm(w) <= 1e-8 * np.linalg.norm(v):
            raise ValueError("normal: must not be parallel to (or zero) the first tangent")
        n0 = _unit(w)
    N = _transport(T, n0[None, :])[:, 0]
    return T, N, np.cross(T, N)


def geodesic_reference(points, reference=None, closed: bool = False):
    """The course's geodesic reference frame ("Geometric Construction of Space of Frames"): at
    each sample the frame is the fixed reference frame turned by ``R(ẑ·T̂, ẑ × T̂)``, the minimal
    rotation taking the reference direction ẑ (default (0, 0, 1)) to T̂. The reference frame is
    (ẑ, x̂, ŷ) for ẑ = (0, 0, 1) — so N = R x̂, B = R ŷ — and in general (ẑ, e, ẑ × e) with e the
    axis least aligned with ẑ, orthogonalized. LOCAL, but undefined where T̂ = −ẑ (ValueError
    naming the sample: choose another reference)."""
    p = _curve("points", points, (3,), closed)
    T = tangents(p, closed)
    z = np.array([0.0, 0.0, 1.0]) if reference is None else finite_float64("reference", reference, 1, "(3,)")
    if z.shape != (3,) or not np.linalg.norm(z) > 0:
        raise ValueError(f"reference: expected a finite non-zero 3-vector, got {reference!r}")
    z = z / np.linalg.norm(z)
    e = frame(z[None])[:, 1]  # (ẑ, e, ẑ × e) = frame([ẑ]); e = x̂ for ẑ = (0, 0, 1)
    bad = 1.0 + T @ z <= ANTIPARALLEL_TOL
    if np.any(bad):
        raise ValueError(f"reference: the tangent at sample {int(np.argmax(bad))} is "
                         f"opposite to the reference direction; choose another reference")
    N = minimal_rotation(z, T, e)
    return T, N, np.cross(T, N)


def twist_angles(T, N, B, closed: bool = False) -> np.ndarray:
    """The twist of a frame relative to parallel transport, per segment: the signed angle about
    T_{i+1} from N_i transported to sample i + 1 (:func:`minimal_rotation`) to N_{i+1}.
    (n − 1,) for an open curve; (n,) when closed, the last entry being the seam n − 1 → 0.
    Zero for parallel transport except at the seam, where it is minus the holonomy."""
    T, N, B = _frame(T, N, B)
    nxt = np.roll(np.arange(len(T)), -1)[: len(T) if closed else len(T) - 1]
    cur = np.arange(len(nxt))
    moved = minimal_rotation(T[cur], T[nxt], N[cur])
    return np.arctan2(np.sum(np.cross(moved, N[nxt]) * T[nxt], axis=1), np.sum(moved * N[nxt], axis=1))


def optimal_periodic(points, method: Literal["quaternion", "arclength"] = "quaternion", normal=None):
    """A closed frame for a closed curve: the parallel-transport frame (T, N⁰, B⁰) turned by φ_i
    about the tangent, N_i = cos φ_i N⁰_i + sin φ_i B⁰_i, with the twists Δ_i = φ_{i+1} − φ_i of
    all n segments (the seam n − 1 → 0 included) adding up to the parallel transport's closure
    defect Φ (minus the holonomy angle, wrapped to (−π, π]) so the frame closes.

    ``method="quaternion"`` (default) minimizes the quaternion length Σ arccos|⟨q_i, q_{i+1}⟩|
    (course: "Minimizing Quaternion Length Solves Periodic Tube"). Between neighbouring frames the
    rotation is the minimal rotation by θ_i (the angle between T_i and T_{i+1}, about an axis ⊥
    both) followed by the twist Δ_i about T_{i+1}, so ⟨q_i, q_{i+1}⟩ = cos(θ_i/2)·cos(Δ_i/2)
    exactly. Each term arccos(cos(θ_i/2) cos(Δ_i/2)) is convex in Δ_i, and the Lagrange condition
    of ``min Σ_i arccos(cos(θ_i/2)cos(Δ_i/2))  s.t.  Σ_i Δ_i = Φ`` gives the closed form

        sin(Δ_i/2) = μ·tan(θ_i/2)

    with one scalar μ found by bisection (Σ Δ_i is increasing in μ): the twist goes where the
    tangent turns (≈ proportional to θ_i), none on straight pieces.

    ``method="arclength"`` spreads Φ linearly in arclength (Δ_i = Φ·ℓ_i/L), the simple
    correction; it also closes, and its quaternion length is never smaller.

    ``normal`` is the starting normal as in :func:`parallel_transport` (φ_0 = 0)."""
    if method not in ("quaternion", "arclength"):
        raise ValueError(f"method: expected 'quaternion' or 'arclength', got {method!r}")
    p = _curve("points", points, (3,), closed=True)
    T, N0, B0 = parallel_transport(p, closed=True, normal=normal)
    # 1. The closure defect Φ: the seam twist of parallel transport, wrapped to (−π, π].
    seam = twist_angles(T, N0, B0, closed=True)[-1]
    phi_total = float(np.angle(np.exp(1j * seam)))
    # 2. Distribute it over the n segments.
    if method == "arclength":
        s = arclength(p, closed=True)
        delta = phi_total * np.diff(s) / s[-1]
    else:
        nxt = np.roll(T, -1, axis=0)
        theta = np.arctan2(np.linalg.norm(np.cross(T, nxt), axis=1), np.sum(T * nxt, axis=1))
        tan_half = np.tan(theta / 2)

        def total(mu: float) -> float:
            return float(np.sum(2 * np.arcsin(np.clip(mu * tan_half, -1.0, 1.0))))

        hi = 1.0 / tan_half.max()  # Σ Δ_i(hi) ≥ π ≥ |Φ|: the root lies in [−hi, hi]
        lo, hi = -hi, hi
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if total(mid) < phi_total else (lo, mid)
        delta = 2 * np.arcsin(np.clip(0.5 * (lo + hi) * tan_half, -1.0, 1.0))
    # 3. Turn the transported frame by φ_i (the seam's twist is what is left: Φ − Σ_{i<n−1} Δ_i).
    phi = np.concatenate([[0.0], np.cumsum(delta[:-1])])[:, None]
    N = np.cos(phi) * N0 + np.sin(phi) * B0
    return T, N, np.cross(T, N)


# -- quaternion frames -------------------------------------------------------------------------------
def frame_quaternions(T, N, B) -> np.ndarray:
    """The quaternion curve (n, 4) on S³ of a frame: q_i with R(q_i) (eq. 9) = [T_i N_i B_i]
    (columns), signs chosen so that consecutive quaternions have ⟨q_i, q_{i+1}⟩ ≥ 0."""
    T, N, B = _frame(T, N, B)
    return matrix_to_quat(np.stack([T, N, B], axis=-1), continuous=True)


def quaternion_length(q, closed: bool = False) -> float:
    """Length of a quaternion frame curve on S³ as the course measures it: Σ arccos|⟨q_i, q_{i+1}⟩|
    (the rotation angle between neighbouring frames, halved), the seam included when closed."""
    q = _quaternions("q", q)
    nxt = np.roll(q, -1, axis=0)[: None if closed else -1]
    return float(np.sum(np.arccos(np.clip(np.abs(np.sum(q[: len(nxt)] * nxt, axis=1)), 0.0, 1.0))))


def quaternion_loop(q) -> np.ndarray:
    """The closed curve on S³ of a closed frame's quaternions q (n, 4) (sign-continuous): q itself
    when the last quaternion returns next to +q_0, otherwise q followed by −q (2n, 4) — the
    frame's quaternion curve closes only after going twice around the space curve (course:
    "torus knot and its (twice around) quaternion Frenet frame")."""
    q = _quaternions("q", q)
    return q if np.dot(q[-1], q[0]) >= 0 else np.concatenate([q, -q])


def tait_matrix(k1, k2, sigma) -> np.ndarray:
    """The 4 × 4 matrix A of Tait's equation q' = ½ A q (q a column (q0, q1, q2, q3)), batched::

        A = [[ 0,  −σ,  k2, −k1],
             [ σ,   0,  k1,  k2],
             [−k2, −k1,  0,   σ],
             [ k1, −k2, −σ,   0]]

    i.e. A q = q ∗ (0, σ, −k2, k1): the body-frame angular velocity. With R(q) of eq. 9 and
    columns T, N, B it reproduces T' = k1 N + k2 B, N' = −k1 T + σ B, B' = −k2 T − σ N. (The
    matrix printed in the notes uses another ordering of the frame and does not.)

    k1, k2, σ are finite numbers or arrays whose shapes broadcast → (..., 4, 4)."""
    args = [(name, finite_float64(name, x, 0, "() or (...)")) for name, x in (("k1", k1), ("k2", k2), ("sigma", sigma))]
    try:
        k1, k2, sigma = np.broadcast_arrays(*(a for _, a in args))
    except ValueError:
        shapes = ", ".join(f"{name} {a.shape}" for name, a in args)
        raise ValueError(f"k1, k2, sigma: batch axes do not broadcast: {shapes}") from None
    return _tait_matrix(k1, k2, sigma)


def _tait_matrix(k1, k2, sigma) -> np.ndarray:
    """:func:`tait_matrix` of already validated, broadcast coefficients."""
    z = np.zeros_like(k1)
    rows = [[z, -sigma, k2, -k1], [sigma, z, k1, k2], [-k2, -k1, z, sigma], [k1, -k2, -sigma, z]]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def _coefficient(name: str, value, s: np.ndarray) -> Callable[[float], float]:
    """k(s) at one arclength, from a callable (whose every value is checked: one finite real
    number), a number, or per-sample values (linearly interpolated)."""
    if callable(value):
        def checked(x: float) -> float:
            raw = value(x)
            try:
                v = np.asarray(raw, dtype=np.float64)
            except (TypeError, ValueError):
                v = None
            if v is None or v.size != 1:
                raise ValueError(f"{name}: the callable returned {raw!r} at s = {x}; expected one "
                                 f"real number")
            if not np.isfinite(v).all():
                raise ValueError(f"{name}: the callable returned {float(v.reshape(()))} at s = {x}; "
                                 f"expected a finite number")
            return float(v.reshape(()))
        return checked
    try:
        v = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a callable, a number or {len(s)} finite values, "
                         f"got {value!r}") from None
    if v.ndim == 0:
        v = np.full(len(s), float(v))
    if v.shape != s.shape or not np.all(np.isfinite(v)):
        raise ValueError(f"{name}: expected a callable, a number or {len(s)} finite values, got shape {v.shape}")
    return lambda x: float(np.interp(x, s, v))


def tait(q0, k1, k2, sigma, s) -> np.ndarray:
    """Integrates Tait's quaternion frame equation q' = ½ A(k1, k2, σ) q (:func:`tait_matrix`)
    from q(s_0) = q0 over the arclength samples s (n,) with classical RK4 (one step per
    interval), renormalizing q after each step. k1, k2, σ are per-sample arrays (n,) (linearly
    interpolated between samples), numbers, or callables of s (called with one arclength, each
    must return one finite number). Returns (n, 4). q0 must be a unit quaternion
    (``rotation.UNIT_TOLERANCE``); it is normalized before integrating.

    σ = 0 gives parallel transport; k2 = 0, k1 = κ, σ = τ gives the Frenet frame."""
    s = finite_float64("s", s, 1, "(n,)")
    if s.ndim != 1 or len(s) < 2 or np.any(np.diff(s) <= 0):
        raise ValueError("s: expected at least 2 finite, strictly increasing arclengths")
    q = finite_float64("q0", q0, 1, "(4,)")
    if q.shape != (4,):
        raise ValueError(f"q0: expected a unit quaternion (4,), got shape {q.shape}")
    _k.check_units("q0", np.ascontiguousarray(q), 4, "quaternion")
    q = q / np.linalg.norm(q)
    coeffs = [_coefficient(name, v, s) for name, v in (("k1", k1), ("k2", k2), ("sigma", sigma))]

    def rate(x: float, q: np.ndarray) -> np.ndarray:
        k1_x, k2_x, sigma_x = (np.float64(c(float(x))) for c in coeffs)
        return 0.5 * _tait_matrix(k1_x, k2_x, sigma_x) @ q

    out = np.empty((len(s), 4))
    out[0] = q
    for i, h in enumerate(np.diff(s)):
        a = rate(s[i], q)
        b = rate(s[i] + h / 2, q + h / 2 * a)
        c = rate(s[i] + h / 2, q + h / 2 * b)
        d = rate(s[i] + h, q + h * c)
        q = q + h / 6 * (a + 2 * b + 2 * c + d)
        q /= np.linalg.norm(q)
        out[i + 1] = q
    return out


def frame_curvatures(T, N, B, s, closed: bool = False):
    """The generalized curvatures (k1, k2, σ) (each (n,)) of a discrete frame at arclengths s
    ((n,), or (n + 1,) from ``arclength(points, closed=True)``): for each segment, the rotation
    between neighbouring frames expressed in the frame, R_i^T R_{i+1} = exp(ℓ_i [ω]×), gives the
    body angular velocity ω = (σ, −k2, k1) exactly for that segment (ℓ_i = s_{i+1} − s_i); each
    sample gets the mean of its (one or two) segments. Feeding them to :func:`tait` reproduces
    the frame to second order in the sample spacing."""
    T, N, B = _frame(T, N, B)
    n = len(T)
    s = finite_float64("s", s, 1, f"({n + 1 if closed else n},)")
    if s.shape != (n + 1 if closed else n,) or np.any(np.diff(s) <= 0):
        raise ValueError(f"s: expected {n + 1 if closed else n} increasing arclengths, got shape {s.shape}")
    q = frame_quaternions(T, N, B)
    nxt = np.roll(q, -1, axis=0)[: n if closed else n - 1]
    rel = quat_multiply(quat_conjugate(q[: len(nxt)]), nxt)  # R_i^T R_{i+1}
    rel *= np.where(rel[:, :1] < 0, -1.0, 1.0)
    v = np.linalg.norm(rel[:, 1:], axis=1)
    angle = 2 * np.arctan2(v, rel[:, 0])
    omega = rel[:, 1:] * (angle / np.where(v > 0, v, 1.0) / np.diff(s))[:, None]
    if closed:
        per_sample = 0.5 * (omega + np.roll(omega, 1, axis=0))
    else:
        per_sample = np.empty((n, 3))
        per_sample[1:-1] = 0.5 * (omega[1:] + omega[:-1])
        per_sample[0], per_sample[-1] = omega[0], omega[-1]
    sigma, minus_k2, k1 = per_sample.T
    return k1, -minus_k2, sigma


# -- curves and tubes --------------------------------------------------------------------------------
def torus_knot(p: int, q: int, n: int, R: float = 1.0, r: float = 0.4) -> np.ndarray:
    """n samples (n, 3) of the (p, q) torus knot, winding p times around the z axis and q times
    around the core circle of radius R (tube radius r < R)::

        x = (R + r cos qt) cos pt,  y = (R + r cos qt) sin pt,  z = r sin qt,   t = 2πk/n

    A closed curve: the first point is not repeated."""
    p, q, n = _count("p", p, 1), _count("q", q, 1), _count("n", n, 3)
    R, r = _positive("R", R), _positive("r", r)
    if r >= R:
        raise ValueError(f"r: must be smaller than R = {R}, got {r}")
    t = 2 * np.pi * np.arange(n) / n
    rho = R + r * np.cos(q * t)
    return np.stack([rho * np.cos(p * t), rho * np.sin(p * t), r * np.sin(q * t)], axis=1)


def tube_3d(points, T, N, B, radius: float, sides: int = 16, closed: bool = False, aspect: float = 1.0):
    """A triangle-mesh tube (vertices (V, 3), simplices (S, 3)) around a curve, following its
    frame: ring i has vertices p_i + radius·(cos θ_j N_i + aspect·sin θ_j B_i), θ_j = 2πj/sides
    (``aspect`` < 1 flattens it into a ribbon that shows the frame's twist).

    Layout: triangles 2(i·sides + j) and 2(i·sides + j) + 1 are segment i, side j (between θ_j and
    θ_{j+1}) — so ``(k // 2) % sides`` is a triangle's side, to colour stripes. ``closed=True``
    also joins ring n − 1 to ring 0 (seamless when the frame closes; a frame that does not close,
    e.g. parallel transport, shows its twist there). An open tube gets two flat end caps (fans
    around the end points, appended last), so every tube is a closed surface. All triangles are
    oriented with outward normals (x1 − x0) × (x2 − x0). The tube is embedded (no folds on the
    inside of bends) while ``radius`` is below the curve's smallest radius of curvature."""
    p = _curve("points", points, (3,), closed)
    T, N, B = _frame(T, N, B)
    if len(T) != len(p):
        raise ValueError(f"T, N, B: expected {len(p)} frames for {len(p)} points, got {len(T)}")
    radius, aspect = _positive("radius", radius), _positive("aspect", aspect)
    sides = _count("sides", sides, 3)
    n = len(p)
    # 1. Rings.
    theta = 2 * np.pi * np.arange(sides) / sides
    ring = radius * (np.cos(theta)[None, :, None] * N[:, None, :]
                     + aspect * np.sin(theta)[None, :, None] * B[:, None, :])
    vertices = (p[:, None, :] + ring).reshape(-1, 3)
    # 2. Two triangles per quad: with a = (i, j), b = (i+1, j), c = (i, j+1), d = (i+1, j+1),
    #    (a, c, b) and (c, d, b) have normals ∝ (∂θ × T), i.e. outward.
    segs = n if closed else n - 1
    i, j = np.meshgrid(np.arange(segs), np.arange(sides), indexing="ij")
    a = i * sides + j
    b = ((i + 1) % n) * sides + j
    c = i * sides + (j + 1) % sides
    d = ((i + 1) % n) * sides + (j + 1) % sides
    simplices = np.stack([np.stack([a, c, b], -1), np.stack([c, d, b], -1)], axis=2).reshape(-1, 3)
    if not closed:
        # 3. End caps: fans around the end points, facing −T_0 and +T_{n−1}.
        start, end = len(vertices), len(vertices) + 1
        vertices = np.concatenate([vertices, p[[0, -1]]])
        jj = np.arange(sides)
        last = (n - 1) * sides
        caps = [np.stack([np.full(sides, start), (jj + 1) % sides, jj], -1),
                np.stack([np.full(sides, end), last + jj, last + (jj + 1) % sides], -1)]
        simplices = np.concatenate([simplices] + caps)
    return vertices, simplices.astype(np.int64)


def icosphere(subdivisions: int = 0):
    """The unit 2-sphere as a subdivided icosahedron: vertices (V, 3), triangles (F, 3) oriented
    with outward normals. Level k has 20·4^k triangles."""
    subdivisions = _count("subdivisions", subdivisions, 0)
    g = (1 + 5 ** 0.5) / 2
    v = [(-1, g, 0), (1, g, 0), (-1, -g, 0), (1, -g, 0), (0, -1, g), (0, 1, g), (0, -1, -g), (0, 1, -g),
         (g, 0, -1), (g, 0, 1), (-g, 0, -1), (-g, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4), (11, 10, 2),
         (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8), (3, 8, 9), (4, 9, 5),
         (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(x, dtype=np.float64) / np.linalg.norm(x) for x in v]
    for _ in range(subdivisions):
        mid: dict[tuple[int, int], int] = {}

        def middle(x: int, y: int, mid: dict[tuple[int, int], int] = mid) -> int:
            key = (min(x, y), max(x, y))
            if key not in mid:
                mid[key] = len(verts)
                verts.append(_unit(verts[x] + verts[y]))
            return mid[key]

        f = [t for a, b, c in f for t in ((a, middle(a, b), middle(c, a)), (b, middle(b, c), middle(a, b)),
                                          (c, middle(c, a), middle(b, c)),
                                          (middle(a, b), middle(b, c), middle(c, a)))]
    V, F = np.array(verts), np.array(f, dtype=np.int64)
    outward = np.einsum("ij,ij->i", np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), V[F[:, 0]])
    F[outward < 0] = F[outward < 0][:, [1, 0, 2]]
    return V, F


def tube_4d(curve4, radius: float, subdivisions: int = 0, closed: bool = False):
    """A 4D curve (n, 4) thickened into a tube for N = 4 rendering (notes, "Extensions to 4D
    rendering": curves get small spheres attached): at each sample a 2-sphere of ``radius`` in
    the curve's 3D normal space. Returns (vertices (V, 4), simplices (S, 4)): the tube's boundary,
    the 3-manifold S² × curve, as tetrahedra, oriented with outward normals (eq. 6).

    1. Normal-space frames: the last three columns of ``rotation.frame([T_0])`` (T_0 completed
       to a rotation, det +1) are parallel-transported in 4D (the minimal rotation between
       consecutive tangents). On a closed curve the transported frame comes back turned by a
       holonomy H ∈ SO(3); frame i is turned by the fraction s_i/L of H⁻¹ (a quaternion slerp
       from the identity), so it closes.
    2. The cross-section is :func:`icosphere` (``subdivisions``); ring i has the vertices
       c_i + radius·Σ_k d_k F_i,k.
    3. Each S² triangle times a segment is a prism split into 3 tetrahedra by the vertex order
       a < b < c of its S² indices (primes on ring i + 1): [a b c c′], [a b b′ c′], [a a′ b′ c′].
       Every quad face is cut along the diagonal from its lower-index bottom vertex to its
       higher-index top vertex, so neighbouring prisms agree and the boundary is closed.
    4. An open tube gets two balls as end caps (the cones [c_0 a b c], [c_{n−1} a b c]).
    5. Orientation is combinatorial (so it holds however the curve bends): the prism's three
       tetrahedra have alternating signs, times the parity of the S² triangle's sorting; each is
       ordered so its normal points outward (away from the curve; −T_0 / +T_{n−1} on the caps).

    Layout: tetrahedra 3·F·i … 3·F·(i + 1) − 1 (F = 20·4^subdivisions) are segment i; the caps
    of an open tube come last. ``radius`` must be below the curve's extent (its bounding-box
    diagonal) and large enough that the rings survive rounding (else a tetrahedron is
    degenerate): ValueError naming ``radius``. As in 3D, the tube is embedded only while
    ``radius`` is below the curve's smallest radius of curvature (quaternion frame curves turn
    sharply where the space curve's torsion peaks).
    """
    c = _curve("curve4", curve4, (4,), closed)
    radius = _positive("radius", radius)
    extent = float(np.linalg.norm(np.ptp(c, axis=0)))
    if not radius < extent:
        raise ValueError(f"radius: expected a radius below the curve's extent {extent:.6g} (its "
                         f"bounding-box diagonal), got {radius!r}")
    n = len(c)
    T = tangents(c, closed)
    # 1. Normal frames (n, 3, 4): [T_0 F_0,1 F_0,2 F_0,3] = frame([T_0]), a rotation.
    F = _transport(T, frame(T[:1])[:, 1:].T)
    if closed:
        back = minimal_rotation(T[-1], T[0], F[-1])  # frame n−1 transported across the seam
        H = F[0] @ back.T  # back_l = Σ_k H[k, l] F0_k
        qH = matrix_to_quat(H.T, continuous=False)  # E_n = H⁻¹ = Hᵀ
        qH = qH * np.sign(qH[0]) if qH[0] != 0 else qH
        s = arclength(c, closed=True)
        t = s[:n] / s[-1]
        identity = np.array([1.0, 0.0, 0.0, 0.0])
        E = quat_to_matrix(np.array([slerp(identity, qH, ti) for ti in t]))  # (n, 3, 3)
        F = np.einsum("nkl,nkd->nld", E, F)  # columns F_i E_i
    # 2. Rings.
    dirs, faces = icosphere(subdivisions)
    K = len(dirs)
    vertices = (c[:, None, :] + radius * np.einsum("vk,nkd->nvd", dirs, F)).reshape(-1, 4)
    # 3. Prisms → tetrahedra by vertex order.
    tri = np.sort(faces, axis=1)
    segs = n if closed else n - 1
    i = np.arange(segs)[:, None]
    lo, hi = i * K, ((i + 1) % n) * K
    a, b, cc = (tri[None, :, k] for k in range(3))
    tets = np.stack([np.stack([lo + a, lo + b, lo + cc, hi + cc], -1),
                     np.stack([lo + a, lo + b, hi + b, hi + cc], -1),
                     np.stack([lo + a, hi + a, hi + b, hi + cc], -1)], axis=2)  # (segs, F, 3, 4)
    # 5. Orientation. In prism coordinates (S² triangle a b c, then the curve direction) the three
    #    tetrahedra have signs +, −, +; [x_0 … x_3] faces outward (det[edges | outward] > 0) when
    #    (x_1 − x_0, x_2 − x_0) run along an outward-oriented S² triangle and x_3 − x_0 along T,
    #    because det[T, F_1, F_2, F_3] = +1. So a tetrahedron is flipped when its sign times the
    #    parity of the sorting permutation of its outward triangle is negative.
    inversions = (faces[:, 0] > faces[:, 1]).astype(int) + (faces[:, 0] > faces[:, 2]) + (faces[:, 1] > faces[:, 2])
    parity = np.where(inversions % 2 == 0, 1, -1)
    flip = np.broadcast_to((parity[:, None] * np.array([1, -1, 1]))[None] < 0, tets.shape[:3])
    tets[flip] = tets[flip][:, [1, 0, 2, 3]]
    tets = tets.reshape(-1, 4)
    if not closed:
        # 4. End caps: [c_0 a b c] (a b c outward on S²) faces −T_0; at the other end it is flipped.
        centres = len(vertices) + np.array([0, 1])
        vertices = np.concatenate([vertices, c[[0, -1]]])
        caps = np.concatenate([np.column_stack([np.full(len(faces), centres[0]), faces]),
                               np.column_stack([faces[:, 0] + (n - 1) * K, np.full(len(faces), centres[1]),
                                                faces[:, 1:] + (n - 1) * K])])
        tets = np.concatenate([tets, caps])
    # 6. Degenerate tetrahedra: 3!·volume/radius³ from the edges in units of the radius (so
    #    radius³ is never formed; radii so small that the rings are lost to rounding show here).
    pts = vertices[tets]
    with np.errstate(over="ignore"):
        edges = (pts[:, 1:] - pts[:, :1]) / radius
    if not np.all(np.isfinite(edges)):
        raise ValueError(f"radius: {radius!r} is too small for a curve of extent {extent:.6g}")
    relative = np.linalg.norm(geometry.generalized_cross(edges), axis=1)
    flat = ~(relative > 1e-12)
    if np.any(flat):
        raise ValueError(f"radius: tetrahedron {int(np.argmax(flat))} of the tube is degenerate "
                         f"(samples too close together for radius {radius!r}?)")
    return vertices, tets.astype(np.int64)


# -- surface frames and quaternion patches (Part II(A), "3-Manifold of Frames for a Patch") -------
def _patch(name: str, points) -> np.ndarray:
    p = finite_float64(name, points, 3, "(U, V, 3)")
    if p.ndim != 3 or p.shape[2] != 3 or p.shape[0] < 3 or p.shape[1] < 3:
        raise ValueError(f"{name}: expected a grid of shape (U, V, 3) with U, V ≥ 3, got {p.shape}")
    return p


def _grid_difference(p: np.ndarray, axis: int) -> np.ndarray:
    """Central differences along ``axis`` (second-order one-sided at the ends)."""
    d = np.empty_like(p)
    a = np.moveaxis(p, axis, 0)
    out = np.moveaxis(d, axis, 0)
    out[1:-1] = a[2:] - a[:-2]
    out[0] = -3 * a[0] + 4 * a[1] - a[2]
    out[-1] = 3 * a[-1] - 4 * a[-2] + a[-3]
    return d


def surface_normals(points) -> np.ndarray:
    """Unit normals (U, V, 3) of a sampled patch ``points`` (U, V, 3): ∂P/∂u × ∂P/∂v by central
    differences (second-order one-sided at the edges), normalized. A degenerate grid point
    (parallel or zero differences) is a ValueError naming it."""
    p = _patch("points", points)
    n = np.cross(_grid_difference(p, 0), _grid_difference(p, 1))
    length = np.linalg.norm(n, axis=-1)
    scale = np.linalg.norm(_grid_difference(p, 0), axis=-1) * np.linalg.norm(
        _grid_difference(p, 1), axis=-1)
    bad = ~(length > 1e-12 * scale)
    if np.any(bad):
        i, j = (int(x) for x in np.argwhere(bad)[0])
        raise ValueError(f"points: the patch is degenerate at grid point ({i}, {j}) (no normal)")
    return n / length[..., None]


def _geodesic_reference_quaternions(n: np.ndarray) -> np.ndarray:
    """The quaternions of the course's geodesic reference frames R(ẑ·n̂, ẑ × n̂): the minimal
    rotation taking ẑ to n̂, q = normalize(1 + ẑ·n̂, ẑ × n̂) (continuous in n̂ away from −ẑ).
    Its third axis is n̂."""
    z = np.array([0.0, 0.0, 1.0])
    q = np.concatenate([1.0 + n[..., 2:3], np.cross(z, n)], axis=-1)
    length = np.linalg.norm(q, axis=-1, keepdims=True)
    if np.any(length < 1e-6):
        raise ValueError("points: a normal points along −z, where the geodesic reference "
                         "frame is undefined; turn the patch")
    return q / length


def _spin(n: np.ndarray, theta: np.ndarray, g: np.ndarray) -> np.ndarray:
    """(cos θ/2, n̂ sin θ/2) · g: the frame g turned by θ about its third axis n̂."""
    h = 0.5 * theta[..., None]
    r = np.concatenate([np.cos(h), np.sin(h) * n], axis=-1)
    return quat_multiply(r, g)


def _angles(q: np.ndarray, n: np.ndarray, g: np.ndarray) -> np.ndarray:
    """θ with q = _spin(n, θ, g), unwrapped along the grid for continuity."""
    r = quat_multiply(q, quat_conjugate(g))
    theta = 2 * np.arctan2(np.sum(r[..., 1:] * n, axis=-1), r[..., 0])
    theta[:, 0] = np.unwrap(theta[:, 0])
    return np.unwrap(theta, axis=1)


def patch_area(q) -> float:
    """The area of the quaternion patch of a grid of unit quaternions ``q`` (U, V, 4): the sum
    of its triangles' areas in R⁴ (each grid cell split along the diagonal (i, j)–(i+1, j+1)),
    the quantity the minimal-area frames minimize."""
    q = finite_float64("q", q, 3, "(U, V, 4)")
    if q.ndim != 3 or q.shape[2] != 4:
        raise ValueError(f"q: expected shape (U, V, 4), got {q.shape}")
    return float(_area(q)[0])


def _area(q: np.ndarray, dq: np.ndarray | None = None):
    """The patch's area and, with ``dq`` (U, V, 4) = ∂q/∂θ, its gradient in θ (U, V)."""
    a, b, c, d = q[:-1, :-1], q[1:, :-1], q[1:, 1:], q[:-1, 1:]
    total = 0.0
    grad = np.zeros(q.shape[:2]) if dq is not None else None
    for (x, y, z, ix, iy, iz) in ((a, b, c, (0, 0), (1, 0), (1, 1)), (a, c, d, (0, 0), (1, 1), (0, 1))):
        e1, e2 = y - x, z - x
        g11, g22, g12 = (np.sum(e1 * e1, -1), np.sum(e2 * e2, -1), np.sum(e1 * e2, -1))
        area = 0.5 * np.sqrt(np.maximum(g11 * g22 - g12 * g12, 0.0))
        total += float(area.sum())
        if grad is not None and dq is not None:
            safe = np.where(area > 0, area, 1.0)[..., None]
            # ∂A/∂e1 = (g22 e1 − g12 e2)/(4A), ∂A/∂e2 = (g11 e2 − g12 e1)/(4A).
            d1 = np.where(area[..., None] > 0, (g22[..., None] * e1 - g12[..., None] * e2) / (4 * safe), 0)
            d2 = np.where(area[..., None] > 0, (g11[..., None] * e2 - g12[..., None] * e1) / (4 * safe), 0)
            U, V = q.shape[0] - 1, q.shape[1] - 1
            for (di, dj), w in ((ix, -d1 - d2), (iy, d1), (iz, d2)):
                grad[di:di + U, dj:dj + V] += np.sum(w * dq[di:di + U, dj:dj + V], -1)
    return total, grad


def _minimal_area(n: np.ndarray, g: np.ndarray, theta: np.ndarray, iterations: int) -> np.ndarray:
    """Gradient descent on the angles θ with a backtracking line search: every step lowers the
    quaternion patch's area, so the result is at most the start's."""
    def at(t):
        q = _spin(n, t, g)
        h = 0.5 * t[..., None]
        dr = 0.5 * np.concatenate([-np.sin(h), np.cos(h) * n], axis=-1)
        return q, quat_multiply(dr, g)

    q, dq = at(theta)
    area, grad = _area(q, dq)
    step = 1.0
    for _ in range(iterations):
        gg = float(np.sum(grad * grad))
        if gg < 1e-24:
            break
        while step > 1e-12:
            t = theta - step * grad
            q1, dq1 = at(t)
            a1, g1 = _area(q1, dq1)
            if a1 <= area - 1e-4 * step * gg:
                theta, area, grad, q = t, a1, g1, q1
                step *= 2.0
                break
            step *= 0.5
        else:
            break
    return theta


def surface_frames(points, method: Literal["geodesic_reference", "parallel_transport",
                                         "minimal_area"] = "minimal_area",
                   iterations: int = 500) -> np.ndarray:
    """Unit quaternions (U, V, 4) of frames on a sampled patch ``points`` (U, V, 3) whose third
    axis is the surface normal (:func:`surface_normals`): ``quat_to_matrix(q)[..., :, 2] = n̂``
    (notes, "3-Manifold of Frames for a Patch": a curve's tangent replaced by the normal).
    Every such frame is the geodesic reference ``R(ẑ·n̂, ẑ × n̂)`` turned by an angle θ about n̂
    (the ring of frames at a point); the methods choose θ:

    * ``"geodesic_reference"``: θ = 0, the minimal rotation taking ẑ to n̂ (undefined where a
      normal is −ẑ: ValueError);
    * ``"parallel_transport"``: the frame at (0, 0) is the geodesic reference, transported
      along the edge j = 0 and then across each row i → i + 1 by the minimal rotation of each
      normal to the next (the discrete parallel transport of curve frames);
    * ``"minimal_area"``: the course's optimal quaternion frame on a patch — θ chosen to
      minimize the area (:func:`patch_area`) of the quaternion patch in S³, by gradient descent
      from the better of the other two (so its area is at most theirs), ``iterations`` steps.

    Signs are continuous over the grid (neighbouring quaternions have positive dot products
    for a smooth patch). ValueError names ``points``, ``method`` or ``iterations``."""
    p = _patch("points", points)
    if method not in ("geodesic_reference", "parallel_transport", "minimal_area"):
        raise ValueError(f"method: expected 'geodesic_reference', 'parallel_transport' or "
                         f"'minimal_area', got {method!r}")
    iterations = _count("iterations", iterations, 0)
    n = surface_normals(p)
    g = _geodesic_reference_quaternions(n)
    if method == "geodesic_reference":
        return g
    # Parallel transport: down the first column, then along each row.
    q = np.empty_like(g)
    q[0, 0] = g[0, 0]

    def step(a, b, qa):
        # The minimal rotation taking normal a to normal b, as a quaternion, then the frame.
        axis = np.cross(a, b)
        c = float(np.dot(a, b))
        m = np.concatenate([[1.0 + c], axis])
        return quat_multiply(m / np.linalg.norm(m), qa)

    for i in range(1, p.shape[0]):
        q[i, 0] = step(n[i - 1, 0], n[i, 0], q[i - 1, 0])
    for j in range(1, p.shape[1]):
        for i in range(p.shape[0]):
            q[i, j] = step(n[i, j - 1], n[i, j], q[i, j - 1])
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    if method == "parallel_transport":
        return q
    theta_pt = _angles(q, n, g)
    start = theta_pt if _area(q)[0] <= _area(g)[0] else np.zeros(n.shape[:2])
    return _spin(n, _minimal_area(n, g, start, iterations), g)


def quaternion_patch(frames, method: Literal["geodesic_reference", "parallel_transport",
                                            "minimal_area"] = "minimal_area"):
    """The course's quaternion surface patch: the map of a patch's frames into S³ ⊂ R⁴ as a
    triangulated surface ``(vertices (V, 4), triangles (T, 3))``, ready for ``shape =
    "surface"``. ``frames`` is a grid of unit quaternions (U, V, 4) (from
    :func:`surface_frames`) or of points (U, V, 3), whose frames ``method`` chooses. Vertex
    ``i·V + j`` is grid point (i, j); each grid cell is two triangles, split along the diagonal
    (i, j)–(i+1, j+1) as :func:`patch_area` counts them."""
    a = finite_float64("frames", frames, 3, "(U, V, 4) or (U, V, 3)")
    if a.ndim != 3 or a.shape[2] not in (3, 4):
        raise ValueError(f"frames: expected quaternions (U, V, 4) or points (U, V, 3), got {a.shape}")
    q = surface_frames(a, method) if a.shape[2] == 3 else a
    if a.shape[2] == 4:
        _k.check_units("frames", np.ascontiguousarray(q).reshape(-1), 4, "quaternion")
    U, V = q.shape[:2]
    idx = np.arange(U * V).reshape(U, V)
    a0, b0, c0, d0 = idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]
    triangles = np.concatenate([np.stack([a0, b0, c0], -1).reshape(-1, 3),
                                np.stack([a0, c0, d0], -1).reshape(-1, 3)])
    return q.reshape(-1, 4).copy(), triangles.astype(np.int64)


def smooth_patch(n: int = 16, height: float = 0.4) -> np.ndarray:
    """The course's smooth example patch, a bump z = h·exp(−2(x² + y²)) − h·x·y/2 over
    [−1, 1]², sampled on an n × n grid → (n, n, 3)."""
    n = _count("n", n, 3)
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n), indexing="ij")
    z = height * (np.exp(-2 * (x * x + y * y)) - 0.5 * x * y)
    return np.stack([x, y, z], axis=-1)


def spherical_patch(n: int = 16, extent: float = 1.0) -> np.ndarray:
    """The course's spherical example: a patch of the unit sphere around its north pole,
    longitude and colatitude-like coordinates (u, v) ∈ [−extent, extent]² mapped by
    (sin u cos v, sin v, cos u cos v) → (n, n, 3)."""
    n = _count("n", n, 3)
    extent = _positive("extent", extent)
    u, v = np.meshgrid(np.linspace(-extent, extent, n), np.linspace(-extent, extent, n),
                       indexing="ij")
    return np.stack([np.sin(u) * np.cos(v), np.sin(v), np.cos(u) * np.cos(v)], axis=-1)
