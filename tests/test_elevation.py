"""3D scalar fields as 4D elevation maps: ``ndtrace.mesh.elevation_map`` and the ``elevation``
scene shape with its textures (colormap, isolines, lattice).

The references are independent of the core: the tiling is checked by point location with
numpy barycentric coordinates, depths and normals of linear fields against exact formulas, the
colormap tables against matplotlib, and the file paths against each other."""

from __future__ import annotations

import os
import textwrap

import numpy as np
import pytest

import ndtrace
from ndtrace.mesh import elevation_map

RNG = np.random.default_rng(20)


def _volumes(v, s):
    """Signed volumes of the simplices' projections to xyz (numpy)."""
    p = v[s][:, :, :3]
    return np.linalg.det(p[:, 1:] - p[:, :1]) / 6.0


def _normals4(v, s):
    """Generalized cross products (eq. 6) of the tetrahedra of R^4, by cofactors."""
    e = v[s[:, 1:]] - v[s[:, :1]]  # (S, 3, 4)
    n = np.empty((len(s), 4))
    for k in range(4):
        minor = np.delete(e, k, axis=2)
        n[:, k] = (-1) ** (k + 3) * np.linalg.det(minor)
    return n


@pytest.mark.parametrize("shape", [(2, 2, 2), (3, 4, 5), (6, 2, 3)])
def test_the_tetrahedra_tile_the_box(shape):
    field = RNG.normal(size=shape)
    extent = ((-0.5, 1.5), (0.0, 3.0), (-2.0, -1.0))
    v, s = elevation_map(field, extent=extent, height=0.7)
    assert v.dtype == np.float64 and s.dtype == np.int64
    assert v.shape == (field.size, 4) and s.shape == (6 * np.prod(np.subtract(shape, 1)), 4)
    # One vertex per grid point, in C order, w exactly height·f.
    axes = [np.linspace(a, b, n) for (a, b), n in zip(extent, shape)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
    np.testing.assert_allclose(v[:, :3], grid, rtol=0, atol=1e-12)
    assert np.array_equal(v[:, 3], 0.7 * field.reshape(-1))
    # Volumes of the projections: all positive (consistent orientation), summing to the box.
    vol = _volumes(v, s)
    assert np.all(vol > 0)
    box = np.prod([b - a for a, b in extent])
    assert vol.sum() == pytest.approx(box, rel=1e-12)
    # No overlap: every random point of the box lies in exactly one tetrahedron's projection.
    lo, hi = np.array(extent).T
    pts = lo + (hi - lo) * RNG.random((3000, 3))
    p = v[s][:, :, :3]
    t = np.linalg.inv(np.transpose(p[:, 1:] - p[:, :1], (0, 2, 1)))  # (S, 3, 3)
    b = np.einsum("sij,psj->psi", t, pts[:, None, :] - p[None, :, 0])  # (P, S, 3)
    inside = (b >= -1e-12).all(-1) & (b.sum(-1) <= 1 + 1e-12)
    assert np.all(inside.sum(1) == 1)
    # The 4D normals point to +w (the graph's upper side).
    assert np.all(_normals4(v, s)[:, 3] > 0)


def test_the_default_extent_is_centred_with_cubic_voxels():
    v, _ = elevation_map(np.zeros((5, 3, 2)))
    # Longest side (x, 4 voxels) spans [−1, 1]: voxel 0.5; y spans 1, z spans 0.5, centred.
    assert v[:, 0].min() == -1 and v[:, 0].max() == 1
    assert v[:, 1].min() == pytest.approx(-0.5) and v[:, 1].max() == pytest.approx(0.5)
    assert v[:, 2].min() == pytest.approx(-0.25) and v[:, 2].max() == pytest.approx(0.25)


def test_nan_cells_become_holes_with_a_warning():
    field = np.zeros((4, 4, 4))
    field[1, 1, 1] = np.nan  # touches 8 of the 27 cubes
    with pytest.warns(UserWarning, match=r"field: 8 grid cubes touching NaN values left out"):
        v, s = elevation_map(field)
    assert len(s) == 6 * (27 - 8)
    assert not np.isnan(v[s].sum())


@pytest.mark.parametrize("bad, message", [
    (np.zeros((3, 3)), r"field: expected a 3D array indexed \[x, y, z\], got 2 dimensions"),
    (np.full((3, 3, 3), np.nan), r"field: .*NaN"),
    (np.array([[["a"]]]), r"field: expected a numeric 3D array, got dtype <U1"),
    (np.zeros((1, 3, 3)), r"field: .*at least 2"),
])
def test_bad_fields_are_refused(bad, message):
    with pytest.raises(ValueError, match=message):
        elevation_map(bad)


def test_a_bad_extent_is_refused():
    with pytest.raises(ValueError, match=r"extent.*x1 .*x0|extent\[0\]"):
        elevation_map(np.zeros((3, 3, 3)), extent=((1, 0), (0, 1), (0, 1)))
    with pytest.raises(ValueError, match=r"extent: expected \(\(x0, x1\)"):
        elevation_map(np.zeros((3, 3, 3)), extent=((0, 1), (0, 1)))
    with pytest.raises(ValueError, match=r"height: expected a number"):
        elevation_map(np.zeros((3, 3, 3)), height="tall")


# -- the scene shape ------------------------------------------------------------------------

D = 5.0  # distance of the orthographic camera above w = 0
CAMERA = dict(position=[0, 0, 0, D], orientation=np.diag([1.0, 1.0, 1.0, -1.0]).tolist(),
              projection="orthographic", extent=0.9, resolution=24)


def _linear():
    a = np.array([0.3, -0.2, 0.5])
    axis = np.linspace(-1, 1, 9)
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    return a, 0.1 + a[0] * x + a[1] * y + a[2] * z


def _cells(r: int, extent: float):
    """xyz of the centres of the retina cells of CAMERA, indexed like the retina [i3, i2, i1]."""
    cell = 2 * extent / r
    i = np.arange(r)
    u1 = (i + 0.5 - r / 2) * cell
    u2 = (r / 2 - i - 0.5) * cell
    u3 = (i + 0.5 - r / 2) * cell
    z, y, x = np.meshgrid(u3, u2, u1, indexing="ij")
    return x, y, z


@pytest.mark.parametrize("smooth", [False, True])
def test_depth_and_normal_of_a_linear_field_are_exact(smooth):
    a, f = _linear()
    h = 0.8
    scene = (ndtrace.Scene(4).set_camera(**CAMERA)
             .add_object("elevation", field=f, height=h, smooth=smooth)
             .set_render(samples=1))
    r = ndtrace.trace(scene)
    assert r.hit.all()
    x, y, z = _cells(24, 0.9)
    expected = D - h * (0.1 + a[0] * x + a[1] * y + a[2] * z)
    np.testing.assert_allclose(r.depth, expected, rtol=0, atol=2e-6)  # float32 depths
    n = np.append(-h * a, 1.0)
    n /= np.linalg.norm(n)
    np.testing.assert_allclose(r.normal.reshape(-1, 4), np.broadcast_to(n, (24**3, 4)), atol=2e-6)


def test_smooth_normals_follow_the_gradient_of_a_curved_field():
    axis = np.linspace(-1, 1, 33)
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    f = 0.5 * (x**2 + y * z)
    h = 0.6
    scene = (ndtrace.Scene(4).set_camera(**{**CAMERA, "resolution": 16})
             .add_object("elevation", field=f, height=h, smooth=True).set_render(samples=1))
    r = ndtrace.trace(scene)
    cx, cy, cz = _cells(16, 0.9)
    grad = np.stack([cx, 0.5 * cz, 0.5 * cy], -1)
    n = np.concatenate([-h * grad, np.ones(cx.shape + (1,))], -1)
    n /= np.linalg.norm(n, axis=-1, keepdims=True)
    # Central differences on a grid of spacing 1/16 are exact for quadratics at the grid points;
    # between them the interpolation error is O(spacing²).
    assert np.abs(r.normal - n).max() < 5e-3


def _flat_scene(material: dict, values=None):
    """A flat field (the hyperplane w = 0) under ambient light only: the retina's colour is the
    texture's colour, unshaded."""
    obj = dict(field=np.zeros((9, 9, 9)), material={"ambient": 1.0, **material})
    if values is not None:
        obj["values"] = values
    return (ndtrace.Scene(4, ambient=[1, 1, 1]).set_camera(**CAMERA)
            .add_object("elevation", **obj).set_render(samples=1))


def _vertex_x():
    axis = np.linspace(-1, 1, 9)
    return np.meshgrid(axis, axis, axis, indexing="ij")[0].reshape(-1)


def _linear_rgb(srgb):
    """matplotlib's tables are sRGB; the retina is linear RGB (IEC 61966-2-1)."""
    return np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)


def _table(mpl, name, t):
    """matplotlib's 256-entry table of ``name``, in linear RGB, interpolated linearly at t."""
    k = np.linspace(0, 1, 256)
    table = _linear_rgb(mpl.colormaps[name].resampled(256)(k)[:, :3])
    return np.stack([np.interp(t, k, table[:, c]) for c in range(3)], -1)


def test_the_colormap_colours_by_value():
    mpl = pytest.importorskip("matplotlib")
    r = ndtrace.trace(_flat_scene({"colormap": "viridis", "range": [-1, 1]}, _vertex_x()))
    x, _, _ = _cells(24, 0.9)
    want = _table(mpl, "viridis", (x + 1) / 2)
    assert np.abs(r.rgba[..., :3] - want).max() < 1e-5


@pytest.mark.parametrize("name", ["viridis", "magma", "coolwarm", "terrain", "gray_r"])
def test_the_colormap_tables_are_matplotlibs(name):
    mpl = pytest.importorskip("matplotlib")
    r = ndtrace.trace(_flat_scene({"colormap": name, "range": [-1, 1]}, _vertex_x()))
    row = r.rgba[12, 12, :, :3]  # x varies along i1
    x, _, _ = _cells(24, 0.9)
    want = _table(mpl, name, (x[12, 12] + 1) / 2)
    assert np.abs(row - want).max() < 1e-5, name
    # And within one table step of matplotlib's own (nearest-entry) lookup.
    assert np.abs(row - _linear_rgb(mpl.colormaps[name]((x[12, 12] + 1) / 2)[..., :3])).max() < 0.03


def test_isolines_and_the_lattice_fall_where_they_should():
    width = 0.1
    scene = _flat_scene({"color": [0, 0, 1], "isolines": {"values": [0.25], "width": width,
                                                          "color": [1, 0, 0]}}, _vertex_x())
    r = ndtrace.trace(scene)
    x, _, _ = _cells(24, 0.9)
    red = r.rgba[..., 0] > 0.5
    assert np.array_equal(red, np.abs(x - 0.25) <= width / 2 + 1e-9)
    assert np.all(r.rgba[~red][:, 2] == 1)
    # The lattice: planes x, y, z = k·spacing.
    spacing, width = 0.5, 0.08
    r = ndtrace.trace(_flat_scene({"color": [0, 0, 1], "lattice": {"spacing": spacing, "width": width,
                                                                   "color": [1, 1, 1]}}))
    x, y, z = _cells(24, 0.9)
    on = np.zeros(x.shape, bool)
    for c in (x, y, z):
        on |= np.abs(c / spacing - np.round(c / spacing)) * spacing <= width / 2
    assert np.array_equal(r.rgba[..., 0] > 0.5, on)
    assert on.any() and (~on).any()


# -- files ----------------------------------------------------------------------------------

def _toml(tmp_path, field_line: str) -> str:
    text = textwrap.dedent(f"""\
        dim = 4
        [camera]
        position = [0.6, 0.8, 1.0, 3.0]
        look_at = [0, 0, 0, 0]
        up = [[0, 1, 0, 0], [0, 0, 1, 0]]
        fov = 50
        resolution = 12
        [[lights]]
        type = "directional"
        direction = [0.3, 0.5, 0.2, 1.0]
        [[objects]]
        shape = "elevation"
        {field_line}
        height = 0.5
        smooth = true
        material = {{ colormap = "viridis" }}
        """)
    path = tmp_path / "scan.toml"
    path.write_text(text)
    return str(path)


def _field():
    axis = np.linspace(-1, 1, 7)
    x, y, z = np.meshgrid(axis, axis, np.linspace(-1, 1, 5), indexing="ij")
    return np.exp(-2 * (x**2 + y**2 + z**2)) + 0.2 * x


def test_npy_npz_and_nifti_files_load_the_same_scene(tmp_path):
    nib = pytest.importorskip("nibabel")
    f = _field()
    np.save(tmp_path / "f.npy", f)
    np.savez(tmp_path / "f.npz", other=np.zeros(3), density=f)
    nib.save(nib.Nifti1Image(f, np.eye(4)), str(tmp_path / "f.nii.gz"))
    nib.save(nib.Nifti1Image(f.astype(np.float32).astype(np.float64), np.eye(4)), str(tmp_path / "f.nii"))
    inline = ndtrace.trace(ndtrace.load_file(_toml(tmp_path, f"field = {f.tolist()}")))
    assert inline.hit.mean() > 0.1
    for line in ['field = "f.npy"', 'field = "f.npz"\nkey = "density"', 'field = "f.nii.gz"']:
        r = ndtrace.trace(ndtrace.load_file(_toml(tmp_path, line)))
        assert np.array_equal(r.rgba, inline.rgba), line
        assert np.array_equal(r.depth, inline.depth), line
    # The builder takes the array itself, and mesh.read_field the files.
    built = (ndtrace.Scene(4).set_camera([0.6, 0.8, 1.0, 3.0], look_at=[0, 0, 0, 0],
                                         up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=50, resolution=12)
             .add_light("directional", direction=[0.3, 0.5, 0.2, 1.0])
             .add_object("elevation", field=f, height=0.5, smooth=True,
                         material={"colormap": "viridis"}))
    assert np.array_equal(ndtrace.trace(built).rgba, inline.rgba)
    for name in ("f.npy", "f.nii.gz"):
        assert np.array_equal(ndtrace.mesh.read_field(tmp_path / name), f)
    assert np.array_equal(ndtrace.mesh.read_field(tmp_path / "f.npz", key="density"), f)


@pytest.mark.parametrize("line, message", [
    ('field = "missing.npy"', r"scan\.toml:\d+:\d+: objects\[0\]\.field: .*missing\.npy"),
    ('field = [[1, 2], [3, 4]]', r"scan\.toml:13:9: objects\[0\]\.field: expected a file name or a "
                                 r"3-D array of numbers"),
    ('field = "f2.npy"', r"scan\.toml:13:9: objects\[0\]\.field: .*f2\.npy: expected a 3-D array "
                         r"indexed \[x, y, z\], got shape \[3, 3\]"),
    ('field = "fs.npy"', r"objects\[0\]\.field: .*fs\.npy: unsupported dtype '<U1'"),
    ('field = "nan.npy"', r"objects\[0\]\.field: .*NaN"),
    ('field = "f.npz"\nkey = "nope"', r"objects\[0\]\.field: .*f\.npz has no array named \"nope\" "
                                     r"\(arrays: density\)"),
    ('field = "f.npy"\nextent = [[1, 0], [0, 1], [0, 1]]', r"scan\.toml:\d+:\d+: objects\[0\]\.extent"),
])
def test_bad_fields_in_scene_files_give_located_errors(tmp_path, line, message):
    np.save(tmp_path / "f.npy", _field())
    np.save(tmp_path / "f2.npy", np.zeros((3, 3)))
    np.save(tmp_path / "fs.npy", np.array([[["a", "b"]] * 2] * 2))
    np.save(tmp_path / "nan.npy", np.full((3, 3, 3), np.nan))
    np.savez(tmp_path / "f.npz", density=_field())
    with pytest.raises(ValueError, match=message):
        ndtrace.load_file(_toml(tmp_path, line))


def test_the_cli_renders_an_elevation_scene(tmp_path):
    import subprocess
    import sys

    np.save(tmp_path / "f.npy", _field())
    out = tmp_path / "scan.png"
    subprocess.run([sys.executable, "-m", "ndtrace.cli", _toml(tmp_path, 'field = "f.npy"'), "-o",
                    str(out), "--quiet"], check=True)
    assert out.stat().st_size > 1000


def test_the_example_scenes_use_real_data():
    """The MR scene reads the volume bundled with nibabel's tests (nothing downloaded)."""
    nib = pytest.importorskip("nibabel")
    path = os.path.join(os.path.dirname(nib.__file__), "tests", "data", "anatomical.nii")
    assert os.path.isfile(path)
    img = nib.load(path)
    assert img.shape[:3] == (33, 41, 25)


def _array_scene(field):
    return (ndtrace.Scene(4).set_camera([0.6, 0.8, 1.0, 3.0], look_at=[0, 0, 0, 0],
                                        up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=50, resolution=12)
            .add_light("directional", direction=[0.3, 0.5, 0.2, 1.0])
            .add_object("elevation", field=field, height=0.5, smooth=True,
                        material={"colormap": "viridis"}))


def test_an_array_field_travels_as_an_array_and_equals_its_lists():
    f = _field()
    scene = _array_scene(f)
    # to_dict gives the array back (not 35 nested lists), and every way round gives the same scene.
    d = scene.to_dict()
    assert isinstance(d["objects"][0]["field"], np.ndarray)
    assert np.array_equal(d["objects"][0]["field"], f)
    again = ndtrace.load_dict(d)
    from_toml = ndtrace.load_toml(scene.to_toml())
    assert isinstance(from_toml.to_dict()["objects"][0]["field"], list)
    lists = _array_scene(f.tolist())
    assert scene == again == from_toml == lists and lists == scene
    changed = f.copy()
    changed[3, 2, 1] += 1e-9
    assert scene != _array_scene(changed) and _array_scene(changed) != lists
    want = ndtrace.trace(lists)
    for other in (scene, again, from_toml, scene.copy()):
        r = ndtrace.trace(other)
        assert np.array_equal(r.rgba, want.rgba) and np.array_equal(r.depth, want.depth)
    # Strided, float32 and integer arrays are read in C order as float64.
    g = np.asfortranarray(np.round(f * 100))
    assert ndtrace.trace(_array_scene(g)).depth.tobytes() == \
        ndtrace.trace(_array_scene(g.astype(np.int32)[:, :, :])).depth.tobytes()
    assert ndtrace.trace(_array_scene(f[::-1].astype(np.float32))).depth.tobytes() == \
        ndtrace.trace(_array_scene(f[::-1].astype(np.float32).astype(np.float64).tolist())).depth.tobytes()


def test_loading_a_dict_with_an_array_field_leaves_the_dict_alone():
    f = _field()
    d = _array_scene(f).to_dict()
    obj = d["objects"][0]
    ndtrace.load_dict(d)
    assert d["objects"][0] is obj and obj["field"] is not None
    assert isinstance(obj["field"], np.ndarray) and np.array_equal(obj["field"], f)


@pytest.mark.parametrize("bad, message", [
    (np.zeros((3, 3)), r"objects\[0\]\.field: expected a 3D array indexed \[x, y, z\], got 2 dimensions"),
    (np.array([[["a", "b"]] * 2] * 2), r"objects\[0\]\.field: expected a numeric 3D array, got dtype <U1"),
])
def test_bad_array_fields_in_dicts_give_located_errors(bad, message):
    d = _array_scene(_field()).to_dict()
    d["objects"] = [{"shape": "hypercube"}, d["objects"][0]]
    d["objects"][1]["field"] = bad
    with pytest.raises(ValueError, match="^<dict>: " + message.replace("0", "1", 1)):
        ndtrace.load_dict(d)
    # The builder refuses it at once, naming the object it would be.
    scene = ndtrace.Scene(4).add_object("hypercube")
    with pytest.raises(ValueError, match="^" + message.replace("0", "1", 1)):
        scene.add_object("elevation", field=bad)


def test_the_core_loader_reads_a_fortran_ordered_field_in_index_order():
    f = _field()
    d = _array_scene(f).to_dict()
    want = ndtrace.trace(ndtrace.load_dict(d)).depth
    d["objects"][0]["field"] = np.asfortranarray(f)
    got = ndtrace.trace(ndtrace.Scene._from_compiled(ndtrace._ndtrace.load_dict(d, "<d>", None, None), None))
    assert np.array_equal(got.depth, want)


def test_a_masked_field_equals_its_copies():
    f = _field()
    f[2, 3, 1] = np.nan
    with pytest.warns(UserWarning, match="holes"):
        scene = _array_scene(f)
        scene.compiled()
        assert scene == scene.copy() == ndtrace.load_dict(scene.to_dict())


@pytest.mark.parametrize("bad, message", [
    (np.zeros((2, 2, 2), np.int32), r"<d>: objects\[0\]\.field: expected a float64 array, got dtype int32"),
    (np.zeros((2, 2)), r"<d>: objects\[0\]\.field: expected a 3-D array indexed \[x, y, z\], got shape \[2, 2\]"),
])
def test_the_core_loader_checks_array_fields_itself(bad, message):
    # Below the Python wrapper (which converts dtypes), the bindings still refuse what they
    # cannot read, naming the field.
    d = _array_scene(_field()).to_dict()
    d["objects"][0]["field"] = bad
    with pytest.raises(ValueError, match=message):
        ndtrace._ndtrace.load_dict(d, "<d>", None, None)


def test_the_builder_keeps_a_snapshot_of_the_field():
    f = _field()
    scene = _array_scene(f)
    want = ndtrace.trace(scene).depth
    f += 1.0  # the caller's array changes after add_object: the scene does not
    scene.set_render(samples=1)  # (and a rebuild reads the snapshot)
    assert np.array_equal(ndtrace.trace(scene).depth, want)
