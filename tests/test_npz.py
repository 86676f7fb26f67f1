"""Mesh files in numpy's ``.npz`` format, read by the core (npyz): every byte order and numeric
dtype numpy writes gives the retina of the float64 / int64 file, and what cannot be a mesh
(1-D arrays, complex or string dtypes, bool or float indices, missing arrays, broken files) is
a ValueError naming the scene line, the field, the file and the array."""

from __future__ import annotations

import itertools
import zipfile

import numpy as np
import pytest

import ndtrace
from ndtrace import mesh as ndmesh

pytest.importorskip("scipy")


def tesseract_boundary():
    """The 4D hypercube's boundary as outward tetrahedra: integer vertices, exact in every
    dtype (float16 included)."""
    v, s = ndmesh.convex_hull(np.array(list(itertools.product([-1.0, 1.0], repeat=4))))
    return v, s.astype(np.int64)


SCENE = """dim = 4
[camera]
position = [1.2, 1.6, 2.0, 4.5]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 50
resolution = 10

[[lights]]
type = "directional"
direction = [0.4, 0.8, 0.6, 1.0]

[[objects]]
shape = "mesh"
file = "{file}"
"""


def traced(tmp_path, file, **arrays):
    save = np.savez_compressed if file.startswith("z") else np.savez
    save(tmp_path / file, **arrays)
    (tmp_path / "scene.toml").write_text(SCENE.format(file=file))
    return ndtrace.trace(ndtrace.load_file(tmp_path / "scene.toml"))


def same_retina(a, b):
    for k in ("rgba", "depth", "normal", "object_id", "primitive_id"):
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k), err_msg=k)


def test_the_tesseract_is_closed_and_outward_so_it_is_a_fair_reference(tmp_path):
    v, s = tesseract_boundary()
    ref = traced(tmp_path, "ref.npz", vertices=v, simplices=s)
    assert ref.hit.sum() > 30
    scene = ndtrace.load_file(tmp_path / "scene.toml")
    assert not scene.warnings, scene.warnings


@pytest.mark.parametrize("vdtype", [">f8", "<f4", ">f4", "<f2", ">f2", ">i4", "<i2", "|i1", ">i8"])
@pytest.mark.parametrize("sdtype", [">i4", "<i4", ">i8", "<u2", ">u4", "|u1", ">u8"])
def test_every_numeric_dtype_and_byte_order_gives_the_retina_of_float64(tmp_path, vdtype, sdtype):
    v, s = tesseract_boundary()
    ref = traced(tmp_path, "ref.npz", vertices=v, simplices=s)
    got = traced(tmp_path, "other.npz", vertices=v.astype(vdtype), simplices=s.astype(sdtype))
    same_retina(got, ref)


def test_fortran_order_compressed_archives_and_bool_vertices_read_as_numpy_does(tmp_path):
    v, s = tesseract_boundary()
    ref = traced(tmp_path, "ref.npz", vertices=v, simplices=s)
    # A transposed array is saved in Fortran order; savez_compressed deflates the entries.
    same_retina(traced(tmp_path, "fortran.npz", vertices=np.asfortranarray(v), simplices=s.T.copy().T), ref)
    same_retina(traced(tmp_path, "z.npz", vertices=v.astype(">f2"), simplices=s), ref)
    # bool coordinates are 0 and 1: the cube [0, 1]^4 from bool vertices is the tesseract
    # moved and halved.
    cube = traced(tmp_path, "bool.npz", vertices=(v > 0), simplices=s)
    halved = traced(tmp_path, "halved.npz", vertices=(v + 1) / 2, simplices=s)
    same_retina(cube, halved)


def load_error(tmp_path, file="bad.npz", **arrays) -> str:
    if arrays:
        np.savez(tmp_path / file, **arrays)
    (tmp_path / "scene.toml").write_text(SCENE.format(file=file))
    with pytest.raises(ValueError) as e:
        ndtrace.load_file(tmp_path / "scene.toml")
    message = str(e.value)
    prefix = f"{tmp_path / 'scene.toml'}:15:8: objects[0].file: {tmp_path / file}"
    assert message.startswith(prefix), message
    return message[len(prefix):]


def test_arrays_that_cannot_be_a_mesh_are_errors_naming_file_and_array(tmp_path):
    v, s = tesseract_boundary()
    assert load_error(tmp_path, vertices=v.ravel(), simplices=s) == (
        ': array "vertices": expected a 2-D array, got a 1-D array of shape (64,) (dtype '
        "'<f8'); save it with shape (rows, columns), e.g. a.reshape(-1, dim)")
    e = load_error(tmp_path, vertices=v, simplices=s[None])
    assert e.startswith(f': array "simplices": expected a 2-D array, got a 3-D array of shape (1, {len(s)}, 4)'), e
    e = load_error(tmp_path, vertices=v.astype(np.complex128), simplices=s)
    assert e == ': array "vertices": unsupported dtype \'<c16\' (use a float, integer or bool type such as float64 or int64)', e
    e = load_error(tmp_path, vertices=v.astype("U3"), simplices=s)
    assert e.startswith(': array "vertices": unsupported dtype \'<U3\''), e
    assert load_error(tmp_path, vertices=v, simplices=s.astype(np.float64)) == (
        ': array "simplices" must hold integer vertex indices, not floats or bools '
        "(e.g. simplices.astype(numpy.int64))")
    assert "must hold integer vertex indices" in load_error(tmp_path, vertices=v, simplices=s > 0)
    e = load_error(tmp_path, vertices=v[:, :3], simplices=s)
    assert e == ': array "vertices" has shape (16, 3), expected (V, 4) for a scene of dimension 4', e
    e = load_error(tmp_path, vertices=v, simplices=s[:, :3])
    assert e == f': array "simplices" has shape ({len(s)}, 3), expected (S, 4) for a scene of dimension 4', e
    assert load_error(tmp_path, vertices=v) == ' has no array named "simplices"'
    np.savez(tmp_path / "bad.npz", vertices=v, simplices=s + 16)
    with pytest.raises(ValueError, match=r"scene\.toml:\d+:\d+: objects\[0\]\.file:simplices\[0\]\[0\]: "
                       r"vertex index \d+ out of range: the mesh has 16 vertices"):
        ndtrace.load_file(tmp_path / "scene.toml")


def test_broken_files_are_errors_not_crashes(tmp_path):
    (tmp_path / "bad.npz").write_bytes(b"not a zip at all")
    assert "is not an .npz (zip) archive" in load_error(tmp_path)
    # A zip whose vertices entry is cut short, or claims a huge shape in a small file.
    v, s = tesseract_boundary()
    np.savez(tmp_path / "good.npz", vertices=v, simplices=s)
    with zipfile.ZipFile(tmp_path / "good.npz") as z:
        vbytes = z.read("vertices.npy")
    for name, payload, want in [
        ("cut", vbytes[:-8], "truncated data: shape (16, 4) of '<f8' needs 512 bytes, the array holds 504"),
        ("header", vbytes[:20], "truncated .npy header"),
        ("magic", b"\x00" + vbytes[1:], "not an .npy array"),
    ]:
        with zipfile.ZipFile(tmp_path / f"{name}.npz", "w") as z:
            z.writestr("vertices.npy", payload)
            z.writestr("simplices.npy", z_read(tmp_path / "good.npz", "simplices.npy"))
        e = load_error(tmp_path, f"{name}.npz")
        assert e.startswith(': array "vertices": '), e
        if want:
            assert want in e, e


def z_read(path, name):
    with zipfile.ZipFile(path) as z:
        return z.read(name)


def test_a_shape_larger_than_the_file_is_refused_before_allocating(tmp_path):
    v, s = tesseract_boundary()
    np.savez(tmp_path / "good.npz", vertices=v, simplices=s)
    vbytes = z_read(tmp_path / "good.npz", "vertices.npy")
    header_end = vbytes.index(b"\n") + 1
    for shape, want in [
        (b"(100000000000, 4)", "truncated data: the shape claims 400000000000 elements"),
        (b"(4294967296, 4294967296)", "the shape's dimensions overflow when multiplied"),
    ]:
        header = vbytes[10:header_end].replace(b"(16, 4)", shape).rstrip(b" \n")
        header = header + b" " * (-(10 + len(header) + 1) % 64) + b"\n"
        payload = vbytes[:8] + len(header).to_bytes(2, "little") + header + vbytes[header_end:]
        with zipfile.ZipFile(tmp_path / "big.npz", "w") as z:
            z.writestr("vertices.npy", payload)
            z.writestr("simplices.npy", z_read(tmp_path / "good.npz", "simplices.npy"))
        e = load_error(tmp_path, "big.npz")
        assert e.startswith(': array "vertices": ' + want), e
