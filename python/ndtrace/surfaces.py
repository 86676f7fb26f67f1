"""Surfaces in R^4, the course's examples (Part II(B), "4D knotted surfaces", and the
complex-function surfaces of Part II): each generator returns ``(vertices (V, 4), triangles
(T, 3))``, a manifold triangulation ready for :func:`ndtrace.mesh.thicken_surface` or the
``surface`` scene shape::

    vertices, triangles = ndtrace.surfaces.clifford_torus(48)
    mesh = ndtrace.mesh.thicken_surface(vertices, triangles, radius=0.05, segments=16)
"""

from __future__ import annotations

import numbers

import numpy as np

from ._util import check_memory

__all__ = ["clifford_torus", "spun_knot", "complex_graph", "riemann_root", "fermat_patch", "grid_triangles"]


def _int(name: str, value, low: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or int(value) < low:
        raise ValueError(f"{name}: expected an integer ≥ {low}, got {value!r}")
    return int(value)


#: Bytes a generator holds per vertex of its grid while it builds it (coordinates, parameter
#: grids and their temporaries, two triangles of indices and theirs): an estimate for the memory
#: guard.
_BYTES_PER_VERTEX = 600.0


def _budget(vertices: float, what: str) -> None:
    """Refuses, before anything is built, a surface of ``vertices`` grid points too big for the
    memory guard (a ValueError naming ``what`` and the limit)."""
    check_memory(vertices * _BYTES_PER_VERTEX, f"{what}: a surface of {vertices:.0f} vertices")


def _finite(vertices: np.ndarray, what: str) -> np.ndarray:
    """``vertices``, if all are finite; else a ValueError naming the arguments ``what`` that
    made them overflow (or NaN) and the first such vertex."""
    bad = np.flatnonzero(~np.isfinite(vertices).all(axis=1))
    if len(bad):
        raise ValueError(f"{what}: vertex {bad[0]} is {vertices[bad[0]].tolist()}: the surface "
                         "must be finite (a value too large, or a function that overflows)")
    return vertices


def grid_triangles(rows: int, cols: int, wrap_rows: bool = False, wrap_cols: bool = False) -> np.ndarray:
    """Triangles (T, 3) of a ``rows × cols`` grid of vertices numbered ``i·cols + j``, each cell
    split in two, optionally wrapped around (a cylinder or a torus)."""
    i, j = (g.ravel() for g in np.meshgrid(np.arange(rows if wrap_rows else rows - 1),
                                           np.arange(cols if wrap_cols else cols - 1), indexing="ij"))
    i1, j1 = (i + 1) % rows, (j + 1) % cols
    a, b, c, d = i * cols + j, i1 * cols + j, i1 * cols + j1, i * cols + j1
    return np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)]).astype(np.int64)


def clifford_torus(samples: int = 48, radii=(2 ** -0.5, 2 ** -0.5)):
    """The Clifford torus (r1 cos u, r1 sin u, r2 cos v, r2 sin v): with r1 = r2 = 1/√2 the
    flat torus splitting the unit 3-sphere into two solid tori; area 4π²·r1·r2. ``samples`` per
    circle."""
    n = _int("samples", samples, 3)
    r1, r2 = (float(x) for x in radii)
    _budget(float(n) * n, f"samples = {n}")
    u, v = np.meshgrid(2 * np.pi * np.arange(n) / n, 2 * np.pi * np.arange(n) / n, indexing="ij")
    with np.errstate(over="ignore", invalid="ignore"):  # refused below, naming radii
        vertices = np.stack([r1 * np.cos(u), r1 * np.sin(u), r2 * np.cos(v), r2 * np.sin(v)], -1).reshape(-1, 4)
    return _finite(vertices, "radii"), grid_triangles(n, n, True, True)


def _trefoil_arc(samples: int) -> tuple[np.ndarray, float]:
    """A knotted arc in the half-space y > −3.4 of R^3 with both ends on the plane y = −3.4:
    the trefoil (sin s + 2 sin 2s, cos s − 2 cos 2s, −sin 3s) cut open at its lowest point
    s = π, each end bent down to the plane by a cubic Hermite leg arriving perpendicularly."""
    cut, floor = 0.35, -3.4

    def knot(s):
        return np.stack([np.sin(s) + 2 * np.sin(2 * s), np.cos(s) - 2 * np.cos(2 * s), -np.sin(3 * s)], -1)

    def tangent(s):
        return np.stack([np.cos(s) + 4 * np.cos(2 * s), -np.sin(s) + 4 * np.sin(2 * s), -3 * np.cos(3 * s)], -1)

    legs = max(samples // 12, 3)
    body = np.linspace(np.pi + cut, 3 * np.pi - cut, samples - 2 * legs)
    pieces = []
    for s_end, sign in ((np.pi + cut, -1.0), (3 * np.pi - cut, 1.0)):
        p0 = knot(np.array(s_end))
        q = np.array([p0[0], floor, p0[2]])
        t0 = sign * tangent(np.array(s_end)) * 0.35  # leaving the knot outward
        t1 = np.array([0.0, -1.5, 0.0])  # arriving straight down
        h = np.linspace(0, 1, legs + 1)[1:, None]
        leg = ((2 * h**3 - 3 * h**2 + 1) * p0 + (h**3 - 2 * h**2 + h) * t0
               + (-2 * h**3 + 3 * h**2) * q + (h**3 - h**2) * t1)
        pieces.append(leg)
    return np.concatenate([pieces[0][::-1], knot(body), pieces[1]]), floor


def spun_knot(samples: int = 96, sectors: int = 32):
    """Artin's spun trefoil, a knotted 2-sphere in R^4 (course notes, "4D knotted surfaces"):
    a knotted arc (x, y, z) in the half-space y ≥ y0 with its ends on the plane y = y0 is spun
    about that plane, (x, y, z) ↦ (x, z, (y − y0) cos θ, (y − y0) sin θ). ``samples`` along the
    arc, ``sectors`` around; the arc's ends become the sphere's two poles."""
    n = _int("samples", samples, 8)
    k = _int("sectors", sectors, 3)
    _budget(float(n) * k, f"samples × sectors = {n} × {k}")
    arc, floor = _trefoil_arc(n)
    inner = arc[1:-1]
    th = 2 * np.pi * np.arange(k) / k
    h = inner[:, 1] - floor
    ring = np.stack([np.broadcast_to(inner[:, None, 0], (len(inner), k)),
                     np.broadcast_to(inner[:, None, 2], (len(inner), k)),
                     h[:, None] * np.cos(th), h[:, None] * np.sin(th)], -1).reshape(-1, 4)
    poles = np.array([[arc[0, 0], arc[0, 2], 0, 0], [arc[-1, 0], arc[-1, 2], 0, 0]])
    vertices = np.concatenate([ring, poles]) * 0.4
    rows = len(inner)
    tri = [grid_triangles(rows, k, False, True)]
    j = np.arange(k)
    south, north = rows * k, rows * k + 1
    tri.append(np.stack([np.full(k, south), (j + 1) % k, j], 1))
    last = (rows - 1) * k
    tri.append(np.stack([np.full(k, north), last + j, last + (j + 1) % k], 1))
    return vertices, np.concatenate(tri).astype(np.int64)


def _disk(radius: float, rings: int, sectors: int):
    """A polar grid of the disk |ζ| ≤ radius: (ζ values (V,), triangles), centre first."""
    r = radius * np.arange(1, rings + 1) / rings
    th = 2 * np.pi * np.arange(sectors) / sectors
    zeta = np.concatenate([[0], (r[:, None] * np.exp(1j * th)).ravel()])
    grid = grid_triangles(rings, sectors, False, True) + 1
    j = np.arange(sectors)
    fan = np.stack([np.zeros(sectors, dtype=np.int64), 1 + j, 1 + (j + 1) % sectors], 1)
    return zeta, np.concatenate([fan, grid])


def _complex_vertices(z: np.ndarray, w: np.ndarray) -> np.ndarray:
    return np.stack([z.real, z.imag, w.real, w.imag], -1)


def complex_graph(f, radius: float = 1.0, rings: int = 16, sectors: int = 48):
    """The graph {(z, f(z)) : |z| ≤ radius} ⊂ C² = R^4 of a complex function (a callable on
    complex numpy arrays), vertices (Re z, Im z, Re w, Im w); e.g. ``complex_graph(lambda z:
    z**2)``."""
    rings, sectors = _int("rings", rings, 1), _int("sectors", sectors, 3)
    _budget(float(rings) * sectors, f"rings × sectors = {rings} × {sectors}")
    with np.errstate(over="ignore", invalid="ignore"):  # refused below, naming radius
        zeta, tri = _disk(float(radius), rings, sectors)
    w = np.asarray(f(zeta), dtype=np.complex128)
    if w.shape != zeta.shape:
        raise ValueError(f"f: expected one complex value per point, an array of shape {zeta.shape}, "
                         f"got shape {w.shape}")
    return _finite(_complex_vertices(zeta, w), "f, radius"), tri


def riemann_root(n: int = 2, radius: float = 1.0, rings: int = 16, sectors: int = 48):
    """The Riemann surface of w = z^(1/n) over |z| ≤ radius, all n sheets as one smooth patch:
    parametrised by ζ over |ζ| ≤ radius^(1/n) as (z, w) = (ζⁿ, ζ); its projection to the z plane
    winds n times around the branch point z = 0."""
    n = _int("n", n, 1)
    rings, sectors = _int("rings", rings, 1), _int("sectors", sectors, 3)
    _budget(float(rings) * sectors * n, f"rings × sectors × n = {rings} × {sectors} × {n}")
    with np.errstate(over="ignore", invalid="ignore"):  # refused below, naming radius
        zeta, tri = _disk(float(radius) ** (1 / n), rings, sectors * n)
        vertices = _complex_vertices(zeta**n, zeta)
    return _finite(vertices, "radius"), tri


def fermat_patch(n: int = 3, k: int = 0, l: int = 0, samples: int = 24, extent: float = 1.0):
    """One of the n² patches of the Fermat curve zⁿ + wⁿ = 1 in C² (Hanson's "Fermat surface",
    the CP² slice of the course): z = e^{2πik/n} cos(τ)^{2/n}, w = e^{2πil/n} sin(τ)^{2/n} over
    τ = ξ + iη, 0 ≤ ξ ≤ π/2, |η| ≤ extent (then zⁿ + wⁿ = cos²τ + sin²τ = 1)."""
    n = _int("n", n, 2)
    m = _int("samples", samples, 2)
    _budget(2.0 * m * m, f"samples = {m}")
    xi, eta = np.meshgrid(np.linspace(0, np.pi / 2, m), np.linspace(-extent, extent, 2 * m), indexing="ij")
    tau = xi + 1j * eta
    with np.errstate(over="ignore", invalid="ignore"):  # refused below, naming extent
        z = np.exp(2j * np.pi * k / n) * np.cos(tau) ** (2 / n)
        w = np.exp(2j * np.pi * l / n) * np.sin(tau) ** (2 / n)
        vertices = _complex_vertices(z.ravel(), w.ravel())
    return _finite(vertices, "extent"), grid_triangles(m, 2 * m)
