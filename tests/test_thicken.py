"""Surfaces and points in R^4 (issue 21): ``ndtrace.mesh.thicken_surface`` — closed and
consistently outward oriented (every triangle in exactly two tetrahedra with opposite induced
orientations), vertices within the radius of the surface, the exact polygonal-circle 3-volume of
a flat patch and ≈ 2π·r·area on the Clifford torus, no twist seam, a non-orientable normal
bundle — ``thicken_points``, the generators and the argument errors."""

from __future__ import annotations

import numpy as np
import pytest

import ndtrace
from ndtrace import surfaces
from ndtrace.geometry import generalized_cross
from ndtrace.mesh import thicken_points, thicken_surface
from ndtrace.thicken import surface_normal_frames


def ridge_balance(simplices: np.ndarray):
    """(how many tetrahedra share each triangle: min and max, the largest |sum of induced
    orientations| over triangles): a closed consistently oriented mesh gives (2, 2, 0)."""
    faces, signs = [], []
    for i in range(4):
        f = np.delete(simplices, i, axis=1)
        order = np.argsort(f, axis=1, kind="stable")
        inversions = sum((order[:, a] > order[:, b]).astype(int) for a in range(3) for b in range(a + 1, 3))
        faces.append(np.sort(f, axis=1))
        signs.append((-1) ** i * (-1) ** inversions)
    _, inverse, count = np.unique(np.concatenate(faces), axis=0, return_inverse=True, return_counts=True)
    total = np.bincount(inverse.ravel(), np.concatenate(signs))
    return count.min(), count.max(), np.abs(total).max()


def volumes(vertices, simplices):
    """(3-volume of the mesh, the 4-volume it encloses: Σ N_s·x_0 / 4!)."""
    x = vertices[simplices]
    n = generalized_cross(x[:, 1:] - x[:, :1])
    return np.linalg.norm(n, axis=1).sum() / 6, np.einsum("ij,ij->i", n, x[:, 0]).sum() / 24


def area(vertices, triangles):
    x = vertices[triangles]
    e1, e2 = x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]
    g = (e1 * e1).sum(1) * (e2 * e2).sum(1) - (e1 * e2).sum(1) ** 2
    return 0.5 * np.sqrt(g).sum()


def distance_to_surface(points, vertices, triangles):
    """Brute-force distance from each point to the triangulated surface (exact point–triangle
    distance by projected Gram solves, checked at the vertices, edges and faces)."""
    best = np.full(len(points), np.inf)
    for tri in vertices[triangles]:
        a, b, c = tri
        for p, q in ((a, b), (b, c), (c, a)):
            d = q - p
            s = np.clip((points - p) @ d / (d @ d), 0, 1)
            best = np.minimum(best, np.linalg.norm(points - p - s[:, None] * d, axis=1))
        e = np.stack([b - a, c - a], 1)
        coef = np.linalg.solve(e.T @ e, e.T @ (points - a).T).T
        inside = (coef >= 0).all(1) & (coef.sum(1) <= 1)
        foot = a + coef @ e.T
        best = np.where(inside, np.minimum(best, np.linalg.norm(points - foot, axis=1)), best)
    return best


def flat_patch(rows=5, cols=7, size=(1.0, 2.0)):
    g = np.stack(np.meshgrid(np.linspace(0, size[0], rows), np.linspace(0, size[1], cols), indexing="ij"), -1)
    return np.c_[g.reshape(-1, 2), np.zeros((rows * cols, 2))], surfaces.grid_triangles(rows, cols)


def random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(4, 4)))
    return q * np.sign(np.diag(r))


GENERATORS = {
    "clifford_torus": lambda: surfaces.clifford_torus(24),
    "spun_knot": lambda: surfaces.spun_knot(48, 16),
    "z_squared": lambda: surfaces.complex_graph(lambda z: z**2, rings=6, sectors=16),
    "sqrt": lambda: surfaces.riemann_root(2, rings=6, sectors=12),
    "fermat": lambda: surfaces.fermat_patch(3, samples=10),
}


@pytest.mark.parametrize("name", sorted(GENERATORS))
@pytest.mark.parametrize("segments", [3, 8])
def test_thickened_surfaces_are_closed_outward_and_within_the_radius(name, segments):
    v, t = GENERATORS[name]()
    r = 0.03
    tv, ts = thicken_surface(v, t, r, segments=segments)
    assert tv.shape == (len(v) * segments, 4) and ts.shape[1] == 4 and ts.dtype == np.int64
    assert ridge_balance(ts) == (2, 2, 0)
    vol3, vol4 = volumes(tv, ts)
    assert vol4 > 0  # outward
    # Every tetrahedron's normal points away from the surface (locally outward, not only in sum).
    x = tv[ts]
    n = generalized_cross(x[:, 1:] - x[:, :1])
    centre = x.mean(1)
    sample = np.random.default_rng(0).choice(len(ts), 300, replace=False)
    d = distance_to_surface(centre[sample], v, t)
    probe = centre[sample] + 0.3 * r * n[sample] / np.linalg.norm(n[sample], axis=1, keepdims=True)
    # (All but a few near the Fermat patch's branch points, where another sheet comes close.)
    assert np.mean(distance_to_surface(probe, v, t) > d) >= 0.97
    pick = np.random.default_rng(1).choice(len(tv), min(400, len(tv)), replace=False)
    assert distance_to_surface(tv[pick], v, t).max() <= r + 1e-9


@pytest.mark.parametrize("segments", [3, 5, 8, 32])
def test_flat_patch_volume_is_the_polygonal_circle_formula_exactly(segments):
    rng = np.random.default_rng(segments)
    v, t = flat_patch()
    rot = random_rotation(rng)
    v = v @ rot.T + rng.normal(size=4)
    r, m = 0.1, segments
    tv, ts = thicken_surface(v, t, r, m)
    vol3, _ = volumes(tv, ts)
    area_, boundary = 2.0, 6.0
    exact = area_ * m * 2 * r * np.sin(np.pi / m) + boundary * m / 2 * r * r * np.sin(2 * np.pi / m)
    assert vol3 == pytest.approx(exact, rel=1e-12)


def test_clifford_torus_volume_is_two_pi_r_area_at_64_segments():
    v, t = surfaces.clifford_torus(64)
    r = 0.02
    tv, ts = thicken_surface(v, t, r, segments=64)
    vol3, vol4 = volumes(tv, ts)
    assert vol3 == pytest.approx(2 * np.pi * r * area(v, t), rel=0.01)
    assert vol3 == pytest.approx(2 * np.pi * r * 2 * np.pi**2, rel=0.01)  # the smooth torus: 2π²
    assert vol4 == pytest.approx(np.pi * r * r * area(v, t), rel=0.01)


def frame_twists(v, t):
    """The largest angle between a vertex's frame and its neighbour's transported into it."""
    frames, parity = surface_normal_frames(v, t)
    worst = 0.0
    for j, k in ((0, 1), (1, 2), (0, 2)):
        a, b = t[:, j], t[:, k]
        m = np.swapaxes(frames[b], 1, 2) @ frames[a]
        mirrored = parity[:, j] != parity[:, k]
        m[mirrored, :, 1] *= -1
        worst = max(worst, np.abs(np.arctan2(m[:, 1, 0] - m[:, 0, 1], m[:, 0, 0] + m[:, 1, 1])).max())
    return worst


def twisted_torus(n=40, turns=2.0):
    """A torus in R^4 whose normal planes turn as one goes around: (cos u, sin u) ⊕ a circle of
    radius 0.3 in the plane rotated by `turns`·u — transport around u has holonomy."""
    u, w = np.meshgrid(2 * np.pi * np.arange(n) / n, 2 * np.pi * np.arange(n) / n, indexing="ij")
    e1 = np.stack([np.cos(u), np.sin(u), 0 * u, 0 * u], -1)
    e3 = np.stack([0 * u, 0 * u, np.cos(turns * u / 2), np.sin(turns * u / 2)], -1)
    p = 1.5 * e1 + 0.3 * (np.cos(w)[..., None] * e1 + np.sin(w)[..., None] * e3)
    return p.reshape(-1, 4), surfaces.grid_triangles(n, n, True, True)


def test_no_twist_seam_the_holonomy_is_spread_out():
    v, t = twisted_torus()
    # The frames turn by little more than the normal planes do between neighbours: no edge
    # carries the whole holonomy (a seam would show one angle near the total).
    assert frame_twists(v, t) < 0.25
    tv, ts = thicken_surface(v, t, 0.05, 12)
    assert ridge_balance(ts) == (2, 2, 0) and volumes(tv, ts)[1] > 0


def moebius_band(n=48, width=0.4):
    """A Möbius band in R^3 ⊂ R^4: its normal bundle (the band's normal ⊕ the 4th axis) is not
    orientable."""
    u, s = np.meshgrid(2 * np.pi * np.arange(n) / n, np.linspace(-width, width, 5), indexing="ij")
    x = (1 + s * np.cos(u / 2)) * np.cos(u)
    y = (1 + s * np.cos(u / 2)) * np.sin(u)
    z = s * np.sin(u / 2)
    v = np.stack([x, y, z, 0 * x], -1).reshape(-1, 4)
    rows, cols = n, 5
    i, j = np.meshgrid(np.arange(rows), np.arange(cols - 1), indexing="ij")
    i, j = i.ravel(), j.ravel()
    last = i == rows - 1
    i1 = np.where(last, 0, i + 1)
    j1 = np.where(last, cols - 1 - j, j)  # the half turn: row 0 is met upside down
    j2 = np.where(last, cols - 2 - j, j + 1)
    a, b, c, d = i * cols + j, i1 * cols + j1, i1 * cols + j2, i * cols + j + 1
    return v, np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])


def test_moebius_band_non_orientable_normal_bundle_still_closes():
    v, t = moebius_band()
    frames, parity = surface_normal_frames(v, t)
    assert parity.any()  # some corners see the circle mirrored
    tv, ts = thicken_surface(v, t, 0.05, 10)
    assert ridge_balance(ts) == (2, 2, 0)
    vol3, vol4 = volumes(tv, ts)
    assert vol4 > 0
    assert vol3 == pytest.approx(2 * np.pi * 0.05 * area(v, t), rel=0.05)


@pytest.mark.parametrize("subdivisions, verts, tets", [(1, 5, 5), (2, 8, 16), (3, 32, 128)])
def test_thicken_points_spheres(subdivisions, verts, tets):
    rng = np.random.default_rng(subdivisions)
    p = rng.normal(size=(7, 4))
    v, s = thicken_points(p, 0.25, subdivisions)
    assert v.shape == (7 * verts, 4) and s.shape == (7 * tets, 4)
    assert ridge_balance(s) == (2, 2, 0)
    for i in range(7):  # every sphere: centred on its point, vertices at the radius, outward
        mine = v[i * verts:(i + 1) * verts]
        assert np.allclose(np.linalg.norm(mine - p[i], axis=1), 0.25)
        local = s[i * tets:(i + 1) * tets] - i * verts
        assert local.min() == 0 and local.max() == verts - 1
        assert volumes(mine - p[i], local)[1] > 0


def test_thicken_points_trace_as_one_object():
    """A cloud on the 3-sphere traced as one mesh: the retina sees the points where an
    independent projection of the centres through the camera says it should."""
    rng = np.random.default_rng(5)
    p = rng.normal(size=(300, 4))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    v, s = thicken_points(p, 0.12, subdivisions=2)
    scene = ndtrace.Scene(4).set_camera([0, 0, 0, 4.0], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]],
                                        projection="orthographic", extent=1.2, resolution=24)
    scene.add_object("mesh", vertices=v, simplices=s, material={"color": [1, 1, 1]})
    scene.add_light("directional", direction=[0, 0, 0, 1])
    assert len(scene.to_dict()["objects"]) == 1
    r = ndtrace.trace(scene)
    # Orthographic along −w, retina axes u = (x, y, z); the array is indexed [u3, u2 (rows run
    # downward), u1]: a hit cell needs a point's centre within a cell of it.
    hit = r.hit
    assert 0.02 < hit.mean() < 0.9
    res = 24
    q = np.stack([p[:, 2], -p[:, 1], p[:, 0]], 1)
    idx = np.clip(np.floor((q + 1.2) / 2.4 * res).astype(int), 0, res - 1)
    near = np.zeros_like(hit)
    for d in np.ndindex(3, 3, 3):
        q = np.clip(idx + np.array(d) - 1, 0, res - 1)
        near[tuple(q.T)] = True
    assert not np.any(hit & ~near)


BAD = [
    (dict(vertices=np.zeros((3, 3))), "vertices"),
    (dict(vertices=np.array([[0, 0, 0, 0], [1, 0, 0, 0], [0, np.nan, 0, 0]])), "vertices"),
    (dict(triangles=np.array([[0, 1]])), "triangles"),
    (dict(triangles=np.array([[0, 1, 5]])), "triangles"),
    (dict(triangles=np.array([[0, 1, 1]])), "triangles"),
    (dict(triangles=np.array([[0.0, 1, 2]])), "triangles"),
    (dict(radius=0.0), "radius"),
    (dict(radius=-1.0), "radius"),
    (dict(radius=float("nan")), "radius"),
    (dict(segments=2), "segments"),
]


@pytest.mark.parametrize("change, name", BAD)
def test_thicken_surface_bad_input_names_the_argument(change, name):
    args = dict(vertices=np.array([[0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.0]]),
                triangles=np.array([[0, 1, 2]]), radius=0.1, segments=8)
    args.update(change)
    with pytest.raises(ValueError, match=f"^{name}"):
        thicken_surface(**args)


def test_non_manifold_surfaces_are_refused():
    v = np.array([[0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    with pytest.raises(ValueError, match=r"^triangles: the edge \(0, 1\) belongs to 3"):
        thicken_surface(v, [[0, 1, 2], [0, 1, 3], [0, 1, 4]], 0.1)
    bowtie = np.array([[0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0], [-1, 0, 0, 0], [0, -1, 0, 0.0]])
    with pytest.raises(ValueError, match="^triangles: vertex 0 is not a manifold point"):
        thicken_surface(bowtie, [[0, 1, 2], [0, 3, 4]], 0.1)
    with pytest.raises(ValueError, match=r"^triangles\[1\]: appears twice"):
        thicken_surface(v, [[0, 1, 2], [2, 1, 0]], 0.1)
    with pytest.raises(ValueError, match=r"^triangles\[0\]: has zero area"):
        thicken_surface(np.array([[0, 0, 0, 0], [1, 0, 0, 0], [2, 0, 0, 0.0]]), [[0, 1, 2]], 0.1)


@pytest.mark.parametrize("change, name", [
    (dict(points=np.zeros((4, 3))), "points"), (dict(points=np.full((2, 4), np.inf)), "points"),
    (dict(radius=0), "radius"), (dict(subdivisions=0), "subdivisions"), (dict(subdivisions=1.5), "subdivisions")])
def test_thicken_points_bad_input_names_the_argument(change, name):
    args = dict(points=np.zeros((4, 4)), radius=0.1, subdivisions=1)
    args.update(change)
    with pytest.raises(ValueError, match=f"^{name}"):
        thicken_points(**args)


def test_generators_match_their_equations():
    v, t = surfaces.clifford_torus(16)
    assert np.allclose(np.linalg.norm(v, axis=1), 1) and np.allclose(np.linalg.norm(v[:, :2], axis=1), 2**-0.5)
    v, t = surfaces.complex_graph(lambda z: z**2)
    z, w = v[:, 0] + 1j * v[:, 1], v[:, 2] + 1j * v[:, 3]
    assert np.allclose(w, z**2)
    v, t = surfaces.riemann_root(2)
    z, w = v[:, 0] + 1j * v[:, 1], v[:, 2] + 1j * v[:, 3]
    assert np.allclose(w**2, z) and np.abs(z).max() == pytest.approx(1.0)
    v, t = surfaces.fermat_patch(3, 1, 2)
    z, w = v[:, 0] + 1j * v[:, 1], v[:, 2] + 1j * v[:, 3]
    assert np.allclose(z**3 + w**3, 1)
    v, t = surfaces.spun_knot(48, 12)
    # A 2-sphere: V − E + F = 2, every edge in two triangles.
    edges = np.unique(np.sort(np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]]), axis=1), axis=0)
    assert len(v) - len(edges) + len(t) == 2
