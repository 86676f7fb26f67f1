"""Feature edges of meshes (``ndtrace.mesh.feature_edges``) and their N-D visibility
(``ndtrace.visible_edges``), against scipy's Qhull and against the traced retina."""

import itertools

import numpy as np
import pytest
from scipy.spatial import ConvexHull
from scipy.stats import special_ortho_group

import ndtrace

PHI = (1 + 5 ** 0.5) / 2


def even_permutations(n):
    for p in itertools.permutations(range(n)):
        inversions = sum(p[i] > p[j] for i in range(n) for j in range(i + 1, n))
        if inversions % 2 == 0:
            yield p


def signs(v):
    """Every sign change of the non-zero entries of v."""
    nz = [i for i, x in enumerate(v) if x != 0]
    for s in itertools.product([1, -1], repeat=len(nz)):
        w = list(v)
        for i, si in zip(nz, s):
            w[i] = si * w[i]
        yield tuple(w)


def unique_rows(points):
    return np.unique(np.round(np.asarray(points, float), 12), axis=0)


def hypercube(n):
    return np.array(list(itertools.product([-1.0, 1.0], repeat=n)))


def cross_polytope(n):
    return np.vstack([np.eye(n), -np.eye(n)])


def simplex(n):
    # n + 1 points of a regular n-simplex: the standard basis of R^{n+1} in its hyperplane.
    e = np.eye(n + 1) - 1.0 / (n + 1)
    q, _ = np.linalg.qr(e.T)
    return e @ q[:, :n]


def cell24():
    return unique_rows([p for v in [(1, 1, 0, 0)] for p in itertools.permutations(v) for p in signs(p)])


def cell600():
    pts = [p for s in signs((1, 0, 0, 0)) for p in set(itertools.permutations(s))]
    pts += list(signs((0.5, 0.5, 0.5, 0.5)))
    base = (PHI / 2, 0.5, 1 / (2 * PHI), 0.0)
    for perm in even_permutations(4):
        for s in signs(base):
            pts.append(tuple(s[perm[i]] for i in range(4)))
    return unique_rows(pts)


def cell120():
    # The dual of the 600-cell: the centres of its 600 tetrahedral facets.
    hull = ConvexHull(cell600())
    centres = hull.points[hull.simplices].mean(axis=1)
    return unique_rows(centres / np.linalg.norm(centres, axis=1, keepdims=True))


def icosahedron():
    return unique_rows([p for v in [(0, 1, PHI)] for c in range(3)
                        for p in signs(tuple(np.roll(v, c)))])


def dodecahedron():
    pts = list(signs((1, 1, 1)))
    for c in range(3):
        pts += list(signs(tuple(np.roll((0, 1 / PHI, PHI), c))))
    return unique_rows(pts)


POLYTOPES = [
    ("cube", lambda: hypercube(3), 12),
    ("octahedron", lambda: cross_polytope(3), 12),
    ("tetrahedron", lambda: simplex(3), 6),
    ("icosahedron", icosahedron, 30),
    ("dodecahedron", dodecahedron, 30),
    ("tesseract", lambda: hypercube(4), 32),
    ("16-cell", lambda: cross_polytope(4), 24),
    ("4-simplex", lambda: simplex(4), 10),
    ("24-cell", cell24, 96),
    # Neighbouring cells of the 600-cell meet at 164.48°: their normals are 15.5° apart, below
    # the default crease angle, so it needs a smaller one (see the test).
    ("600-cell", cell600, 720),
    ("120-cell", cell120, 1200),
    ("5-cube", lambda: hypercube(5), 80),
    ("5-orthoplex", lambda: cross_polytope(5), 40),
    ("5-simplex", lambda: simplex(5), 15),
    ("6-cube", lambda: hypercube(6), 192),
    ("6-orthoplex", lambda: cross_polytope(6), 60),
]


@pytest.mark.parametrize("name,points,edges", POLYTOPES, ids=[p[0] for p in POLYTOPES])
def test_regular_polytopes_from_qhull_give_their_true_edges(name, points, edges):
    pts = points()
    n = pts.shape[1]
    rng = np.random.default_rng(len(name))
    for _trial in range(2):
        rot = special_ortho_group.rvs(n, random_state=rng)
        hull = ConvexHull(pts @ rot.T)  # Qhull: triangulated facets, orientation not consistent
        angle = 10.0 if name == "600-cell" else 20.0
        e = ndtrace.mesh.feature_edges(hull.points, hull.simplices, angle=angle)
        assert e.dtype == np.int64 and e.shape == (edges, 2), f"{name}: {e.shape}"
        assert (e[:, 0] < e[:, 1]).all()
        assert (np.diff(e[:, 0] * len(pts) + e[:, 1]) > 0).all(), "rows sorted and unique"
        # Every edge has the polytope's edge length (they are all equal for regular polytopes).
        lengths = np.linalg.norm(hull.points[e[:, 0]] - hull.points[e[:, 1]], axis=1)
        dist = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
        shortest = dist[dist > 1e-9].min()
        np.testing.assert_allclose(lengths, shortest, rtol=1e-9)


def test_the_600_cell_is_smooth_at_the_default_angle():
    hull = ConvexHull(cell600())
    assert len(ndtrace.mesh.feature_edges(hull.points, hull.simplices)) == 0


def test_qhull_gives_zero_volume_simplices_and_mixed_orientation():
    """The Qhull inputs above really are the hard cases (so the test above can fail): some of
    their simplices have no volume and their orientations are mixed."""
    hull = ConvexHull(hypercube(4) @ special_ortho_group.rvs(4, random_state=1).T)
    v = hull.points[hull.simplices]
    edges = v[:, 1:] - v[:, :1]
    edges /= np.linalg.norm(edges, axis=-1, keepdims=True)
    gram = np.linalg.det(edges @ edges.transpose(0, 2, 1))
    assert (gram < 1e-12).sum() > 0 and len(hull.simplices) > 48
    solid = gram > 1e-6
    normals = ndtrace.geometry.generalized_cross(edges[solid])
    outward = np.einsum("ij,ij->i", normals, v[solid].mean(axis=1))
    assert (outward > 1e-9).any() and (outward < -1e-9).any()


def test_smooth_sphere_has_no_feature_edges_and_the_angle_matters():
    s = ndtrace.load_dict({"dim": 4, "camera": {"position": [0, 0, 0, 4], "look_at": [0, 0, 0, 0],
                                                "up": [[0, 1, 0, 0], [0, 0, 1, 0]], "fov": 40,
                                                "resolution": 8},
                           "objects": [{"shape": "sphere", "subdivisions": 3}]})
    assert ndtrace.visible_edges(s).shape == (0, 2, 4)
    # A prism in 3D folded by 30°: an edge at 20°, none at 40°.
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -np.cos(np.pi / 6), np.sin(np.pi / 6)]])
    t = np.array([[0, 1, 2], [0, 3, 1]])
    assert [0, 1] in ndtrace.mesh.feature_edges(v, t, angle=20).tolist()
    assert [0, 1] not in ndtrace.mesh.feature_edges(v, t, angle=40).tolist()


def test_feature_edges_bad_input_names_the_argument():
    v = np.zeros((3, 3))
    with pytest.raises(ValueError, match="simplices"):
        ndtrace.mesh.feature_edges(v, [[0, 1, 7]])
    with pytest.raises(ValueError, match="simplices"):
        ndtrace.mesh.feature_edges(v, [[0, 1]])
    with pytest.raises(ValueError, match="vertices"):
        ndtrace.mesh.feature_edges(np.zeros((3, 9)), [[0, 1, 2]])
    with pytest.raises(ValueError, match="vertices"):
        ndtrace.mesh.feature_edges([[0, 0, np.nan], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    with pytest.raises(ValueError, match="angle"):
        ndtrace.mesh.feature_edges(np.eye(3), [[0, 1, 2]], angle=100)


def tesseract():
    return ndtrace.load_file("scenes/tesseract.toml")


def test_visible_edges_of_the_tesseract_agree_with_the_retina():
    scene = tesseract()
    seg = ndtrace.edge_segments(scene)
    vis, hid = seg["visible"], seg["hidden"]
    assert vis.shape[1:] == (2, 4) and hid.shape[1:] == (2, 4)
    total = np.linalg.norm(vis[:, 1] - vis[:, 0], axis=1).sum() + \
        np.linalg.norm(hid[:, 1] - hid[:, 0], axis=1).sum()
    assert abs(total - 64.0) < 1e-9  # the pieces tile the 32 edges of side 2
    np.testing.assert_array_equal(ndtrace.visible_edges(scene), vis)

    # Points of visible pieces are where the retina sees the surface: the depth of the cell
    # they project to is their distance from the eye; points of hidden pieces in view are
    # farther than what the retina sees. (Away from the silhouette, where a cell can see a
    # surface at grazing incidence: only cells whose neighbours all see the object count.)
    retina = ndtrace.trace(scene)
    d = scene.to_dict()["camera"]
    eye = np.array(d["position"], float)
    orient = scene.compiled().camera_orientation
    o = np.array(orient)
    cell = 2 * np.tan(np.radians(d["fov"]) / 2) / retina.shape[-1]

    def cell_of(p):
        c = (p - eye) @ o
        u = c[:3] / c[3] / cell
        r = retina.shape[0]
        i1, i2, i3 = u[0] + r / 2, r / 2 - u[1], u[2] + r / 2
        return tuple(int(np.floor(x)) for x in (i3, i2, i1))

    checked = {True: 0, False: 0}
    for pieces, visible in ((vis, True), (hid, False)):
        for a, b in pieces:
            for s in np.linspace(0.1, 0.9, 17):
                p = a + s * (b - a)
                idx = cell_of(p)
                if not all(1 <= i < 63 for i in idx):
                    continue
                if not retina.hit[tuple(slice(i - 1, i + 2) for i in idx)].all():
                    continue
                dist = np.linalg.norm(p - eye)
                if visible:
                    assert abs(retina.depth[idx] - dist) < 0.05 * dist, (p, retina.depth[idx], dist)
                else:
                    assert retina.depth[idx] < dist - 0.02 * dist, (p, retina.depth[idx], dist)
                checked[visible] += 1
    assert checked[True] > 20 and checked[False] > 20, checked


def test_edge_segments_need_a_scene():
    with pytest.raises(TypeError, match="scene"):
        ndtrace.visible_edges("scenes/tesseract.toml")
