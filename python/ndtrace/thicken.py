"""Thickening: surfaces and points in R^4 made into closed 3-manifolds the ray tracer can see.

Course notes, Part II(B): "A 4D object need not be volumetric to be rendered! … Surfaces ⇒
handled by 'tubing' with a shiny circle attached to each point, forcing it to be volumetric and
thus renderable. … even points can be made structurally visible in 4D by making them tiny
3-spheres". :func:`thicken_surface` builds the boundary of the tubular neighbourhood of a
triangulated surface (surface × circle, plus caps on its boundary) and :func:`thicken_points`
one mesh of small 3-spheres; both are re-exported by :mod:`ndtrace.mesh`.

Everything here is numpy-vectorised over vertices, edges, triangles and circle segments (no
Python loop over the mesh: the loops below run over BFS levels, conjugate-gradient steps and
the 6 vertices of a prism), so a segments = 64 Clifford torus or a cloud of 10⁶ points builds in
seconds without a Rust rebuild of the extension; the arrays go to the core through the ordinary
mesh path.
"""

from __future__ import annotations

import numbers

import numpy as np

from ._util import check_memory
from .geometry import generalized_cross

__all__ = ["thicken_surface", "thicken_points", "surface_normal_frames"]


# -- argument checks ------------------------------------------------------------------------------
def _radius(radius) -> float:
    if isinstance(radius, bool) or not isinstance(radius, numbers.Real):
        raise ValueError(f"radius: expected a positive number, got {radius!r}")
    r = float(radius)
    if not np.isfinite(r) or r <= 0:
        raise ValueError(f"radius: expected a positive finite number, got {radius!r}")
    return r


def _count(name: str, value, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name}: expected an integer in {low}…{high}, got {value!r}")
    if not low <= int(value) <= high:
        raise ValueError(f"{name}: expected an integer in {low}…{high}, got {value}")
    return int(value)


def _points4(name: str, points) -> np.ndarray:
    p = np.asarray(points)
    if p.dtype.kind not in "biuf":
        raise ValueError(f"{name}: expected real numbers, got dtype {p.dtype}")
    if p.ndim != 2 or p.shape[1] != 4:
        raise ValueError(f"{name}: expected shape ({name[0].upper()}, 4), points of R^4, got {p.shape}")
    p = np.ascontiguousarray(p, dtype=np.float64)
    bad = np.argwhere(~np.isfinite(p))
    if len(bad):
        raise ValueError(f"{name}[{bad[0][0]}]: holds NaN or infinite values")
    return p


def _triangles(triangles, vertices: np.ndarray) -> np.ndarray:
    """The checked triangles (T, 3) int64 of a 2-manifold (with or without boundary)."""
    t = np.asarray(triangles)
    if t.size == 0:
        raise ValueError("triangles: expected at least one triangle, got none")
    if t.dtype.kind not in "iu":
        raise ValueError(f"triangles: expected integer vertex indices, got dtype {t.dtype}")
    if t.ndim != 2 or t.shape[1] != 3:
        raise ValueError(f"triangles: expected shape (T, 3), got {t.shape}")
    t = np.ascontiguousarray(t, dtype=np.int64)
    bad = np.argwhere((t < 0) | (t >= len(vertices)))
    if len(bad):
        i, k = bad[0]
        raise ValueError(f"triangles[{i}][{k}]: vertex index {t[i, k]} out of range: there are "
                         f"{len(vertices)} vertices")
    rep = np.flatnonzero((t[:, 0] == t[:, 1]) | (t[:, 1] == t[:, 2]) | (t[:, 0] == t[:, 2]))
    if len(rep):
        raise ValueError(f"triangles[{rep[0]}]: repeats a vertex: {t[rep[0]].tolist()}")
    x = vertices[t]
    area = _areas(x)
    scale = max(float(np.abs(vertices).max()), 1e-300)
    flat = np.flatnonzero(area <= 1e-12 * scale * scale)
    if len(flat):
        raise ValueError(f"triangles[{flat[0]}]: has zero area (its vertices are collinear)")
    # Every edge in at most two triangles; every vertex's triangles one fan (a disk or half-disk).
    key = np.sort(t, axis=1)
    order = np.lexsort(key.T[::-1])
    again = np.flatnonzero(np.all(key[order[1:]] == key[order[:-1]], axis=1))
    if len(again):
        i = int(np.max(order[again[0]:again[0] + 2]))
        raise ValueError(f"triangles[{i}]: appears twice ({t[i].tolist()}): not a manifold surface")
    edges, count = _edges(t)[1:3]
    if np.any(count > 2):
        a, b = edges[np.argmax(count > 2)]
        raise ValueError(f"triangles: the edge ({a}, {b}) belongs to {count.max()} triangles: "
                         "not a manifold surface")
    v = len(vertices)
    corners = np.bincount(t.ravel(), minlength=v)
    inner = np.bincount(edges[count == 2].ravel(), minlength=v)
    border = np.bincount(edges[count == 1].ravel(), minlength=v)
    fans = corners - inner  # 1 per open fan, 0 per closed one
    odd = np.flatnonzero((corners > 0) & ((fans > 1) | (border != 2 * fans)))
    if len(odd):
        raise ValueError(f"triangles: vertex {odd[0]} is not a manifold point (its triangles "
                         "form more than one fan)")
    return t


def _areas(x: np.ndarray) -> np.ndarray:
    e1, e2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    g = np.einsum("ij,ij->i", e1, e1) * np.einsum("ij,ij->i", e2, e2) - np.einsum("ij,ij->i", e1, e2) ** 2
    return 0.5 * np.sqrt(np.maximum(g, 0))


def _edges(t: np.ndarray):
    """(edge of each triangle side (T, 3) → row of ``edges``, edges (E, 2) with a < b, count)
    where side j of triangle i is the edge opposite its corner j."""
    sides = np.stack([t[:, [1, 2]], t[:, [2, 0]], t[:, [0, 1]]], axis=1).reshape(-1, 2)
    edges, inverse, count = np.unique(np.sort(sides, axis=1), axis=0, return_inverse=True,
                                      return_counts=True)
    return inverse.reshape(-1, 3), edges, count


# -- normal-plane frames ---------------------------------------------------------------------------
def _polar2(m: np.ndarray) -> np.ndarray:
    """The nearest orthogonal matrices to 2×2 matrices ``m`` (…, 2, 2) (polar factor)."""
    u, _, vt = np.linalg.svd(m)
    return u @ vt


def _bfs_tree(n: int, edges: np.ndarray):
    """A breadth-first spanning forest of the vertex graph, level by level (vectorised):
    ``levels``: list of (children, parents, edge rows) per level."""
    seen = np.zeros(n, dtype=bool)
    levels = []
    a, b = edges[:, 0], edges[:, 1]
    ends = np.concatenate([a, b])
    others = np.concatenate([b, a])
    rows = np.concatenate([np.arange(len(edges))] * 2)
    order = np.argsort(ends, kind="stable")
    ends, others, rows = ends[order], others[order], rows[order]
    start = np.searchsorted(ends, np.arange(n + 1))
    for root in range(n):
        if seen[root]:
            continue
        seen[root] = True
        frontier = np.array([root])
        while len(frontier):
            # All (frontier vertex → neighbour) pairs, via the CSR adjacency.
            lo, hi = start[frontier], start[frontier + 1]
            size = hi - lo
            if size.sum() == 0:
                break
            idx = np.repeat(lo - np.cumsum(size) + size, size) + np.arange(size.sum())
            nb, rw = others[idx], rows[idx]
            par = ends[idx]
            fresh = ~seen[nb]
            nb, rw, par = nb[fresh], rw[fresh], par[fresh]
            nb, first = np.unique(nb, return_index=True)
            if len(nb) == 0:
                break
            seen[nb] = True
            levels.append((nb, par[first], rw[first]))
            frontier = nb
    return levels


def surface_normal_frames(vertices, triangles):
    """Continuous orthonormal frames of the normal planes of a triangulated surface in R^4.

    Returns ``(frames (V, 4, 2), parity (T, 3))``: at vertex v the columns ``n1, n2`` of
    ``frames[v]`` span the normal plane (the orthogonal complement of the area-weighted mean of
    its triangles' tangent planes), chosen as the course's parallel transport ("Curves: the
    parallel transport frame", carried from curves to surfaces): along a breadth-first spanning
    tree each vertex takes the frame of its parent projected into its own normal plane and made
    orthonormal (the minimal rotation), and the holonomy left on the other edges — a loop around
    a torus, say — is then spread over all vertices by a least-squares rotation of each frame in
    its plane (the surface analogue of ``frames.optimal_periodic``), so no twist seam remains.
    ``parity[i, j]`` is 1 where the frame at corner j of triangle i is mirrored relative to
    corner 0 (a non-orientable normal bundle, e.g. that of a Möbius band): the circle at that
    corner runs the other way.
    """
    v = _points4("vertices", vertices)
    t = _triangles(triangles, v)
    return _frames(v, t)


def _frames(v: np.ndarray, t: np.ndarray):
    n = len(v)
    # 1. Tangent planes: the area-weighted sum of the triangles' tangent-plane projectors;
    #    its two smallest eigenvectors span the vertex's normal plane.
    x = v[t]
    e1 = x[:, 1] - x[:, 0]
    u = e1 / np.linalg.norm(e1, axis=1, keepdims=True)
    e2 = x[:, 2] - x[:, 0]
    w = e2 - np.einsum("ij,ij->i", e2, u)[:, None] * u
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    area = _areas(x)
    proj = area[:, None, None] * (u[:, :, None] * u[:, None, :] + w[:, :, None] * w[:, None, :])
    sums = np.zeros((n, 4, 4))
    for j in range(3):
        np.add.at(sums, t[:, j], proj)
    frames = np.linalg.eigh(sums)[1][:, :, :2].copy()
    side_edge, edges, _ = _edges(t)
    a, b = edges[:, 0], edges[:, 1]
    # 2. Parallel transport along a spanning tree, level by level.
    for child, parent, _ in _bfs_tree(n, edges):
        m = np.swapaxes(frames[child], 1, 2) @ frames[parent]
        frames[child] = frames[child] @ _polar2(m)
    # 3. What is left on each edge: q = the transport from a's frame to b's (a rotation, or a
    #    reflection where the normal bundle is not orientable along it).
    q = _polar2(np.swapaxes(frames[b], 1, 2) @ frames[a])
    eps = np.where(np.linalg.det(q) > 0, 1.0, -1.0)
    # 4. Spread the holonomy: unit vectors x_v ∈ R² (the new n1 in the old frame) minimising
    #    Σ |x_b − q x_a|², the smallest eigenvector of the connection Laplacian (angular
    #    synchronisation; a least-squares fit of the phases themselves would trap 2π vortices
    #    where the wrapped angles around a triangle do not sum to 0). Inverse iteration from the
    #    tree-transported frames, each step a Jacobi-preconditioned conjugate-gradient solve.
    deg = (np.bincount(a, minlength=n) + np.bincount(b, minlength=n))[:, None] + 1e-3
    shift = 1e-3

    def laplacian(x):
        r = x[b] - np.einsum("eij,ej->ei", q, x[a])
        out = shift * x
        np.add.at(out, b, r)
        np.add.at(out, a, -np.einsum("eji,ej->ei", q, r))
        return out

    x = np.tile([1.0, 0.0], (n, 1))
    for _ in range(6):
        y = x.copy()
        res = x - laplacian(y)
        z = res / deg
        p = z.copy()
        rz = np.sum(res * z)
        for _ in range(10 * int(np.sqrt(n)) + 100):
            if np.sum(res * res) <= 1e-20 * n:
                break
            ap = laplacian(p)
            step = rz / np.sum(p * ap)
            y += step * p
            res -= step * ap
            z = res / deg
            rz, rz_old = np.sum(res * z), rz
            p = z + (rz / rz_old) * p
        x = y / np.maximum(np.linalg.norm(y, axis=1, keepdims=True), 1e-300)
    alpha = np.arctan2(x[:, 1], x[:, 0])
    c, s = np.cos(alpha), np.sin(alpha)
    rot = np.stack([np.stack([c, s], -1), np.stack([-s, c], -1)], -1)  # columns (c, s), (−s, c)
    frames = frames @ rot
    # 5. Parities per triangle corner: a corner is mirrored relative to corner 0 when the edge
    #    between them reflects.
    reflect = eps < 0
    par1 = reflect[side_edge[:, 2]]  # edge (0, 1) is opposite corner 2
    par2 = reflect[side_edge[:, 1]]  # edge (2, 0) is opposite corner 1
    bad = np.flatnonzero(reflect[side_edge[:, 0]] != (par1 ^ par2))
    if len(bad):
        raise ValueError(f"triangles[{bad[0]}]: the normal planes at its corners turn too much "
                         "between them (refine the surface)")
    parity = np.stack([np.zeros(len(t), dtype=bool), par1, par2], axis=1)
    return frames, parity


# -- prisms into tetrahedra ------------------------------------------------------------------------
def _split_prisms(bottom: np.ndarray, top: np.ndarray) -> np.ndarray:
    """Triangular prisms (bottom (K, 3), top (K, 3) point ids, top[j] above bottom[j]) cut into
    3 tetrahedra each (3K, 4), every quad face split by the diagonal through its smallest point
    id (Dompierre et al. 1999, "How to subdivide pyramids, prisms and hexahedra into
    tetrahedra"): neighbouring prisms split a shared quad the same way, for any global order."""
    six = np.concatenate([bottom, top], axis=1)
    # Rotate/mirror each prism so that its smallest id is vertex 0: the 6 symmetries that keep
    # the bottom/top structure (a top vertex becomes the bottom's by swapping top and bottom).
    perms = np.array([[0, 1, 2, 3, 4, 5], [1, 2, 0, 4, 5, 3], [2, 0, 1, 5, 3, 4],
                      [3, 5, 4, 0, 2, 1], [4, 3, 5, 1, 0, 2], [5, 4, 3, 2, 1, 0]])
    p = six[np.arange(len(six))[:, None], perms[np.argmin(six, axis=1)]]
    first = np.minimum(p[:, 1], p[:, 5]) < np.minimum(p[:, 2], p[:, 4])
    case_a = np.array([[0, 1, 2, 5], [0, 1, 5, 4], [0, 4, 5, 3]])
    case_b = np.array([[0, 1, 2, 4], [0, 4, 2, 5], [0, 4, 5, 3]])
    pick = np.where(first[:, None, None], case_a[None], case_b[None])
    return np.take_along_axis(p[:, None, :], pick.reshape(len(p), 1, 12), axis=2).reshape(-1, 4)


def _orient(points: np.ndarray, tets: np.ndarray, outward: np.ndarray) -> np.ndarray:
    """Tetrahedra with two indices swapped where their normal (eq. 6) points against
    ``outward`` (T, 4)."""
    x = points[tets]
    normal = generalized_cross(x[:, 1:] - x[:, :1])
    flip = np.einsum("ij,ij->i", normal, outward) < 0
    tets = tets.copy()
    tets[flip, 0], tets[flip, 1] = tets[flip, 1], tets[flip, 0].copy()
    return tets


# -- the tube around a surface ---------------------------------------------------------------------
def thicken_surface(vertices, triangles, radius, segments=16):
    """The boundary of the tubular neighbourhood of a triangulated surface in R^4 (course notes
    Part II(B): "tubing with a shiny circle attached to each point"): ``(vertices (V·segments, 4),
    simplices (S, 4))``, a closed, consistently outward-oriented mesh of tetrahedra.

    At every vertex p of the surface, ``segments`` points ``p + radius·(cos θ_k n1 + sin θ_k n2)``
    on the circle in its normal plane, θ_k = 2πk/segments, with the continuous frames of
    :func:`surface_normal_frames` (parallel transport, holonomy spread by least squares: no twist
    seam; a mirrored frame — a non-orientable normal bundle — makes that corner's circle run
    backwards). Each triangle × circle segment is a prism, each boundary edge × the fan of the
    circle's polygon (a cap) too; each prism is cut into 3 tetrahedra (:func:`_split_prisms`).
    For a flat patch of area A and boundary length L the 3-volume is exactly
    ``A·segments·2r·sin(π/segments) + L·(segments/2)·r²·sin(2π/segments)`` (perimeter and area
    of the inscribed polygon), and about 2π·r·A for a small radius on a curved surface.

    Raises ValueError naming the argument for wrong shapes, NaN, radius ≤ 0, segments < 3,
    degenerate or repeated triangles and non-manifold ones (an edge in three triangles, two
    fans at one vertex).
    """
    v = _points4("vertices", vertices)
    r = _radius(radius)
    m = _count("segments", segments, 3, 4096)
    t = _triangles(triangles, v)
    # The arrays below, before any is made: per circle point its position, offset and normal
    # frame; per prism (triangle × segment) its three tetrahedra, their corners and radial
    # directions (the largest temporaries).
    check_memory(len(v) * m * 4 * 8 * 4.0 + len(t) * m * 800.0,
                 f"thicken_surface of {len(v)} vertices and {len(t)} triangles × segments = {m}")
    frames, parity = _frames(v, t)
    # 1. The circles: point id v·m + k at angle θ_k around vertex v.
    theta = 2 * np.pi * np.arange(m) / m
    offsets = r * (np.cos(theta)[None, :, None] * frames[:, None, :, 0]
                   + np.sin(theta)[None, :, None] * frames[:, None, :, 1])  # (V, m, 4)
    points = (v[:, None, :] + offsets).reshape(-1, 4)
    radial = offsets.reshape(-1, 4)

    def pid(vertex, k, mirrored):
        return vertex * m + np.where(mirrored, -k, k) % m

    # 2. Sides: triangle × segment (k, k+1), the circle index mirrored at mirrored corners.
    k = np.arange(m)
    tt, kk = np.repeat(np.arange(len(t)), m), np.tile(k, len(t))
    corner, par = t[tt], parity[tt]
    bottom = pid(corner, kk[:, None], par)
    top = pid(corner, kk[:, None] + 1, par)
    sides = _split_prisms(bottom, top)
    sides = _orient(points, sides, radial[sides].sum(axis=1))
    # 3. Caps: boundary edge (a, b) of triangle (a, b, c) × the fan (0, j, j+1) of the polygon.
    side_edge, edges, count = _edges(t)
    tri, opp = np.nonzero(count[side_edge] == 1)
    caps = np.empty((0, 4), dtype=np.int64)
    if len(tri):
        ia, ib = (opp + 1) % 3, (opp + 2) % 3
        a, b, c = t[tri, ia], t[tri, ib], t[tri, opp]
        pa, pb = parity[tri, ia], parity[tri, ib]
        j = np.arange(1, m - 1)
        fan = np.stack([np.zeros_like(j), j, j + 1], axis=1)  # (m−2, 3)
        ee = np.repeat(np.arange(len(tri)), m - 2)
        ff = np.tile(fan, (len(tri), 1))
        cap_bottom = pid(a[ee, None], ff, pa[ee, None])
        cap_top = pid(b[ee, None], ff, pb[ee, None])
        caps = _split_prisms(cap_bottom, cap_top)
        # Outward: in the triangle's plane, perpendicular to the edge, away from c.
        pa4, pb4, pc4 = v[a], v[b], v[c]
        d = pb4 - pa4
        away = 0.5 * (pa4 + pb4) - pc4
        away -= (np.einsum("ij,ij->i", away, d) / np.einsum("ij,ij->i", d, d))[:, None] * d
        caps = _orient(points, caps, np.repeat(away, 3 * (m - 2), axis=0))
    return points, np.concatenate([sides, caps]).astype(np.int64)


# -- points as small 3-spheres ---------------------------------------------------------------------
def _sphere_template(subdivisions: int):
    """The unit 3-sphere of the point cloud: (vertices, outward tetrahedra)."""
    if subdivisions == 1:  # the 5-cell: 5 vertices, 5 tetrahedra
        e = np.eye(5) - 0.2
        basis = np.linalg.svd(e)[2][:4]  # an orthonormal basis of the hyperplane Σx = 0
        verts = e @ basis.T
        tets = np.array([[j for j in range(5) if j != i] for i in range(5)])
    else:  # the 16-cell, each tetrahedron cut into 8 (subdivisions − 2) times
        verts = np.concatenate([np.eye(4), -np.eye(4)])
        tets = np.array([[i + 4 * (s >> i & 1) for i in range(4)] for s in range(16)])
        for _ in range(subdivisions - 2):
            verts, tets = _refine(verts, tets)
    verts = verts / np.linalg.norm(verts, axis=1, keepdims=True)
    return verts, _orient(verts, tets, verts[tets].sum(axis=1))


def _refine(verts: np.ndarray, tets: np.ndarray):
    """Each tetrahedron into 8 (Bey's regular red refinement), edge midpoints shared."""
    pairs = [(0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3)]
    e = np.sort(np.stack([tets[:, [i, j]] for i, j in pairs], axis=1).reshape(-1, 2), axis=1)
    uniq, inv = np.unique(e, axis=0, return_inverse=True)
    mid = len(verts) + inv.reshape(-1, 6)
    verts = np.concatenate([verts, 0.5 * (verts[uniq[:, 0]] + verts[uniq[:, 1]])])
    x0, x1, x2, x3 = tets.T
    m01, m02, m03, m12, m13, m23 = mid.T
    children = [(x0, m01, m02, m03), (m01, x1, m12, m13), (m02, m12, x2, m23), (m03, m13, m23, x3),
                (m01, m02, m03, m13), (m01, m02, m12, m13), (m02, m03, m13, m23), (m02, m12, m13, m23)]
    return verts, np.concatenate([np.stack(c, axis=1) for c in children])


def thicken_points(points, radius, subdivisions=1):
    """Each point of R^4 a small 3-sphere of ``radius``, all in one mesh ``(vertices,
    simplices)`` (one object, one BVH), course notes Part II(B): "even points can be made
    structurally visible in 4D by making them tiny 3-spheres".

    ``subdivisions`` picks the sphere: 1 the 5-cell (5 vertices, 5 tetrahedra per point, the
    least a closed 3-manifold needs), 2 the 16-cell (8, 16), k ≥ 3 the 16-cell cut 8-fold k − 2
    times and pushed onto the sphere (32 vertices and 128 tetrahedra at k = 3). The default is
    the 5-cell because a million points must fit: 5·10⁶ vertices and tetrahedra load from an
    ``.npz`` mesh ``file`` in about 80 s and 3.3 GB peak on the 2-core machine (``bench/surfaces.py
    points``), where the 16-cell would need about 10 GB; a point only a few retina cells wide
    shows no facets either way. Raises ValueError naming the argument.
    """
    p = _points4("points", points)
    r = _radius(radius)
    k = _count("subdivisions", subdivisions, 1, 5)
    verts, tets = _sphere_template(k)
    check_memory(len(p) * (len(verts) * 4 * 8 * 2.0 + len(tets) * 4 * 8 * 2.0),
                 f"thicken_points of {len(p)} points × {len(verts)} vertices and {len(tets)} tetrahedra each")
    out_v = (p[:, None, :] + r * verts[None]).reshape(-1, 4)
    base = (np.arange(len(p), dtype=np.int64) * len(verts))[:, None, None]
    out_t = (base + tets[None]).reshape(-1, 4)
    return out_v, out_t
