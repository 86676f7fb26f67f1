"""Meshes: ``ndtrace.mesh`` (convex hulls against scipy and the regular polytopes, orientation
repair), the load-time orientation warning, mesh files through meshio against the ``.npz``
path (the same retina), and trimesh / meshio objects in the builder."""

from __future__ import annotations

import itertools
import os
import warnings

import numpy as np
import pytest

import ndtrace
from ndtrace import mesh as ndmesh

meshio = pytest.importorskip("meshio")
trimesh = pytest.importorskip("trimesh")
pytest.importorskip("scipy")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PHI = (1 + 5**0.5) / 2


# -- the regular 4D polytopes, from their vertex coordinates ----------------------------------


def even_permutations(v):
    out = []
    for p in itertools.permutations(range(4)):
        inversions = sum(p[i] > p[j] for i in range(4) for j in range(i + 1, 4))
        if inversions % 2 == 0:
            out.append([v[k] for k in p])
    return out


def signs(rows):
    out = set()
    for r in rows:
        nz = [i for i, x in enumerate(r) if x != 0]
        for s in itertools.product((1, -1), repeat=len(nz)):
            q = list(r)
            for i, si in zip(nz, s):
                q[i] = si * q[i]
            out.add(tuple(float(x) for x in q))
    return np.array(sorted(out))


def polytopes() -> dict[str, tuple[np.ndarray, int]]:
    """Name → (vertices, number of facets of the polytope)."""
    perms = lambda v: [list(p) for p in set(itertools.permutations(v))]  # noqa: E731
    cell5 = np.vstack([np.eye(4), np.full(4, (1 - 5**0.5) / 4)])
    cell8 = signs([[1, 1, 1, 1]])
    cell16 = signs(perms([1, 0, 0, 0]))
    cell24 = signs(perms([1, 1, 0, 0]))
    cell600 = np.vstack([signs([[0.5, 0.5, 0.5, 0.5]]), signs(perms([1, 0, 0, 0])),
                         signs(even_permutations([PHI / 2, 0.5, 1 / (2 * PHI), 0]))])
    p2 = PHI**-2
    rows = (perms([0, 0, 2, 2]) + perms([1, 1, 1, 5**0.5]) + perms([PHI**-1, PHI**-1, PHI**-1, PHI**2])
            + perms([p2, PHI, PHI, PHI]) + even_permutations([0, p2, 1, PHI**2])
            + even_permutations([0, PHI**-1, PHI, 5**0.5]) + even_permutations([PHI**-1, 1, PHI, 2]))
    cell120 = signs(rows)
    return {"5-cell": (cell5, 5), "8-cell": (cell8, 8), "16-cell": (cell16, 16),
            "24-cell": (cell24, 24), "120-cell": (cell120, 120), "600-cell": (cell600, 600)}


def ridge_counts(simplices: np.ndarray) -> dict[tuple, list[bool]]:
    """Each ridge (sorted vertex indices) → the orientation parities its simplices induce."""
    out: dict[tuple, list[bool]] = {}
    n = simplices.shape[1]
    for s in simplices:
        for k in range(n):
            r = [int(x) for j, x in enumerate(s) if j != k]
            inversions = sum(r[i] > r[j] for i in range(n - 1) for j in range(i + 1, n - 1))
            out.setdefault(tuple(sorted(r)), []).append((k + inversions) % 2 == 1)
    return out


def normals_and_centroids(v, s):
    pts = v[s]
    return ndtrace.geometry.generalized_cross(pts[:, 1:] - pts[:, :1]), pts.mean(axis=1)


def assert_closed_and_outward(v, s):
    counts = ridge_counts(s)
    assert all(len(p) == 2 and p[0] != p[1] for p in counts.values()), "closed, consistent"
    normals, centroids = normals_and_centroids(v, s)
    out = np.einsum("ij,ij->i", normals, centroids - v.mean(axis=0))
    assert np.all(out > 1e-9 * np.linalg.norm(normals, axis=1).max()), "every normal points away from the centroid"


@pytest.mark.parametrize("name", list(polytopes()))
def test_convex_hulls_of_the_regular_4d_polytopes_are_closed_and_outward(name):
    points, facets = polytopes()[name]
    rng = np.random.default_rng(1)
    order = rng.permutation(len(points))
    v, s = ndmesh.convex_hull(points[order])
    assert v.shape == points.shape and s.dtype == np.int64 and s.shape[1] == 4
    assert_closed_and_outward(v, s)
    # The facets: hyperplanes of the simplices, merged, are the polytope's.
    normals, _ = normals_and_centroids(v, s)
    unit = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    assert len(np.unique(np.round(unit, 6), axis=0)) == facets
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a hull from convex_hull loads without warnings
        scene = ndtrace.load_dict(scene_dict(4, {"shape": "mesh", "vertices": v, "simplices": s}))
    assert scene.warnings == []


@pytest.mark.parametrize("n", range(2, 9))
def test_convex_hulls_of_random_points_match_scipy_in_every_dimension(n):
    from scipy.spatial import ConvexHull

    rng = np.random.default_rng(n)
    points = rng.normal(size=(3 * n + 6, n))
    v, s = ndmesh.convex_hull(points)
    hull = ConvexHull(points)
    np.testing.assert_array_equal(v, points[np.unique(hull.simplices)])
    assert len(s) == len(hull.simplices)
    assert_closed_and_outward(v, s)
    # Every point lies on the inner side of every simplex (eq. 11 with outward normals).
    normals, _ = normals_and_centroids(v, s)
    d = np.einsum("sk,pk->sp", normals, points) - np.einsum("sk,sk->s", normals, v[s[:, 0]])[:, None]
    assert d.max() < 1e-9


def test_convex_hull_errors_name_the_points():
    with pytest.raises(ValueError, match=r"points: a hull in R\^3 needs at least 4 points"):
        ndmesh.convex_hull(np.eye(3))
    with pytest.raises(ValueError, match=r"points: no convex hull in R\^3"):
        ndmesh.convex_hull([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [2, 3, 0]])
    with pytest.raises(ValueError, match=r"points: expected shape \(V, N\) with N in 2\.\.8"):
        ndmesh.convex_hull(np.zeros((20, 9)))
    with pytest.raises(ValueError, match="points: holds NaN"):
        ndmesh.convex_hull([[0, 0], [1, 0], [np.nan, 1]])


def scrambled(s: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    flip = rng.random(len(s)) < 0.45
    out = s.copy()
    out[flip, 1], out[flip, 2] = s[flip, 2], s[flip, 1]
    return out, flip


def scene_dict(n: int, *objects: dict, **render) -> dict:
    return {"dim": n,
            "camera": {"position": [0.3, 0.5, 0.7, 5.0][-n:] if n <= 4 else [0.2] * (n - 1) + [5.0],
                       "look_at": [0] * n,
                       "up": [[1.0 if i == k + 1 else 0.0 for i in range(n)] for k in range(n - 2)],
                       "fov": 40, "resolution": 12},
            "lights": [{"type": "directional", "direction": [0.3] * (n - 1) + [1.0]}],
            "objects": list(objects), "render": render}


def test_a_scrambled_hull_warns_and_orient_repairs_it():
    v, s = ndmesh.convex_hull(polytopes()["24-cell"][0])
    bad, flip = scrambled(s, 3)
    with pytest.warns(UserWarning) as rec:
        scene = ndtrace.load_dict(scene_dict(4, {"shape": "mesh", "vertices": v, "simplices": bad}))
    message = f"objects[0]: the closed mesh is not consistently oriented: {flip.sum()} of its 96 simplices face inward"
    assert [str(w.message) for w in rec if "oriented" in str(w.message)][0].startswith(message)
    assert scene.warnings[0].startswith(message)
    v2, fixed = ndmesh.orient(v, bad)
    np.testing.assert_array_equal(v2, v)
    assert_closed_and_outward(v, fixed)
    # Only the scrambled simplices changed, each back to the orientation of the hull's.
    changed = np.any(fixed != bad, axis=1)
    np.testing.assert_array_equal(changed, flip)
    np.testing.assert_allclose(normals_and_centroids(v, fixed)[0], normals_and_centroids(v, s)[0])
    # With back-face culling the scrambled mesh loses cells; the repaired one shows them all.
    culled = {"cull_backfaces": True, "shadows": False}
    with pytest.warns(UserWarning, match="not consistently oriented"):
        broken = ndtrace.trace(ndtrace.load_dict(scene_dict(4, {"shape": "mesh", "vertices": v, "simplices": bad}, **culled)))
    good = ndtrace.trace(ndtrace.load_dict(scene_dict(4, {"shape": "mesh", "vertices": v, "simplices": fixed}, **culled)))
    assert good.hit.sum() > broken.hit.sum()


def test_orient_keeps_open_meshes_near_as_given_and_rejects_odd_ones():
    # A fan of triangles around a vertex (an open disc), two of them reversed.
    k = 8
    t = np.linspace(0, 2 * np.pi, k, endpoint=False)
    v = np.column_stack([np.cos(t), np.sin(t), np.zeros(k)])
    v = np.vstack([[0, 0, 0.5], v])
    s = np.array([[0, 1 + i, 1 + (i + 1) % k] for i in range(k)])
    bad = s.copy()
    bad[[2, 5]] = bad[[2, 5]][:, [1, 0, 2]]
    _, fixed = ndmesh.orient(v, bad)
    np.testing.assert_array_equal(fixed[[0, 1, 3, 4, 6, 7]], s[[0, 1, 3, 4, 6, 7]])
    assert ridge_counts(fixed)[(0, 1)][0] != ridge_counts(fixed)[(0, 1)][1]
    with pytest.raises(ValueError, match=r"simplices: the ridge with vertices \[0, 1\] belongs to 3 simplices"):
        ndmesh.orient(v, np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]]))
    mobius = np.array([[i, (i + 1) % 5, (i + 2) % 5] for i in range(5)])
    with pytest.raises(ValueError, match="not orientable"):
        ndmesh.orient(v[:5], mobius)
    with pytest.raises(ValueError, match=r"simplices\[0\]\[2\]: vertex index 9 out of range"):
        ndmesh.orient(v, [[0, 1, 9]])
    with pytest.raises(ValueError, match=r"simplices: expected shape \(S, 3\)"):
        ndmesh.orient(v, [[0, 1]])


# -- mesh files and objects ------------------------------------------------------------------


def icosphere():
    with np.load(os.path.join(ROOT, "scenes", "data", "icosphere.npz")) as z:
        return z["vertices"], z["simplices"]


def tesseract_boundary():
    """The 4D hypercube's boundary as tetrahedra (outward), from its convex hull."""
    return ndmesh.convex_hull(signs([[1, 1, 1, 1]]))


def toml_scene(n: int, file: str) -> str:
    cam = {3: 'position = [0.8, 1.2, 3.2]\nlook_at = [0, 0, 0]\nup = [[0, 1, 0]]',
           4: 'position = [1.2, 1.6, 2.0, 4.5]\nlook_at = [0, 0, 0, 0]\nup = [[0, 1, 0, 0], [0, 0, 1, 0]]'}[n]
    light = "[0.4, 0.8, 0.6]" if n == 3 else "[0.4, 0.8, 0.6, 1.0]"
    return (f"dim = {n}\n[camera]\n{cam}\nfov = 50\nresolution = {24 if n == 3 else 10}\n\n"
            f'[[lights]]\ntype = "directional"\ndirection = {light}\n\n'
            f'[[objects]]\nshape = "mesh"\nfile = "{file}"\nmaterial = {{ smooth = true }}\n')


def same_retina(a, b):
    for k in ("rgba", "depth", "normal", "object_id", "primitive_id"):
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k), err_msg=k)


def traced(tmp_path, n, file):
    path = tmp_path / f"scene-{os.path.basename(file)}.toml"
    path.write_text(toml_scene(n, file))
    return ndtrace.trace(ndtrace.load_file(path))


@pytest.mark.parametrize("ext", ["obj", "ply", "stl", "off", "vtk", "vtu", "msh"])
def test_triangle_mesh_files_give_the_retina_of_the_npz(tmp_path, ext):
    v, s = icosphere()
    if ext == "stl":  # STL stores float32 coordinates (and meshio merges its repeated points)
        v = v.astype(np.float32).astype(np.float64)
    (tmp_path / "meshes").mkdir()
    np.savez(tmp_path / "meshes" / "ref.npz", vertices=v, simplices=s)
    meshio.write(tmp_path / "meshes" / f"m.{ext}", meshio.Mesh(v, [("triangle", s)]),
                 **({"binary": True} if ext == "stl" else {}))
    reference = traced(tmp_path, 3, "meshes/ref.npz")
    assert reference.hit.sum() > 100
    same_retina(traced(tmp_path, 3, f"meshes/m.{ext}"), reference)


def test_tetrahedral_mesh_files_give_the_retina_of_the_npz(tmp_path):
    v, s = tesseract_boundary()
    np.savez(tmp_path / "ref.npz", vertices=v, simplices=s)
    meshio.write(tmp_path / "t.vtu", meshio.Mesh(v, [("tetra", s)]))
    reference = traced(tmp_path, 4, "ref.npz")
    assert reference.hit.sum() > 100
    same_retina(traced(tmp_path, 4, "t.vtu"), reference)
    # Gmsh stores 3 coordinates: a tetrahedral solid lies in x_3 = 0 of R^4.
    v3, s3 = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1.0]]), np.array([[0, 1, 2, 3]])
    meshio.write(tmp_path / "t.msh", meshio.Mesh(v3, [("tetra", s3)]), file_format="gmsh")
    np.savez(tmp_path / "flat.npz", vertices=np.pad(v3, ((0, 0), (0, 1))), simplices=s3)
    same_retina(traced(tmp_path, 4, "t.msh"), traced(tmp_path, 4, "flat.npz"))


def test_mesh_file_errors_name_scene_line_field_and_file(tmp_path):
    meshio.write(tmp_path / "lines.vtu", meshio.Mesh(np.eye(3), [("line", np.array([[0, 1], [1, 2]]))]))
    (tmp_path / "junk.obj").write_text("this is not a mesh\n")
    (tmp_path / "scene.toml").write_text(toml_scene(3, "lines.vtu"))
    where = r"scene\.toml:\d+:8: objects\[0\]\.file: "
    with pytest.raises(ValueError, match=where + r".*lines\.vtu: no triangle or quad cells for a dim = 3 scene \(cells: line\)"):
        ndtrace.load_file(tmp_path / "scene.toml")
    (tmp_path / "scene.toml").write_text(toml_scene(3, "missing.stl"))
    with pytest.raises(ValueError, match=where + r"cannot open .*missing\.stl: no such file"):
        ndtrace.load_file(tmp_path / "scene.toml")
    with pytest.raises(FileNotFoundError):
        ndmesh.read(tmp_path / "missing.stl")
    with pytest.raises(ValueError, match=r"no triangle or quad cells"):
        ndmesh.read(tmp_path / "junk.obj", dim=3)


def test_a_missing_meshio_is_an_error_naming_the_extra(tmp_path, monkeypatch):
    import builtins

    real = builtins.__import__

    def no_meshio(name, *args, **kw):
        if name == "meshio":
            raise ImportError("No module named 'meshio'")
        return real(name, *args, **kw)

    monkeypatch.setattr(builtins, "__import__", no_meshio)
    (tmp_path / "x.obj").write_text("v 0 0 0\n")
    (tmp_path / "scene.toml").write_text(toml_scene(3, "x.obj"))
    with pytest.raises(ValueError, match=r'objects\[0\]\.file: .*x\.obj: reading \.obj mesh files needs meshio: pip install "ndtrace\[mesh\]"'):
        ndtrace.load_file(tmp_path / "scene.toml")
    with pytest.raises(ImportError, match=r'pip install "ndtrace\[mesh\]"'):
        ndmesh.read(tmp_path / "x.obj")


def test_trimesh_and_meshio_objects_are_accepted_by_the_builder():
    v, s = icosphere()
    base = scene_dict(3)
    inline = ndtrace.load_dict({**base, "objects": [{"shape": "mesh", "vertices": v, "simplices": s}]})
    reference = ndtrace.trace(inline)
    tm = trimesh.Trimesh(vertices=v, faces=s, process=False)
    mm = meshio.Mesh(v, [("vertex", np.arange(3)[:, None]), ("triangle", s)])
    for obj in (tm, mm, (v, s)):
        b = ndtrace.load_dict({**base, "objects": []})
        b.add_object("mesh", mesh=obj)
        same_retina(ndtrace.trace(b), reference)
    # A quad mesh is split into triangles with the quads' orientation.
    quad = meshio.Mesh(np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]]), [("quad", np.array([[0, 1, 2, 3]]))])
    verts, tris = ndmesh.from_object(quad, dim=3)
    np.testing.assert_array_equal(tris, [[0, 1, 2], [0, 2, 3]])
    b = ndtrace.Scene(4)
    with pytest.raises(ValueError, match=r"no tetra cells for a dim = 4 scene \(cells: triangle\)"):
        b.add_object("mesh", mesh=tm)
    with pytest.raises(ValueError, match='mesh: goes with shape "mesh"'):
        ndtrace.Scene(3).add_object("mesh", mesh=tm, vertices=v)
    with pytest.raises(TypeError, match=r"mesh: expected an object with \.vertices and \.faces"):
        ndtrace.Scene(3).add_object("mesh", mesh=42)


def test_a_missing_scene_file_is_file_not_found(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such scene file"):
        ndtrace.load_file(tmp_path / "nope.toml")
