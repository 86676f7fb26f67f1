"""Mesh arrays from numpy travel as arrays (issue 23): a mesh's or surface's ``vertices``,
``simplices``, ``triangles`` and per-vertex ``values`` go to the core as one buffer each (no
nested lists), come back from ``to_dict`` as arrays, and give the same scene and bit-identical
traces as the nested lists they equal."""

from __future__ import annotations

import pickle
import re

import numpy as np
import pytest

import ndtrace
from ndtrace import _ndtrace

CAMERA = dict(position=[0.6, 0.8, 1.0, 3.0], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]],
              fov=50, resolution=10)


def _mesh():
    v, s = ndtrace.mesh.elevation_map(np.random.default_rng(7).random((5, 4, 3)), height=0.4)
    values = v[:, 3] * 2 - 0.1
    return v, s, values


def _scene(v, s, values, **material):
    return (ndtrace.Scene(4).set_camera(**CAMERA)
            .add_light("directional", direction=[0.3, 0.5, 0.2, 1.0])
            .add_object("mesh", vertices=v, simplices=s, values=values,
                        material={"colormap": "viridis", **material}))


def _same_trace(a, b):
    ra, rb = ndtrace.trace(a), ndtrace.trace(b)
    assert np.isfinite(ra.depth).any()
    for name in ("rgba", "depth", "normal", "object_id", "primitive_id"):
        assert np.array_equal(getattr(ra, name), getattr(rb, name), equal_nan=True), name


def test_mesh_arrays_travel_as_arrays_and_equal_their_lists():
    v, s, values = _mesh()
    scene = _scene(v, s, values)
    d = scene.to_dict()["objects"][0]
    for key, want in (("vertices", v), ("simplices", s), ("values", values)):
        assert isinstance(d[key], np.ndarray), key
        assert np.array_equal(d[key], want), key
    assert d["simplices"].dtype == np.int64 and d["vertices"].dtype == np.float64
    lists = _scene(v.tolist(), s.tolist(), values.tolist())
    assert isinstance(lists.to_dict()["objects"][0]["vertices"], list)
    again = ndtrace.load_dict(scene.to_dict())
    from_toml = ndtrace.load_toml(scene.to_toml())
    assert scene == lists == again == from_toml and lists == scene
    # to_dict(lists=True) is plain data, the same whichever form the scene was given in.
    assert scene.to_dict(lists=True) == lists.to_dict(lists=True) == lists.to_dict()
    for other in (lists, again, from_toml, scene.copy(), pickle.loads(pickle.dumps(scene))):
        _same_trace(scene, other)
    moved = v.copy()
    moved[5, 1] += 1e-9
    assert _scene(moved, s, values) != scene and lists != _scene(moved, s, values)


@pytest.mark.parametrize("convert", [
    lambda v, s, x: (v.astype(np.float32).astype(np.float64), s.astype(np.int32), x),
    lambda v, s, x: (np.asfortranarray(v), np.asfortranarray(s), x),
    lambda v, s, x: (np.hstack([v, v])[:, :4], s[::-1][::-1], np.repeat(x, 2)[::2]),
    lambda v, s, x: (v.astype(np.float32), s.astype(np.uint16), x.astype(np.float32)),
], ids=["int32 indices", "Fortran order", "strided views", "float32 and uint16"])
def test_any_numeric_dtype_and_layout_reads_as_its_values(convert):
    v, s, values = _mesh()
    cv, cs, cx = convert(v, s, values)
    want = _scene(np.asarray(cv, np.float64).tolist(), np.asarray(cs).tolist(),
                  np.asarray(cx, np.float64).tolist())
    got = _scene(cv, cs, cx)
    assert got == want
    _same_trace(got, want)


def test_the_scene_keeps_a_snapshot_and_leaves_the_callers_dict_alone():
    v, s, values = _mesh()
    scene = _scene(v, s, values)
    want = ndtrace.trace(scene).depth
    v += 0.5
    s[:] = s[::-1]
    scene.set_render(samples=1)  # a rebuild reads the snapshot
    assert np.array_equal(ndtrace.trace(scene).depth, want, equal_nan=True)
    d = scene.to_dict()
    obj = d["objects"][0]
    keep = {k: obj[k] for k in ("vertices", "simplices", "values")}
    ndtrace.load_dict(d)
    assert all(obj[k] is keep[k] for k in keep)
    # The description's own arrays are read-only (copies share them).
    data_obj = scene._data["objects"][0]
    assert not data_obj["vertices"].flags.writeable and not data_obj["simplices"].flags.writeable
    assert scene.copy()._data["objects"][0]["vertices"] is data_obj["vertices"]


def test_a_surface_takes_its_arrays_too():
    t = np.linspace(0, 2 * np.pi, 9)[:-1]
    u, w = np.meshgrid(t, t, indexing="ij")
    verts = np.stack([np.cos(u), np.sin(u), np.cos(w), np.sin(w)], -1).reshape(-1, 4) * 0.7
    n = len(t)
    idx = np.arange(n * n).reshape(n, n)
    a, b = idx, np.roll(idx, -1, 0)
    c, d = np.roll(idx, -1, 1), np.roll(np.roll(idx, -1, 0), -1, 1)
    tris = np.concatenate([np.stack([a, b, d], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])

    def surface(v, t):
        return ndtrace.Scene(4).set_camera(**CAMERA).add_object("surface", vertices=v, triangles=t)
    arrays, lists = surface(verts, tris), surface(verts.tolist(), tris.tolist())
    assert isinstance(arrays.to_dict()["objects"][0]["triangles"], np.ndarray)
    assert arrays == lists
    _same_trace(arrays, lists)


def _located(scene_or_dict):
    with pytest.raises(ValueError) as e:
        if isinstance(scene_or_dict, dict):
            ndtrace.load_dict(scene_or_dict, name="<d>")
        else:
            scene_or_dict.compiled()
    return str(e.value)


def test_bad_arrays_are_located_errors():
    v, s, values = _mesh()
    bad = s.copy()
    bad[3, 2] = len(v)
    assert re.search(rf"objects\[0\]\.simplices\[3\]\[2\]: vertex index {len(v)} out of range",
                     _located(_scene(v, bad, values)))
    nan = v.copy()
    nan[2, 1] = np.nan
    assert re.search(r"objects\[0\]\.vertices\[2\]\[1\]: non-finite", _located(_scene(nan, s, values)))
    assert re.search(r"objects\[0\]\.vertices\[0\]: expected 4 numbers \(dim = 4\), got 3",
                     _located(_scene(v[:, :3], s, values)))
    assert re.search(r"objects\[0\]\.simplices\[0\]: an \(N−1\)-simplex has 4 vertex indices",
                     _located(_scene(v, s[:, :3], values)))
    assert re.search(r"objects\[0\]\.values: one value per vertex", _located(_scene(v, s, values[:-1])))
    # A float array of indices is not taken as indices (as with lists of floats).
    assert "objects[0].simplices" in _located(_scene(v, s.astype(float) + 0.5, values))


def _raw(**obj):
    return {"dim": 4, "camera": {k: v for k, v in CAMERA.items()},
            "objects": [{"shape": "mesh", **obj}]}


@pytest.mark.parametrize("key, value, message", [
    ("vertices", np.zeros((4, 4), np.float32), r"expected a float64 array, got dtype float32"),
    ("simplices", np.zeros((1, 4), np.int32), r"expected an int64 array, got dtype int32"),
    ("vertices", np.zeros(4), r"expected a 2-D array indexed \(vertex, coordinate\), got shape \[4\]"),
    ("values", np.zeros((4, 1)), r"expected a 1-D array indexed \(vertex,\), got shape \[4, 1\]"),
])
def test_the_bindings_check_arrays_themselves(key, value, message):
    # Below the Python wrapper (which converts dtypes), the bindings refuse what they cannot take.
    obj = {"vertices": np.eye(4), "simplices": np.array([[0, 1, 2, 3]]), key: value}
    with pytest.raises(ValueError, match=r"^<raw>: objects\[0\]\." + key + ": " + message):
        _ndtrace.load_dict(_raw(**obj), "<raw>", None, None)


def test_masked_entries_and_empty_rows_are_refused_as_their_lists_are():
    v, s, values = _mesh()
    mv = np.ma.masked_array(v, mask=np.zeros_like(v, bool))
    mv.mask[2, 1] = True
    assert re.search(r"objects\[0\]\.vertices\[2\]\[1\]: non-finite", _located(_scene(mv, s, values)))
    mx = np.ma.masked_array(values, mask=np.arange(len(values)) == 4)
    assert re.search(r"objects\[0\]\.values\[4\]: must be finite", _located(_scene(v, s, mx)))
    ms = np.ma.masked_array(s, mask=np.zeros_like(s, bool))
    ms.mask[1, 0] = True
    assert "objects[0].simplices" in _located(_scene(v, ms, values))
    # A mask with nothing masked is the plain array.
    assert _scene(np.ma.masked_array(v), s, values) == _scene(v, s, values)
    # Rows of no numbers are refused (an empty mesh is not silently made of them).
    assert re.search(r"objects\[0\]\.simplices\[0\]: an \(N−1\)-simplex has 4 vertex indices \(dim = 4\), got 0",
                     _located(_scene(v, np.zeros((5, 0), np.int64), values)))
    with pytest.raises(ValueError, match=r"^<raw>: objects\[0\]\.simplices: expected rows of numbers"):
        _ndtrace.load_dict(_raw(vertices=np.eye(4), simplices=np.zeros((5, 0), np.int64)), "<raw>", None, None)


def test_a_read_only_view_of_the_callers_memory_is_still_a_snapshot():
    v, s, values = _mesh()
    base = v.copy()
    view = base.view()
    view.setflags(write=False)
    scene = _scene(view, s, values)
    want = ndtrace.trace(scene).depth
    base += 0.5  # the caller's memory changes under its read-only view
    scene.set_render(samples=1)
    assert np.array_equal(ndtrace.trace(scene).depth, want, equal_nan=True)
    assert scene == _scene(v, s, values)


def test_the_bindings_read_any_layout_in_index_order():
    # Straight to the bindings (the wrapper makes C-ordered copies first): Fortran-ordered and
    # strided arrays are read in index order, not as their memory lies.
    v, s, values = _mesh()
    cam = {"position": CAMERA["position"], "look_at": CAMERA["look_at"], "up": CAMERA["up"],
           "fov": CAMERA["fov"], "resolution": CAMERA["resolution"]}

    def depth(vv, ss):
        d = {"dim": 4, "camera": cam, "objects": [{"shape": "mesh", "vertices": vv, "simplices": ss}]}
        compiled = _ndtrace.load_dict(d, "<raw>", None, None)
        return ndtrace.trace(ndtrace.Scene._from_compiled(compiled, None)).depth
    want = depth(v, s)
    assert np.isfinite(want).any()
    wide_v = np.zeros((len(v), 8))
    wide_v[:, ::2] = v
    wide_s = np.zeros((len(s) * 2, 4), np.int64)
    wide_s[::2] = s
    for vv, ss in ((np.asfortranarray(v), np.asfortranarray(s)), (wide_v[:, ::2], wide_s[::2])):
        assert not (vv.flags.c_contiguous or ss.flags.c_contiguous)
        assert np.array_equal(depth(vv, ss), want, equal_nan=True)


def _in_bytes(a):
    return np.frombuffer(a.tobytes(), a.dtype).reshape(a.shape)


def _bytes_of(a):
    while not isinstance(a, bytes):
        a = a.base
    return a


def test_only_numbers_in_bytes_are_lendable():
    a = np.arange(12.0).reshape(4, 3)
    assert not _ndtrace.lendable(a)  # writeable
    owned = a.copy()
    owned.setflags(write=False)
    assert not _ndtrace.lendable(owned)  # its memory can change (resize, setflags, a view)
    in_bytes = _in_bytes(a)
    assert _ndtrace.lendable(in_bytes) and _ndtrace.lendable(in_bytes[1:])
    assert not _ndtrace.lendable(in_bytes[:, ::2])  # not C-ordered
    mutable = np.frombuffer(bytearray(96))
    mutable.setflags(write=False)
    assert not _ndtrace.lendable(mutable)  # the bytearray can change

    class Lie(np.ndarray):
        base = property(lambda self: bytes(96))

    liar = owned.view(Lie)
    assert not _ndtrace.lendable(liar)  # its memory is not in the bytes it names
    assert not _ndtrace.lendable([1.0, 2.0])


def test_the_scene_snapshots_in_bytes_and_the_core_reads_them_in_place():
    import sys

    v, s, values = _mesh()
    given = _in_bytes(v)
    scene = _scene(given, s, values)
    obj = scene._data["objects"][0]
    # Numbers already in bytes are their own snapshot; the others are snapshot in bytes once.
    assert obj["vertices"] is given
    assert all(_ndtrace.lendable(obj[k]) for k in ("vertices", "simplices", "values"))
    held = [_bytes_of(obj[k]) for k in ("vertices", "simplices", "values")]
    before = [sys.getrefcount(b) for b in held]
    compiled = scene.compiled()
    # The core holds each bytes object (one reference each) instead of copying its numbers.
    assert [sys.getrefcount(b) for b in held] == [n + 1 for n in before]
    _same_trace(scene, _scene(v.tolist(), s.tolist(), values.tolist()))
    del compiled
    scene.set_render(samples=1)
    import gc

    gc.collect()
    assert [sys.getrefcount(b) for b in held] == before


def test_memory_the_caller_can_still_change_is_copied():
    v, s, values = _mesh()
    owned = v.copy()
    early_view = owned[:]  # made before the array is made read-only
    owned.setflags(write=False)
    compiled = _scene(owned, s, values).compiled()
    early_view[0, 0] += 1.0
    owned.setflags(write=True)
    owned[1, 0] += 1.0
    got = compiled.to_dict()["objects"][0]["vertices"]
    assert got[0, 0] == v[0, 0] and got[1, 0] == v[1, 0]


def test_the_core_keeps_lent_numbers_alive():
    import gc

    def compiled():
        v, s, values = _mesh()
        return _scene(v, s, values).compiled(), v.copy(), s.copy()

    c, v, s = compiled()  # the scene and its arrays are gone but for the core's references
    gc.collect()
    junk = [np.full(v.shape, 7.0) for _ in range(50)]  # memory freed would be reused
    obj = c.to_dict()["objects"][0]
    assert np.array_equal(obj["vertices"], v) and np.array_equal(obj["simplices"], s)
    del junk
