"""Hyperplane slices (``ndtrace.mesh.slice``, ``ndtrace.slice_scene``, ``[slice]``, ``--slice``,
the slice sweep and ``layout = "slice"``), checked against independent computations: the
convex section's volume from scipy's hull of the polytope edges' crossings, closedness as a
chain, outward orientation against the section's centroid."""

import itertools
import math

import numpy as np
import pytest

import ndtrace
from ndtrace.cli import run

scipy_spatial = pytest.importorskip("scipy.spatial")


def tesseract():
    return np.array(list(itertools.product([-1.0, 1.0], repeat=4))), 2.0


def cell16():
    return np.vstack([np.eye(4), -np.eye(4)]), math.sqrt(2)


def cell24():
    pts = set()
    for i, j in itertools.combinations(range(4), 2):
        for a, b in itertools.product([-1.0, 1.0], repeat=2):
            p = [0.0] * 4
            p[i], p[j] = a, b
            pts.add(tuple(p))
    return np.array(sorted(pts)), math.sqrt(2)


def penteract():
    return np.array(list(itertools.product([-1.0, 1.0], repeat=5))), 2.0


POLYTOPES = {"tesseract": tesseract, "16-cell": cell16, "24-cell": cell24, "5-cube": penteract}


def enclosed_volume(coords, pieces):
    """Σ N_s·y_0 / (N−1)! = Σ det[y_1−y_0 … y_{N−2}−y_0 | y_0] / (N−1)! (eq. 6's normal N_s of
    each piece): the volume a closed, outward slice encloses."""
    m = coords.shape[1]
    y = coords[pieces]
    rows = np.concatenate([y[:, 1:] - y[:, :1], y[:, :1]], axis=1)
    return float(np.linalg.det(rows).sum() / math.factorial(m))


def open_faces(pieces):
    """The (N−3)-faces whose oriented count does not sum to zero (none for a closed chain)."""
    total: dict[tuple, int] = {}
    for p in pieces.tolist():
        for k in range(len(p)):
            face = p[:k] + p[k + 1:]
            order = np.argsort(face)
            # Sign of the permutation that sorts the face.
            sign = round(np.linalg.det(np.eye(len(face))[order])) if len(face) > 1 else 1
            key = tuple(sorted(face))
            total[key] = total.get(key, 0) + (-1) ** k * sign
    return sum(1 for v in total.values() if v != 0)


def section_volume(vertices, edge_length, normal, offset, basis, origin):
    """The volume of the convex section, independently: scipy's hull of the crossings of the
    polytope's edges (vertex pairs at the edge length) with the hyperplane."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    d = vertices @ n - offset
    points = []
    for a, b in itertools.combinations(range(len(vertices)), 2):
        if abs(np.linalg.norm(vertices[a] - vertices[b]) - edge_length) > 1e-9:
            continue
        if d[a] * d[b] < 0:
            t = d[a] / (d[a] - d[b])
            points.append(vertices[a] + t * (vertices[b] - vertices[a]))
    y = (np.array(points) - origin) @ basis.T
    return scipy_spatial.ConvexHull(y).volume


@pytest.mark.parametrize("name", sorted(POLYTOPES))
def test_random_slices_of_regular_polytopes_enclose_the_convex_section(name):
    points, edge = POLYTOPES[name]()
    vertices, simplices = ndtrace.mesh.convex_hull(points)
    n_dim = vertices.shape[1]
    rng = np.random.default_rng(51)
    for _ in range(6):
        normal = rng.normal(size=n_dim)
        # Through the interior: within half the inradius of the centre.
        offset = rng.uniform(-0.4, 0.4)
        coords, pieces, basis, origin = ndtrace.mesh.slice(vertices, simplices, normal, offset)
        assert coords.shape[1] == n_dim - 1 and pieces.shape[1] == n_dim - 1
        assert basis.shape == (n_dim - 1, n_dim) and origin.shape == (n_dim,)
        # An orthonormal frame of the hyperplane, origin on it.
        nh = normal / np.linalg.norm(normal)
        np.testing.assert_allclose(basis @ basis.T, np.eye(n_dim - 1), atol=1e-12)
        np.testing.assert_allclose(basis @ nh, 0, atol=1e-12)
        assert abs(origin @ nh - offset) < 1e-12
        # Closed, and its volume is the section's.
        assert open_faces(pieces) == 0
        expected = section_volume(points, edge, normal, offset, basis, origin)
        assert enclosed_volume(coords, pieces) == pytest.approx(expected, rel=1e-9)
        # Outward: every piece's normal points away from the (convex) section's centroid.
        centroid = coords.mean(axis=0)
        y = coords[pieces]
        normals = ndtrace.geometry.generalized_cross(y[:, 1:] - y[:, :1])
        assert np.all(np.einsum("ij,ij->i", normals, y[:, 0] - centroid) > 0)
        # The slice lies on the hyperplane, back in R^N.
        world = origin + coords @ basis
        np.testing.assert_allclose(world @ nh, offset, atol=1e-12)


def polygon_area(coords, pieces):
    return enclosed_volume(coords, pieces)


@pytest.mark.parametrize("normal, offset, area, corners", [
    ([0, 0, 1], 0.3, 4.0, [(-1, -1), (-1, 1), (1, -1), (1, 1)]),
    ([1, 1, 1], 0.0, 3 * math.sqrt(3), None),
    ([1, 1, 1], 2 / math.sqrt(3), math.sqrt(3) / 2, None),
])
def test_a_cube_sliced_by_planes_gives_the_right_polygons(normal, offset, area, corners):
    vertices, simplices = ndtrace.mesh.convex_hull(list(itertools.product([-1, 1], repeat=3)))
    coords, pieces, basis, origin = ndtrace.mesh.slice(vertices, simplices, normal, offset)
    assert open_faces(pieces) == 0
    assert polygon_area(coords, pieces) == pytest.approx(area, rel=1e-12)
    hull = scipy_spatial.ConvexHull(coords)
    assert hull.volume == pytest.approx(area, rel=1e-12)  # (the area, in 2D)
    if corners is not None:
        assert sorted(map(tuple, np.round(coords[hull.vertices], 12))) == sorted(corners)
    # Every output vertex is a corner or lies on the polygon's boundary (a face diagonal).
    for y in coords:
        assert np.max(hull.equations[:, :2] @ y + hull.equations[:, 2]) > -1e-12


def check_clean(coords, pieces):
    """No duplicate vertex, no duplicate piece, no piece of zero area."""
    assert len(np.unique(np.round(coords, 12), axis=0)) == len(coords)
    assert len({tuple(sorted(p)) for p in pieces.tolist()}) == len(pieces)
    if len(pieces):
        y = coords[pieces]
        normals = ndtrace.geometry.generalized_cross(y[:, 1:] - y[:, :1])
        assert np.all(np.linalg.norm(normals, axis=1) > 1e-9)


@pytest.mark.parametrize("normal, offset, volume", [
    ([0, 0, 0, 1], 1.0, 8.0),                 # along a facet: the facet (limit from below)
    ([0, 0, 0, 1], -1.0, 0.0),                # touching a facet from outside: nothing
    ([1, 1, 1, 1], 2.0, 0.0),                 # through one vertex only
    ([1, 1, 0, 0], math.sqrt(2), 0.0),        # along a ridge (a square face)
    ([1, 1, 1, 1], 0.0, None),                # through the centre and six vertices
    ([1, 1, 0, 0], 0.0, None),                # through the centre and eight edges
    ([1, 0, 0, 0], 0.0, 8.0),                 # through the centre, no vertex
])
def test_degenerate_cuts_of_the_tesseract(normal, offset, volume):
    points, edge = tesseract()
    vertices, simplices = ndtrace.mesh.convex_hull(points)
    coords, pieces, basis, origin = ndtrace.mesh.slice(vertices, simplices, normal, offset)
    check_clean(coords, pieces)
    assert open_faces(pieces) == 0
    got = enclosed_volume(coords, pieces) if len(pieces) else 0.0
    if volume is None:
        # The section through vertices: scipy's hull of the vertices on the hyperplane and
        # the edges' crossings.
        n = np.asarray(normal, float) / np.linalg.norm(normal)
        on = points[np.abs(points @ n - offset) < 1e-12]
        y = np.vstack([(on - origin) @ basis.T, coords])
        volume = scipy_spatial.ConvexHull(y).volume
    assert got == pytest.approx(volume, rel=1e-9, abs=1e-12)


def test_vertex_on_the_hyperplane_is_one_output_vertex():
    # The 16-cell through w = 0 passes six of its vertices; the octahedron |x|+|y|+|z| ≤ 1.
    vertices, simplices = ndtrace.mesh.convex_hull(cell16()[0])
    coords, pieces, _, _ = ndtrace.mesh.slice(vertices, simplices, [0, 0, 0, 1], 0.0)
    check_clean(coords, pieces)
    assert len(coords) == 6 and len(pieces) == 8
    assert enclosed_volume(coords, pieces) == pytest.approx(4 / 3, rel=1e-12)


@pytest.mark.parametrize("args, name", [
    (([[0, 0, 0]], [[0, 0, 0]], [0, 0, 0], 0.0), "normal"),
    (([[0, 0, 0]], [[0, 0, 0]], [0, 0, 1, 0], 0.0), "normal"),
    (([[0, 0, 0]], [[0, 0, 0]], [0, np.nan, 1], 0.0), "normal"),
    (([[0, 0, 0]], [[0, 0, 0]], [0, 0, 1], np.nan), "offset"),
    (([[0, 0, 0]], [[0, 0, 0]], [0, 0, 1], "a"), "offset"),
    (([[0, 0, np.nan]], [[0, 0, 0]], [0, 0, 1], 0.0), "vertices"),
    (([[0, 0]], [[0, 0]], [0, 1], 0.0), "vertices"),
    (([[0, 0, 0]], [[0, 0]], [0, 0, 1], 0.0), "simplices"),
    (([[0, 0, 0]], [[0, 0, 3]], [0, 0, 1], 0.0), "simplices[0][2]"),
])
def test_bad_input_names_the_argument(args, name):
    with pytest.raises(ValueError, match=rf"^{name.replace('[', '.').replace(']', '.')}"):
        ndtrace.mesh.slice(*args)


def test_slice_scene_is_the_sliced_world_mesh_as_a_scene_of_dimension_n_minus_1():
    scene = ndtrace.load_file("scenes/tesseract.toml")
    cut = ndtrace.slice_scene(scene, [0, 0, 0, 1], 0.3)
    assert cut.dim == 3
    data = cut.to_dict()
    assert len(data["objects"]) == 1
    obj = data["objects"][0]
    assert obj["shape"] == "mesh" and obj["material"] == scene.to_dict()["objects"][0]["material"]
    assert np.asarray(obj["vertices"]).shape[1] == 3
    # The lights projected: (0.4, 0.8, 0.6, 1.0) → (0.4, 0.8, 0.6).
    d = np.asarray(data["lights"][0]["direction"])
    np.testing.assert_allclose(d / np.linalg.norm(d), np.array([0.4, 0.8, 0.6]) / np.sqrt(1.16))
    # The volume the slice encloses is that of the rotated tesseract's section at w = 0.3.
    v = np.asarray(obj["vertices"])
    s = np.asarray(obj["simplices"])
    assert open_faces(s) == 0 and enclosed_volume(v, s) > 0
    retina = ndtrace.trace(cut)
    assert retina.rgba.shape == (64, 64, 4) and retina.object_id.max() == 0
    # The scene's [slice] gives the same scene.
    same = ndtrace.slice_scene(scene.copy().set_slice([0, 0, 0, 2], 0.3))
    assert same == cut


def test_an_unrotated_tesseract_at_w_0_3_slices_to_the_cube():
    scene = ndtrace.load_dict({
        "dim": 4, "camera": {"position": [1.2, 1.6, 2.0, 4.5], "look_at": [0, 0, 0, 0],
                             "up": [[0, 1, 0, 0], [0, 0, 1, 0]], "fov": 50, "resolution": 16},
        "objects": [{"shape": "hypercube"}]})
    obj = ndtrace.slice_scene(scene, [0, 0, 0, 1], 0.3).to_dict()["objects"][0]
    v = np.asarray(obj["vertices"])
    np.testing.assert_allclose(v.min(axis=0), -1) and np.testing.assert_allclose(v.max(axis=0), 1)
    assert enclosed_volume(v, np.asarray(obj["simplices"])) == pytest.approx(8.0, rel=1e-12)


@pytest.mark.parametrize("normal, offset, name", [
    ([0, 0, 0], 0.3, "normal"), ([0, 0, 0, 0], 0.3, "normal"), ([0, 0, 0, 1], math.inf, "offset"),
])
def test_slice_scene_bad_input(normal, offset, name):
    scene = ndtrace.load_file("scenes/tesseract.toml")
    with pytest.raises(ValueError, match=f"^{name}"):
        ndtrace.slice_scene(scene, normal, offset)


def test_slice_table_is_checked_and_round_trips(tmp_path):
    text = open("scenes/tesseract.toml").read() + "\n[slice]\nnormal = [0, 0, 0]\noffset = 0.3\n"
    with pytest.raises(ValueError, match=r"slice\.normal: expected 4 numbers, got 3"):
        ndtrace.load_toml(text)
    text = text.replace("normal = [0, 0, 0]", "normal = [0, 0, 0, 1]")
    scene = ndtrace.load_toml(text)
    assert scene.to_dict()["slice"] == {"normal": [0, 0, 0, 1], "offset": 0.3}
    assert ndtrace.load_toml(scene.to_toml()) == scene


def test_cli_slice_flag_axis_and_normal_forms_give_the_same_picture(tmp_path):
    a, b = tmp_path / "a.png", tmp_path / "b.png"
    base = ["scenes/tesseract.toml", "--resolution", "24", "--samples", "1", "--quiet"]
    assert run(base + ["-o", str(a), "--slice", "w=0.3"]) == 0
    assert run(base + ["-o", str(b), "--slice", "0,0,0,5:0.3"]) == 0
    from PIL import Image
    pa, pb = (np.asarray(Image.open(p)) for p in (a, b))
    assert np.array_equal(pa, pb)
    # Not the projection: the slice is a 3D picture of the cut cube.
    c = tmp_path / "c.png"
    assert run(base + ["-o", str(c)]) == 0
    assert not np.array_equal(pa, np.asarray(Image.open(c)))


@pytest.mark.parametrize("spec, message", [
    ("q=0.3", "unknown axis 'q'"), ("w=a", "'a' is not a number"),
    ("1,0,0:0.3", "expected 4 numbers"), ("0,0,0,0:1", "must not be zero"), ("w", "expected AXIS"),
])
def test_cli_slice_flag_errors(tmp_path, capsys, spec, message):
    with pytest.raises(SystemExit) as e:
        ndtrace.cli.main(["scenes/tesseract.toml", "-o", str(tmp_path / "x.png"),
                          "--slice", spec, "--quiet"])
    assert e.value.code == 2
    assert message in capsys.readouterr().err


def test_slice_sweep_animation_moves_the_hyperplane(tmp_path):
    scene = ndtrace.load_file("scenes/tesseract.toml")
    data = scene.to_dict()
    data["camera"]["resolution"] = 16
    data["animation"] = {"frames": 3, "slice": {"normal": [0, 0, 0, 1], "from": -0.5, "to": 0.5}}
    animated = ndtrace.load_dict(data)
    frame = ndtrace.animation.frame_scene(animated, 1).to_dict()
    assert frame["slice"] == {"normal": [0, 0, 0, 1], "offset": 0.0}
    assert frame["objects"] == data["objects"]
    paths = ndtrace.animate(animated, tmp_path / "sweep.gif", keep_frames=True,
                            composite={"size": (48, 48)})
    from PIL import Image
    pictures = [np.asarray(Image.open(p)) for p in paths if p.endswith(".png")]
    assert len(pictures) == 3 and not np.array_equal(pictures[0], pictures[1])
    # Frame 1 is the slice at w = 0.
    still = ndtrace.load_dict({k: v for k, v in data.items() if k != "animation"})
    cut = ndtrace.slice_scene(still, [0, 0, 0, 1], 0.0).to_dict()
    cut["camera"]["resolution"] = [48, 48]  # a 3D slice is traced at the picture's size
    expected = ndtrace.composite(ndtrace.trace(ndtrace.load_dict(cut)), size=(48, 48),
                                 background=data["background"])
    ndtrace.write_png(tmp_path / "expected.png", expected)
    assert np.array_equal(pictures[1], np.asarray(Image.open(tmp_path / "expected.png")))


def test_slice_layout_shows_the_projection_with_the_hyperplane_beside_the_slice(tmp_path):
    out = tmp_path / "side.png"
    assert run(["scenes/tesseract.toml", "-o", str(out), "--resolution", "32", "--samples", "1",
                "--slice", "w=0.3", "--layout", "slice", "--size", "200x100", "--quiet"]) == 0
    from PIL import Image
    p = np.asarray(Image.open(out).convert("RGB")).astype(int)
    assert p.shape == (100, 200, 3)
    left, right = p[:, :100], p[:, 100:]
    band = ndtrace.files.to_srgb8(
        np.array([[[*ndtrace.slicing.BAND_COLOR, 1.0]]], np.float32))[0, 0, :3].astype(int)
    near_band = np.all(np.abs(left - band) < 40, axis=-1)
    assert near_band.sum() > 20, "the hyperplane is marked in the projection"
    bg = p[0, -1]
    assert (np.abs(right - bg).sum(axis=-1) > 30).sum() > 500, "the slice is drawn on the right"
