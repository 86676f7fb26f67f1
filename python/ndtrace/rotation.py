"""Rotations in N dimensions, after Part I(B) of Hanson's SIGGRAPH '98 course notes
("N-Dimensional Rotations for Computer Graphics") and the quaternion parts of Part II(A).

Every function takes float64-convertible arrays, batched over leading axes where that is
natural, and returns float64 arrays. Bad input (wrong shapes, NaN, non-unit quaternions,
matrices that are not rotations) raises ValueError naming the argument.

Tolerances (one policy, the constants of the Rust core, also used by ``ndtrace.frames``):
arguments that must be unit vectors or unit quaternions are *computed* values and must have
``| |q| − 1 | ≤ UNIT_TOLERANCE`` (1e-9); they are used as given. Rotation arguments must have
``max |RᵀR − I| ≤ ORTHOGONALITY_TOLERANCE`` (1e-9) and det +1. Only quaternions typed by hand
into a scene file (``{ rotate = { quaternions = [q, p] } }``) get the looser
``SCENE_UNIT_TOLERANCE`` (1e-3, so four digits such as ``[0.7071, 0.7071, 0, 0]`` are enough)
and are normalized before use. Normalize computed quaternions yourself (``q / |q|``) if they
may have drifted.

Conventions
-----------
* Matrices act on column vectors; **columns are the new axes** (``frame``).
* ``plane(n, i, j, θ)`` is the course's R_ij (eq. 6): it turns axis i toward axis j,
  ``R e_i = cos θ e_i + sin θ e_j``. Axes are numbered from 0; θ is in radians.
* ``compose([R_1, …, R_k]) = R_k ⋯ R_1``: **the first rotation in the list acts first**, as
  in a scene's ``transform`` list.
* Rolling ball (eq. 5): the displacement ``d = r n̂`` lives in the first N − 1 axes and the
  hidden "north pole" is the last axis. ``M e_N = c e_N + s n̂``: the pole is pulled toward the
  motion (``M[:-1, -1] = s n̂``, ``M[-1, :-1] = −s n̂``). ``angle="course"`` uses
  ``c = R/D, s = r/D`` with ``D² = R² + r²``; ``angle="arc"`` uses ``θ = r/R``.
* Commutator sense: incremental rolls accumulate as ``M_total = M_k ⋯ M_1`` (``compose`` of
  the steps in order). A small counterclockwise loop of the controller in its (i, j) plane
  (+e_i, +e_j, −e_i, −e_j) of area A (with ``angle="arc"``, R = 1) gives
  ``plane(n, i, j, −A)`` to second order: the object turns *against* the loop (j toward i).
* Quaternions are ``(q0, q1, q2, q3)`` with **q0 the scalar part** (scipy uses scalar-last
  ``(x, y, z, w)``). ``quat_to_matrix(q)`` is eq. 9, ``V ↦ q V q̄``; ``q = (cos θ/2, n̂ sin θ/2)``
  turns by θ about n̂. ``matrix_to_quat`` treats axis 0 of a batch as a **sequence by
  default** (``continuous=True``): signs are chosen so that consecutive quaternions along axis
  0 have non-negative dot products (the first has q0 ≥ 0), as animation and frame curves need.
  For a batch of unrelated rotations pass ``continuous=False`` to get q0 ≥ 0 for every item.
* ``rotation_between(a, b)`` is the minimal rotation taking unit a to unit b: in their plane,
  fixing everything orthogonal to both; antipodal pairs turn by π in the plane of a and the
  coordinate axis least aligned with a (the axis ``frame([a])`` puts second).
* ``so4_from_quaternions(q, p)`` is ``v ↦ q v p̄`` on all quaternions v = (v0, v1, v2, v3);
  with p = q it is ``1 ⊕ quat_to_matrix(q)``. ``quaternions_from_so4`` inverts it up to the
  shared sign of (q, p) (the largest-magnitude component of q is made positive).
* 4D arcball: ``arcball_4d(a0, a1, b0, b1) = so4_from_quaternions(a1 ā0, b1 b̄0)``; it maps
  ``a0 b̄0`` to ``a1 b̄1``; with b0 = b1 it is left multiplication taking a0 to a1; with equal
  pairs of pure quaternions it is Shoemake's 3D arcball on axes 1–3 (twice the arc).
* ``look_at`` returns exactly the orientation of a scene's ``look_at`` camera: columns
  u_1 … u_{N−1}, then the view direction, with ``det[u_1 … u_{N−1}, −view] = +1`` — so its
  determinant is −1 (a camera frame, not a rotation).
* Splines through keyframes (rotations paper, "the explicit 4D extension of 3D quaternion
  orientation splines"): ``quaternion_spline(keys, times, t)`` is Shoemake's Bézier
  construction evaluated by de Casteljau's algorithm with slerps, its inner control points
  from Catmull–Rom tangents weighted for unequal times as in Schlag (Graphics Gems II), C¹ in
  time, the shorter arc between neighbours, the slerp itself for two keys;
  ``so4_spline(left_keys, right_keys, times, t)`` is the course's double-quaternion form, one
  spline per S³ factor (the pairs' signs chosen jointly); ``so_n_spline(keys, times, t)`` —
  beyond the course, which says explicit splines for N > 4 are unknown — runs the same
  construction in SO(N) itself, its geodesics through the matrix logarithm and exponential.
  Times outside the keys' span are clamped to it.
* Nested spheres (SO(N)/SO(N−1) = S^{N−1}): ``to_nested_spheres(R)`` gives v_N = R[:, -1]
  on S^{N−1}, then the same for the SO(N−1) block left after undoing the minimal rotation
  taking e_N to v_N, down to v_2 on S^1; ``from_nested_spheres`` rebuilds
  ``R = P_N(v_N) · (P_{N−1}(v_{N−1}) ⊕ 1) ⋯``.
"""

from __future__ import annotations

import operator
from collections.abc import Sequence
from typing import Literal

import numpy as np

from . import _ndtrace
from ._util import batch_size, broadcast_batch, finite_float64

_k = _ndtrace.rotation

__all__ = [
    "plane",
    "compose",
    "rolling_ball",
    "frame",
    "rotation_between",
    "look_at",
    "slerp",
    "to_nested_spheres",
    "from_nested_spheres",
    "nested_slerp",
    "quat_multiply",
    "quat_conjugate",
    "quat_to_matrix",
    "matrix_to_quat",
    "so4_from_quaternions",
    "quaternions_from_so4",
    "slerp_so4",
    "arcball_4d",
    "quaternion_spline",
    "so4_spline",
    "so_n_spline",
]

_DIMS = f"{_ndtrace.MIN_DIM}..{_ndtrace.MAX_DIM}"

#: | |q| − 1 | allowed for unit-vector and unit-quaternion arguments (computed values)
UNIT_TOLERANCE: float = _k.UNIT_TOLERANCE
#: | |q| − 1 | allowed for quaternions typed into scene files (normalized when accepted)
SCENE_UNIT_TOLERANCE: float = _k.SCENE_UNIT_TOLERANCE
#: max |RᵀR − I| allowed for rotation arguments
ORTHOGONALITY_TOLERANCE: float = _k.ORTHOGONALITY_TOLERANCE


def _c(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


def _int(name: str, value) -> int:
    try:
        return operator.index(value)
    except TypeError:
        raise ValueError(f"{name}: expected an integer, got {value!r}") from None


def _axis(name: str, value) -> int:
    """An axis number: an integer ≥ 0 (whether it fits the dimension is checked in Rust)."""
    i = _int(name, value)
    if i < 0:
        raise ValueError(f"{name}: expected an axis number ≥ 0 (axes count from 0), got {i}")
    if i >= _ndtrace.MAX_DIM:
        raise ValueError(f"{name}: axis {i} is out of range: N ≤ {_ndtrace.MAX_DIM}, axes 0..N−1")
    return i


def _n(name: str, n: int, shape: tuple | None = None) -> int:
    if not (_ndtrace.MIN_DIM <= n <= _ndtrace.MAX_DIM):
        got = f"{shape} (N = {n})" if shape is not None else f"{n}"
        raise ValueError(f"{name}: N must be in {_DIMS} (the supported dimensions), got {got}")
    return n


def _square(name: str, value) -> tuple[np.ndarray, int]:
    """A stack of square matrices (..., N, N) → (array, N)."""
    m = finite_float64(name, value, 2, "(..., N, N)")
    if m.shape[-1] != m.shape[-2]:
        raise ValueError(f"{name}: expected shape (..., N, N), got {m.shape}")
    return m, _n(name, m.shape[-1], m.shape)


def _fixed(name: str, value, width: int, what: str = "") -> np.ndarray:
    """An array of shape (..., width)."""
    a = finite_float64(name, value, 1, f"(..., {width})")
    if a.shape[-1] != width:
        raise ValueError(f"{name}: expected shape (..., {width}){what}, got {a.shape}")
    return a


def _times(t) -> np.ndarray:
    return finite_float64("t", t, 0, "() or (T...)")


def plane(n: int, i: int, j: int, theta) -> np.ndarray:
    """The course's plane rotation R_ij(θ) (eq. 6) in R^n: turns axis i toward axis j
    (``R e_i = cos θ e_i + sin θ e_j``), θ in radians, scalar or array (...) → (..., n, n)."""
    n = _n("n", _int("n", n))
    i, j = _axis("i", i), _axis("j", j)  # the plane itself is checked by the kernel
    th = finite_float64("theta", theta, 0, "() or (...)")
    return _k.plane(n, i, j, _c(th).reshape(-1)).reshape(th.shape + (n, n))


def compose(rotations) -> np.ndarray:
    """The product of rotations ``(..., K, N, N)`` with the first acting first:
    ``compose([R_1, …, R_k]) = R_k ⋯ R_1`` → ``(..., N, N)``. Each must be a rotation."""
    r = finite_float64("rotations", rotations, 3, "(..., K, N, N)")
    if r.shape[-1] != r.shape[-2]:
        raise ValueError(f"rotations: expected shape (..., K, N, N), got {r.shape}")
    n = _n("rotations", r.shape[-1], r.shape)
    batch, k = r.shape[:-3], r.shape[-3]
    return _k.compose(n, k, batch_size(batch), _c(r).reshape(-1)).reshape(batch + (n, n))


def rolling_ball(displacement, radius: float = 1.0,
                 angle: Literal["course", "arc"] = "course") -> np.ndarray:
    """The N-D rolling ball M_N (eq. 5) for controller displacements ``(..., N−1)`` →
    ``(..., N, N)``: turns the last axis toward the displacement direction n̂ by θ with
    ``tan θ = r/R`` (``angle="course"``) or ``θ = r/R`` (``angle="arc"``). Zero → identity."""
    d = finite_float64("displacement", displacement, 1, "(..., N−1)")
    n = d.shape[-1] + 1
    if not (_ndtrace.MIN_DIM <= n <= _ndtrace.MAX_DIM):
        raise ValueError(
            f"displacement: expected shape (..., N−1) with N in {_DIMS}, got {d.shape} (N = {n})"
        )
    try:
        radius = float(radius)
    except (TypeError, ValueError):
        raise ValueError(f"radius: expected a positive number, got {radius!r}") from None
    batch = d.shape[:-1]
    return _k.rolling_ball(n, _c(d).reshape(-1), radius, angle).reshape(batch + (n, n))


def frame(vectors) -> np.ndarray:
    """The rotation whose columns are ``vectors (..., K, N)`` (K ≤ N) after Gram–Schmidt,
    completed with coordinate axes to a right-handed frame (det +1) when K < N: each next
    column is the axis least in the span so far (the lowest index on ties), orthogonalized, so
    ``frame([])`` and ``frame([e_0])`` are the identity and ``frame([a])[:, 1]`` is the axis
    least aligned with a. N vectors that form a left-handed frame, or dependent vectors, raise
    ValueError."""
    v = finite_float64("vectors", vectors, 2, "(..., K, N)")
    n = _n("vectors", v.shape[-1], v.shape)
    k = v.shape[-2]
    if k > n:
        raise ValueError(f"vectors: expected shape (..., K, N) with K ≤ N, got {v.shape}")
    batch = v.shape[:-2]
    return _k.frame(n, k, batch_size(batch), _c(v).reshape(-1)).reshape(batch + (n, n))


def rotation_between(a, b) -> np.ndarray:
    """The minimal rotation taking unit vectors ``a`` to ``b`` ``(..., N)`` (batch axes
    broadcast) → ``(..., N, N)``: it turns a toward b in their plane and fixes everything
    orthogonal to both (``R v = v − (a + b)((a + b)·v)/(1 + a·b) + 2b(a·v)``), built as a
    product of two reflections so it is exactly orthogonal with det +1. Antipodal pairs turn by
    π in the plane of a and the coordinate axis least aligned with a."""
    av = finite_float64("a", a, 1, "(..., N)")
    n = _n("a", av.shape[-1], av.shape)
    bv = _fixed("b", b, n, " to match a")
    batch, (av, bv) = broadcast_batch([("a", av, 1), ("b", bv, 1)])
    return _k.rotation_between(n, av.reshape(-1), bv.reshape(-1)).reshape(batch + (n, n))


def look_at(position, target, up=None) -> np.ndarray:
    """The orientation of a ``look_at`` camera at ``position`` looking at ``target`` with
    ``up`` (N−2 vectors; one vector for N = 3; none for N = 2) — exactly what a scene's
    ``camera.look_at`` builds: columns u_1 … u_{N−1}, view, and det −1."""
    p = finite_float64("position", position, 1, "(N,)")
    if p.ndim != 1:
        raise ValueError(f"position: expected shape (N,), got {p.shape}")
    n = _n("position", p.shape[0], p.shape)
    t = finite_float64("target", target, 1, f"({n},)")
    if t.shape != (n,):
        raise ValueError(f"target: expected shape ({n},), got {t.shape}")
    u = np.zeros((0, n)) if up is None else finite_float64("up", up, 1, f"({n - 2}, {n})")
    if u.ndim == 1 and n == 3:
        u = u[None, :]
    if u.shape != (n - 2, n):
        raise ValueError(f"up: expected shape ({n - 2}, {n}) (N − 2 vectors), got {u.shape}")
    return _k.look_at(n, _c(p), _c(t), _c(u).reshape(-1)).reshape(n, n)


def slerp(a, b, t) -> np.ndarray:
    """Spherical linear interpolation between unit vectors ``a``, ``b`` ``(..., N)``
    (broadcast) at ``t`` (scalar or array): constant angular speed, ``angle(a, slerp) = t·θ``
    → ``t.shape + batch + (N,)``. Antipodal pairs turn in the plane of a and the coordinate
    axis least aligned with it."""
    av = finite_float64("a", a, 1, "(..., N)")
    n = _n("a", av.shape[-1], av.shape)
    bv = _fixed("b", b, n, " to match a")
    batch, (av, bv) = broadcast_batch([("a", av, 1), ("b", bv, 1)])
    ts = _times(t)
    out = _k.slerp(n, av.reshape(-1), bv.reshape(-1), _c(ts).reshape(-1))
    return out.reshape(ts.shape + batch + (n,))


def to_nested_spheres(R) -> list[np.ndarray]:
    """Nested-sphere coordinates of rotations ``(..., N, N)``: the list
    ``[v_N (..., N), v_{N−1} (..., N−1), …, v_2 (..., 2)]`` of unit vectors, v_N = R[..., :, -1]."""
    m, n = _square("R", R)
    batch = m.shape[:-2]
    flat = _k.to_nested_spheres(n, _c(m).reshape(-1)).reshape(batch + (n * (n + 1) // 2 - 1,))
    out, at = [], 0
    for k in range(n, 1, -1):
        out.append(flat[..., at:at + k].copy())
        at += k
    return out


def from_nested_spheres(vectors: Sequence) -> np.ndarray:
    """The rotations ``(..., N, N)`` with nested-sphere coordinates
    ``[v_N (..., N), …, v_2 (..., 2)]`` (each a unit vector; batch axes broadcast)."""
    if isinstance(vectors, np.ndarray) or not isinstance(vectors, (list, tuple)) or not vectors:
        raise ValueError("vectors: expected a list [v_N, v_{N−1}, …, v_2] of unit vectors")
    first = finite_float64("vectors[0]", vectors[0], 1, "(..., N)")
    n = _n("vectors[0]", first.shape[-1], first.shape)
    if len(vectors) != n - 1:
        raise ValueError(
            f"vectors: expected {n - 1} vectors of lengths "
            f"{', '.join(str(k) for k in range(n, 1, -1))}, got {len(vectors)}"
        )
    parts = [("vectors[0]", first, 1)]
    for idx in range(1, n - 1):
        name = f"vectors[{idx}]"
        parts.append((name, _fixed(name, vectors[idx], n - idx), 1))
    batch, arrays = broadcast_batch(parts)
    packed = _c(np.concatenate(arrays, axis=-1))
    return _k.from_nested_spheres(n, packed.reshape(-1)).reshape(batch + (n, n))


def nested_slerp(R0, R1, t) -> np.ndarray:
    """Interpolates rotations ``R0``, ``R1`` ``(N, N)`` by slerping each nested-sphere vector,
    at ``t`` (scalar or array) → ``t.shape + (N, N)``; t = 0 gives R0, t = 1 gives R1."""
    a, n = _square("R0", R0)
    b = finite_float64("R1", R1, 2, f"({n}, {n})")
    if a.shape != (n, n) or b.shape != (n, n):
        raise ValueError(f"R0, R1: expected two ({n}, {n}) rotations, got {a.shape} and {b.shape}")
    ts = _times(t)
    return _k.nested_slerp(n, _c(a), _c(b), _c(ts).reshape(-1)).reshape(ts.shape + (n, n))


def quat_multiply(a, b) -> np.ndarray:
    """Quaternion product ``a * b`` of ``(..., 4)`` arrays (scalar first), batch broadcast."""
    av, bv = _fixed("a", a, 4), _fixed("b", b, 4)
    batch, (av, bv) = broadcast_batch([("a", av, 1), ("b", bv, 1)])
    return _k.quat_multiply(av.reshape(-1), bv.reshape(-1)).reshape(batch + (4,))


def quat_conjugate(q) -> np.ndarray:
    """The conjugate ``(q0, −q1, −q2, −q3)`` of ``(..., 4)``."""
    qv = _fixed("q", q, 4)
    return _k.quat_conjugate(_c(qv).reshape(-1)).reshape(qv.shape)


def quat_to_matrix(q) -> np.ndarray:
    """The 3D rotations (eq. 9) of unit quaternions ``(..., 4)`` → ``(..., 3, 3)``."""
    qv = _fixed("q", q, 4)
    return _k.quat_to_matrix(_c(qv).reshape(-1)).reshape(qv.shape[:-1] + (3, 3))


def matrix_to_quat(R, continuous: bool = True) -> np.ndarray:
    """Unit quaternions of 3D rotations ``(..., 3, 3)`` → ``(..., 4)`` (Shepperd's method).

    ``continuous=True`` (the default) reads axis 0 of a batch ``(T, ..., 3, 3)`` as a sequence:
    the first quaternion has q0 ≥ 0 and each later one the sign that makes its dot product with
    the previous one (along axis 0) non-negative — q and −q are the same rotation, and this
    choice gives continuous curves on S³. So items after the first may have q0 < 0. For a batch
    of *unrelated* rotations pass ``continuous=False``: then every quaternion has q0 ≥ 0
    (rotation angle in [0, π]). A single matrix (3, 3) always gets q0 ≥ 0."""
    m = finite_float64("R", R, 2, "(..., 3, 3)")
    if m.shape[-2:] != (3, 3):
        raise ValueError(f"R: expected shape (..., 3, 3), got {m.shape}")
    batch = m.shape[:-2]
    stride = batch_size(batch[1:]) if (continuous and len(batch) >= 1) else 0
    return _k.matrix_to_quat(_c(m).reshape(-1), stride).reshape(batch + (4,))


def so4_from_quaternions(q, p) -> np.ndarray:
    """The 4D rotations ``v ↦ q v p̄`` of unit quaternions ``q``, ``p`` ``(..., 4)`` →
    ``(..., 4, 4)``; with p = q: 1 at [0, 0] and ``quat_to_matrix(q)`` in the lower 3×3."""
    qv, pv = _fixed("q", q, 4), _fixed("p", p, 4)
    batch, (qv, pv) = broadcast_batch([("q", qv, 1), ("p", pv, 1)])
    return _k.so4_from_quaternions(qv.reshape(-1), pv.reshape(-1)).reshape(batch + (4, 4))


def quaternions_from_so4(R) -> tuple[np.ndarray, np.ndarray]:
    """The unit quaternion pairs ``(q, p)`` of 4D rotations ``(..., 4, 4)``, up to the shared
    sign, with ``so4_from_quaternions(q, p) = R``."""
    m = finite_float64("R", R, 2, "(..., 4, 4)")
    if m.shape[-2:] != (4, 4):
        raise ValueError(f"R: expected shape (..., 4, 4), got {m.shape}")
    batch = m.shape[:-2]
    out = _k.quaternions_from_so4(_c(m).reshape(-1)).reshape(batch + (8,))
    return out[..., :4].copy(), out[..., 4:].copy()


def _pair(name: str, qp) -> tuple[np.ndarray, np.ndarray]:
    a = finite_float64(name, qp, 2, "(2, 4)")
    if a.shape != (2, 4):
        raise ValueError(f"{name}: expected a pair (q, p) of quaternions, shape (2, 4), got {a.shape}")
    return _c(a[0]), _c(a[1])


def slerp_so4(qp0, qp1, t) -> tuple[np.ndarray, np.ndarray]:
    """Geodesic interpolation between 4D frames given as unit quaternion pairs
    ``qp0 = (q0, p0)``, ``qp1 = (q1, p1)``: q and p are slerped with the same t, the sign of
    (q1, p1) taken to make the total angle shortest. Returns ``(q, p)``, each
    ``t.shape + (4,)``; ``so4_from_quaternions(q, p)`` gives the matrices."""
    q0, p0 = _pair("qp0", qp0)
    q1, p1 = _pair("qp1", qp1)
    ts = _times(t)
    out = _k.slerp_so4(q0, p0, q1, p1, _c(ts).reshape(-1)).reshape(ts.shape + (8,))
    return out[..., :4].copy(), out[..., 4:].copy()


def arcball_4d(a0, a1, b0, b1) -> np.ndarray:
    """The 4D arcball from two pairs of unit quaternions (points of S³) ``(..., 4)``:
    ``so4_from_quaternions(a1 ā0, b1 b̄0)``, the rotation ``v ↦ a1 ā0 v b0 b̄1`` taking
    ``a0 b̄0`` to ``a1 b̄1`` → ``(..., 4, 4)``."""
    args = [(name, _fixed(name, v, 4), 1) for name, v in (("a0", a0), ("a1", a1), ("b0", b0), ("b1", b1))]
    batch, (x0, x1, y0, y1) = broadcast_batch(args)
    return _k.arcball_4d(x0.reshape(-1), x1.reshape(-1), y0.reshape(-1), y1.reshape(-1)).reshape(
        batch + (4, 4)
    )


def _key_times(times, count: int) -> np.ndarray:
    ts = finite_float64("times", times, 1, "(K,)")
    if ts.shape != (count,):
        raise ValueError(f"times: expected shape ({count},), one time per key, got {ts.shape}")
    if count < 2:
        raise ValueError(f"keys: a spline needs at least two keys, got {count}")
    bad = np.flatnonzero(np.diff(ts) <= 0)
    if len(bad):
        i = int(bad[0]) + 1
        raise ValueError(f"times: must increase strictly: times[{i}] = {ts[i]} follows "
                         f"{ts[i - 1]}")
    return _c(ts)


def _keys(name: str, keys) -> np.ndarray:
    k = finite_float64(name, keys, 2, "(K, 4)")
    if k.ndim != 2 or k.shape[1] != 4:
        raise ValueError(f"{name}: expected unit quaternions of shape (K, 4), got {k.shape}")
    return _c(k)


def quaternion_spline(keys, times, t) -> np.ndarray:
    """A C¹ spline of unit quaternions through ``keys`` ``(K, 4)`` at strictly increasing
    ``times`` ``(K,)``, evaluated at ``t`` (scalar or array) → ``t.shape + (4,)``.

    Shoemake's Bézier construction ("Animating rotation with quaternion curves", 1985) by de
    Casteljau's algorithm with slerps; the inner control points ``a_i = q_i exp(ω_i Δt_i/3)``,
    ``b_i = q_{i+1} exp(−ω_{i+1} Δt_i/3)`` come from the body-frame angular velocity ω_i, the
    time-weighted mean of the neighbouring chords' ``log(q̄_i q_{i+1})/Δt_i`` (Catmull–Rom
    tangents as in Schlag, Graphics Gems II, weighted for unequal times), so the velocity is
    the same on both sides of a key. Neighbouring keys take the shorter arc (q_{i+1} → −q_{i+1}
    when q_i·q_{i+1} < 0); the curve passes through the keys so signed. Two keys give the slerp.
    ``t`` outside ``[times[0], times[-1]]`` is clamped. ValueError names ``keys``, ``times``
    (not strictly increasing, wrong length, NaN) or ``t``."""
    k = _keys("keys", keys)
    ts = _key_times(times, len(k))
    tt = _times(t)
    return _k.quaternion_spline(k.reshape(-1), ts, _c(tt).reshape(-1)).reshape(tt.shape + (4,))


def so4_spline(left_keys, right_keys, times, t) -> np.ndarray:
    """The SO(4) spline through the rotations ``v ↦ q_i v p̄_i`` with ``q_i = left_keys[i]``,
    ``p_i = right_keys[i]`` (each ``(K, 4)``) at ``times``, at ``t`` → ``t.shape + (4, 4)``:
    the course's double-quaternion construction, ``so4_from_quaternions(q(t), p(t))`` with a
    :func:`quaternion_spline` on each S³ factor. The pairs' signs are chosen jointly for the
    shorter way (the smaller θ_q² + θ_p² between neighbours, as :func:`slerp_so4`)."""
    left, right = _keys("left_keys", left_keys), _keys("right_keys", right_keys)
    if len(right) != len(left):
        raise ValueError(f"right_keys: expected {len(left)} keys like left_keys, got {len(right)}")
    ts = _key_times(times, len(left))
    tt = _times(t)
    out = _k.so4_spline(left.reshape(-1), right.reshape(-1), ts, _c(tt).reshape(-1))
    return out.reshape(tt.shape + (4, 4))


def so_n_spline(keys, times, t) -> np.ndarray:
    """Beyond the course: a C¹ spline through rotations ``keys`` ``(K, N, N)`` of SO(N), any N,
    at ``times``, at ``t`` → ``t.shape + (N, N)``. The notes say explicit splines in SO(N) for
    N > 4 are unknown; this runs the construction of :func:`quaternion_spline` in SO(N) itself,
    its geodesics ``R_a expm(s logm(R_aᵀ R_b))`` (the bi-invariant metric's) through the matrix
    logarithm and exponential. For N = 3 and 4 it gives the curves of the quaternion forms, to
    rounding. Neighbouring keys must be less than a half turn apart."""
    k, n = _square("keys", keys)
    if k.ndim != 3:
        raise ValueError(f"keys: expected rotations of shape (K, N, N), got {k.shape}")
    ts = _key_times(times, len(k))
    tt = _times(t)
    out = _k.so_n_spline(n, _c(k).reshape(-1), ts, _c(tt).reshape(-1))
    return out.reshape(tt.shape + (n, n))
