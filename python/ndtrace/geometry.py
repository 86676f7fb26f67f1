"""N-dimensional geometry of the course notes ("Geometry for N-Dimensional Graphics").

Every function takes float64-convertible arrays, batched over leading axes (which broadcast
against each other like numpy's), and returns float64 arrays. Equation numbers refer to the
paper printed in Hanson's SIGGRAPH '98 course notes.

Conventions
-----------
* A simplex is given by its points ``x_0 … x_K`` along the second-to-last axis; edges are
  ``x_k − x_0``, used as matrix *columns* with ``x_0`` as origin (eqs. 2–3).
* The normal of an (N−1)-simplex is the generalized cross product of its edges (eq. 6), so
  ``det[e_1 … e_{N−1} | N] = |N|² > 0``; "above" a hyperplane is the side the normal points to.

Degenerate input
----------------
A simplex is degenerate when its K-volume is negligible against its edge lengths
(``W_K ≤ 1e-12 · Π|e_k|``); a segment or ray is parallel to a hyperplane when
``|n̂·d| ≤ 1e-12·|d|``. ``generalized_cross``, ``signed_volume``, ``gram_volume`` and
``transform_normal`` are always defined (zero normal or volume); ``side`` returns 0 for a
degenerate hyperplane. ``hyperplane``, ``point_hyperplane_distance``, ``barycentric``,
``clip_segment`` and ``ray_hyperplane`` take ``degenerate="raise"`` (the default: ValueError
naming the first degenerate batch index, counted in C order over the flattened batch axes) or ``degenerate="nan"`` (NaN in that item's results,
and the flag is ``numpy.isnan`` of them).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from . import _ndtrace
from ._util import batch_size, broadcast_batch, finite_float64

_k = _ndtrace.geometry

__all__ = [
    "generalized_cross",
    "signed_volume",
    "gram_volume",
    "hyperplane",
    "point_hyperplane_distance",
    "barycentric",
    "clip_segment",
    "side",
    "ray_hyperplane",
    "transform_normal",
]

Degeneracy = Literal["raise", "nan"]


def _dim(name: str, n: int, shape_text: str, shape: tuple) -> int:
    if not (_ndtrace.MIN_DIM <= n <= _ndtrace.MAX_DIM):
        raise ValueError(
            f"{name}: expected shape {shape_text} with N in {_ndtrace.MIN_DIM}..{_ndtrace.MAX_DIM}"
            f" (the supported dimensions), got {shape} (N = {n})"
        )
    return n


def _raise(degenerate: str) -> bool:
    if degenerate not in ("raise", "nan"):
        raise ValueError(f'degenerate: expected "raise" or "nan", got {degenerate!r}')
    return degenerate == "raise"


def _simplex(name: str, points, rows: str) -> tuple[np.ndarray, int]:
    """Points of shape (..., rows, N); ``rows`` is 'N-1', 'N', 'N+1' — returns (array, N)."""
    shape_text = f"(..., {rows}, N)"
    p = finite_float64(name, points, 2, shape_text)
    n = _dim(name, p.shape[-1], shape_text, p.shape)
    want = {"N-1": n - 1, "N": n, "N+1": n + 1}[rows]
    if p.shape[-2] != want:
        raise ValueError(
            f"{name}: expected shape {shape_text} = (..., {want}, {n}), got {p.shape}"
        )
    return p, n


def _vector(name: str, x, n: int) -> np.ndarray:
    a = finite_float64(name, x, 1, f"(..., {n})")
    if a.shape[-1] != n:
        raise ValueError(f"{name}: expected shape (..., {n}) to match the points, got {a.shape}")
    return a


def generalized_cross(edges) -> np.ndarray:
    """Generalized cross product (eq. 6) of edges ``(..., N−1, N)``, row k = x_k − x_0 → ``(..., N)``.

    The cofactors of the last column of ``[x_1−x_0 … x_{N−1}−x_0 | unit vectors]``. Orthogonal to
    every edge, ``|N|²`` is the Gram determinant ``((N−1)!·V_{N−1})²``; e_1 … e_{N−1} give +e_N,
    and in 2D the edge (a, b) gives (−b, a). Dependent edges give the zero vector.
    """
    e, n = _simplex("edges", edges, "N-1")
    batch = e.shape[:-2]
    e = np.ascontiguousarray(e)
    return _k.generalized_cross(n, batch_size(batch), e).reshape(batch + (n,))


def signed_volume(points) -> np.ndarray:
    """Signed N-volume (eqs. 2–3) of simplices ``(..., N+1, N)`` → ``(...)``:
    ``det[x_1−x_0 … x_N−x_0] / N!``; the standard simplex has +1/N!."""
    p, n = _simplex("points", points, "N+1")
    batch = p.shape[:-2]
    return _k.signed_volume(n, batch_size(batch), np.ascontiguousarray(p)).reshape(batch)


def gram_volume(points) -> np.ndarray:
    """Unsigned K-volume (eqs. 4–5) of K-simplices ``(..., K+1, N)``, 1 ≤ K ≤ N → ``(...)``:
    ``√det G / K!`` with G the Gram matrix of the edges."""
    shape_text = "(..., K+1, N) with 1 ≤ K ≤ N"
    p = finite_float64("points", points, 2, shape_text)
    n = _dim("points", p.shape[-1], shape_text, p.shape)
    k = p.shape[-2] - 1
    if not 1 <= k <= n:
        raise ValueError(f"points: expected shape {shape_text}, got {p.shape} (K = {k})")
    batch = p.shape[:-2]
    return _k.gram_volume(n, k, batch_size(batch), np.ascontiguousarray(p)).reshape(batch)


def hyperplane(points, *, degenerate: Degeneracy = "raise") -> tuple[np.ndarray, np.ndarray]:
    """Hyperplane (eq. 1) through points ``(..., N, N)`` → ``(n̂ (..., N), c (...))`` with
    n̂ the unit normal in the direction of ``generalized_cross`` and ``c = n̂·x_0``."""
    p, n = _simplex("points", points, "N")
    batch = p.shape[:-2]
    out = _k.hyperplane(n, batch_size(batch), np.ascontiguousarray(p), _raise(degenerate))
    out = out.reshape(batch + (n + 1,))
    return out[..., :n], out[..., n]


def point_hyperplane_distance(
    x, points, *, degenerate: Degeneracy = "raise"
) -> tuple[np.ndarray, np.ndarray]:
    """Signed distance (eq. 11) from ``x (..., N)`` to the hyperplane of ``points (..., N, N)``
    and the foot point: ``(h (...), p (..., N))`` with ``h = n̂·(x − x_0) = N·V_N/V_{N−1}``
    (V_N the signed volume of (x_0, …, x_{N−1}, x), x last) and ``p = x − h·n̂``."""
    p, n = _simplex("points", points, "N")
    xs = _vector("x", x, n)
    batch, (xs, p) = broadcast_batch([("x", xs, 1), ("points", p, 2)])
    out = _k.point_hyperplane_distance(n, batch_size(batch), xs, p, _raise(degenerate))
    out = out.reshape(batch + (n + 1,))
    return out[..., 0], out[..., 1:]


def barycentric(x, points, *, degenerate: Degeneracy = "raise") -> np.ndarray:
    """Barycentric coordinates of ``x (..., N)`` in the K-simplex ``points (..., K+1, N)``,
    K ≤ N → ``(..., K+1)`` summing to 1, from the invariant Gram/Cramer form (for K < N, of the
    orthogonal projection of x onto the simplex's affine hull). x is inside iff all are ≥ 0."""
    shape_text = "(..., K+1, N) with 1 ≤ K ≤ N"
    p = finite_float64("points", points, 2, shape_text)
    n = _dim("points", p.shape[-1], shape_text, p.shape)
    k = p.shape[-2] - 1
    if not 1 <= k <= n:
        raise ValueError(f"points: expected shape {shape_text}, got {p.shape} (K = {k})")
    xs = _vector("x", x, n)
    batch, (xs, p) = broadcast_batch([("x", xs, 1), ("points", p, 2)])
    out = _k.barycentric(n, k, batch_size(batch), xs, p, _raise(degenerate))
    return out.reshape(batch + (k + 1,))


def side(x, points) -> np.ndarray:
    """Which side of the hyperplane of ``points (..., N, N)`` each ``x (..., N)`` lies on →
    int8 ``(...)``: the sign of ``V_N(x_0, …, x_{N−1}, x)`` with x last — +1 above (where the
    normal points), 0 on (to a relative 1e-12), −1 below; 0 for a degenerate hyperplane."""
    p, n = _simplex("points", points, "N")
    xs = _vector("x", x, n)
    batch, (xs, p) = broadcast_batch([("x", xs, 1), ("points", p, 2)])
    return _k.side(n, batch_size(batch), xs, p).reshape(batch).astype(np.int8)


def clip_segment(a, b, points, *, degenerate: Degeneracy = "raise") -> np.ndarray:
    """Parameter t (eq. 10) where the line ``a + t·(b − a)`` crosses the hyperplane of
    ``points (..., N, N)``: ``t = n̂·(a − x_0) / n̂·(a − b)``. The segment itself crosses iff
    ``0 ≤ t ≤ 1``. A segment parallel to the hyperplane is degenerate."""
    p, n = _simplex("points", points, "N")
    av, bv = _vector("a", a, n), _vector("b", b, n)
    batch, (av, bv, p) = broadcast_batch([("a", av, 1), ("b", bv, 1), ("points", p, 2)])
    return _k.clip_segment(n, batch_size(batch), av, bv, p, _raise(degenerate)).reshape(batch)


def ray_hyperplane(origin, direction, points, *, degenerate: Degeneracy = "raise") -> np.ndarray:
    """Ray parameter t of the hit with the hyperplane of ``points (..., N, N)`` (section
    "Ray Tracing"): ``t = n̂·(x_0 − C) / n̂·(P − C)`` with C = origin and P − C = direction (not
    normalized), so the hit is ``origin + t·direction``. Parallel rays are degenerate."""
    p, n = _simplex("points", points, "N")
    c, d = _vector("origin", origin, n), _vector("direction", direction, n)
    batch, (c, d, p) = broadcast_batch([("origin", c, 1), ("direction", d, 1), ("points", p, 2)])
    return _k.ray_hyperplane(n, batch_size(batch), c, d, p, _raise(degenerate)).reshape(batch)


def transform_normal(matrix, normal) -> np.ndarray:
    """Transforms normals ``(..., N)`` by linear maps ``(..., N, N)`` as pseudotensors ("Are
    Normals Vectors? Almost!"): ``cof(M)·N`` with ``cof(M) = det(M)·M^{−T}`` the cofactor
    matrix, which equals the generalized cross product of the transformed edges. For an
    orthogonal R it is ``det(R)·R·N`` (a reflection flips it). Singular M are allowed."""
    m = finite_float64("matrix", matrix, 2, "(..., N, N)")
    n = _dim("matrix", m.shape[-1], "(..., N, N)", m.shape)
    if m.shape[-2] != n:
        raise ValueError(f"matrix: expected shape (..., N, N), got {m.shape}")
    nv = _vector("normal", normal, n)
    batch, (m, nv) = broadcast_batch([("matrix", m, 2), ("normal", nv, 1)])
    return _k.transform_normal(n, batch_size(batch), m, nv).reshape(batch + (n,))
