"""Meshes: the tessellations of (N−1)-simplices that ndtrace renders, to and from the Python
mesh ecosystem (scipy, meshio, trimesh).

A mesh is a pair ``(vertices, simplices)``: ``vertices`` of shape (V, N), float64, and
``simplices`` of shape (S, N), int64 indices into ``vertices``, one row per (N−1)-simplex. The
order of a row fixes the simplex's orientation: its normal is the generalized cross product of
``x_1 − x_0 … x_{N−1} − x_0`` (eq. 6 of the course notes; for N = 3 the usual right-hand,
counter-clockwise rule of OBJ and STL files). A closed mesh is **consistently oriented** when
the two simplices at every ridge (N − 1 shared vertices) induce opposite orientations on it, and
**outward** when its enclosed volume ``Σ N_s·(x_0 − c) / N!`` is positive. Back-face culling
and the convexity shortcut of shadow rays rely on both; a scene warns when it loads a closed
mesh that is not consistently oriented.

Every function takes and returns such a pair, so they compose::

    vertices, simplices = ndtrace.mesh.convex_hull(points)            # outward hull, N = 2…8
    vertices, simplices = ndtrace.mesh.orient(vertices, simplices)    # repair orientation
    edges = ndtrace.mesh.feature_edges(vertices, simplices)           # the polytope's edges
    vertices, simplices = ndtrace.mesh.read("bunny.obj")               # meshio formats, .npz
    vertices, simplices = ndtrace.mesh.thicken_surface(v4, triangles, radius=0.05)  # a tube in R^4
    vertices, simplices = ndtrace.mesh.thicken_points(points4, radius=0.01)  # tiny 3-spheres
    vertices, simplices = ndtrace.mesh.elevation_map(field, height=0.5)  # w = 0.5·f(x, y, z)
    coords, pieces, basis, origin = ndtrace.mesh.slice(vertices, simplices, [0, 0, 0, 1], 0.3)
    scene.add_object("mesh", mesh=(vertices, simplices))               # or a trimesh / meshio mesh

File formats: ``.npz`` archives with arrays ``vertices`` and ``simplices`` (any N, read by the
core without extra packages), and through meshio (``pip install "ndtrace[mesh]"``) ``.obj``,
``.ply``, ``.stl``, ``.off``, ``.vtk``, ``.vtu``, ``.msh`` and meshio's other formats: line
cells for N = 2, triangles (quads split in two) for N = 3, tetrahedra for N = 4. Points with
fewer than N coordinates get zeros for the missing ones (a tetrahedral mesh of a 3D solid lies
in the hyperplane x_3 = 0 of R^4).
"""

from __future__ import annotations

import contextlib
import errno
import io
import numbers
import os
import warnings

import numpy as np

from . import _ndtrace
from ._optional import need
from ._util import angle_degrees, check_memory, field_array
from .geometry import generalized_cross
from .thicken import thicken_points, thicken_surface

__all__ = ["convex_hull", "orient", "feature_edges", "read", "read_field", "from_object",
           "elevation_map", "slice", "thicken_surface", "thicken_points", "CELL_TYPES"]

#: The meshio cell types that hold the (N−1)-simplices of a dimension-N scene ("quad" cells are
#: split into two triangles).
CELL_TYPES: dict[int, tuple[str, ...]] = {2: ("line",), 3: ("triangle", "quad"), 4: ("tetra",)}

def _vertices(name: str, vertices, dim: int | None = None) -> np.ndarray:
    v = np.asarray(vertices)
    if v.dtype.kind not in "biuf":
        raise ValueError(f"{name}: expected real numbers, got dtype {v.dtype}")
    v = np.ascontiguousarray(v, dtype=np.float64)
    if v.ndim != 2 or not 2 <= v.shape[1] <= 8:
        raise ValueError(f"{name}: expected shape (V, N) with N in 2..8, got {v.shape}")
    if dim is not None and v.shape[1] != dim:
        raise ValueError(f"{name}: expected shape (V, {dim}) (dim = {dim}), got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ValueError(f"{name}: holds NaN or infinite values")
    return v


def _simplices(name: str, simplices, vertex_count: int, dim: int) -> np.ndarray:
    s = np.asarray(simplices)
    if s.size == 0:
        s = s.reshape(0, dim).astype(np.int64)
    if s.dtype.kind not in "iu":
        raise ValueError(f"{name}: expected integer vertex indices, got dtype {s.dtype}")
    if s.ndim != 2 or s.shape[1] != dim:
        raise ValueError(f"{name}: expected shape (S, {dim}), {dim} vertex indices per "
                         f"(N−1)-simplex, got {s.shape}")
    bad = np.argwhere((s < 0) | (s >= vertex_count))
    if len(bad):
        i, k = bad[0]
        raise ValueError(f"{name}[{i}][{k}]: vertex index {s[i, k]} out of range: there are "
                         f"{vertex_count} vertices")
    return np.ascontiguousarray(s, dtype=np.int64)


def _mesh(vertices, simplices, dim: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    v = _vertices("vertices", vertices, dim)
    return v, _simplices("simplices", simplices, len(v), v.shape[1])


def _affine_rank(p: np.ndarray, idx, tol: float) -> int:
    x = p[list(idx)]
    if len(x) < 2:
        return 0
    sv = np.linalg.svd(x[1:] - x[0], compute_uv=False)
    return int(np.sum(sv > tol))


def _facets(hull, scale: float) -> list[tuple[frozenset, int]]:
    """Qhull's triangulated facets merged back into the hull's facets: (vertex set, index of one
    of its simplices), joining neighbouring simplices whose hyperplanes agree."""
    count = len(hull.simplices)
    parent = list(range(count))

    def root(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    eq = hull.equations
    tol = np.r_[np.full(eq.shape[1] - 1, 1e-9), 1e-9 * scale]  # unit normals, then offsets
    for i in range(count):
        for j in hull.neighbors[i]:
            if j > i and np.all(np.abs(eq[i] - eq[j]) <= tol):
                parent[root(i)] = root(j)
    groups: dict[int, set] = {}
    for i in range(count):
        groups.setdefault(root(i), set()).update(int(k) for k in hull.simplices[i])
    return [(frozenset(v), r) for r, v in groups.items()]


def _pulling(face: frozenset, dim: int, facets: list[frozenset], p: np.ndarray, tol: float,
             memo: dict) -> list[tuple[int, ...]]:
    """The pulling triangulation of a face of the hull (its vertex set, affine dimension
    ``dim``): cone from its lowest vertex over the triangulations of its own facets not
    containing it. A face's facets are its intersections with the hull's facets that have
    dimension ``dim − 1``; memoized, so each face is triangulated once and neighbours agree."""
    if face in memo:
        return memo[face]
    if len(face) == dim + 1:
        out = [tuple(sorted(face))]
    else:
        v = min(face)
        subs = {face & f for f in facets if not face <= f}
        out = []
        for sub in subs:
            if v not in sub and len(sub) >= dim and _affine_rank(p, sub, tol) == dim - 1 and \
                    not any(sub < other for other in subs if _affine_rank(p, other, tol) == dim - 1):
                out += [(v,) + t for t in _pulling(sub, dim - 1, facets, p, tol, memo)]
    memo[face] = out
    return out


def convex_hull(points) -> tuple[np.ndarray, np.ndarray]:
    """The boundary of the convex hull of ``points`` (P, N), N = 2…8, as an outward-oriented
    mesh ``(vertices, simplices)``: ``vertices`` are the hull's vertices (a subset of the
    points, in their order) and every simplex's normal (eq. 6) points away from the hull.

    The hull's facets come from scipy's Qhull. Facets with more than N vertices (the cubes of
    the tesseract, the octahedra of the 24-cell, the dodecahedra of the 120-cell) are cut into
    simplices by the pulling triangulation (each face coned from its lowest-numbered vertex
    over its own faces), which agrees on the faces neighbouring facets share and has no
    zero-volume simplices, unlike Qhull's own; so the mesh is closed and consistently oriented.
    Needs scipy (``pip install "ndtrace[mesh]"``). Raises ValueError when the points do not
    span N dimensions.
    """
    p = _vertices("points", points)
    n = p.shape[1]
    if len(p) < n + 1:
        raise ValueError(f"points: a hull in R^{n} needs at least {n + 1} points, got {len(p)}")
    need("scipy", extra="mesh", what="ndtrace.mesh.convex_hull")
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(p)
    except QhullError as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else "Qhull failed"
        raise ValueError(f"points: no convex hull in R^{n} (do the points span {n} "
                         f"dimensions?): {first}") from None
    scale = float(np.abs(p).max()) or 1.0
    tol = 1e-9 * scale
    facets = _facets(hull, scale)
    sets = [f for f, _ in facets]
    memo: dict = {}
    rows, normals = [], []
    for face, r in facets:
        for t in _pulling(face, n - 1, sets, p, tol, memo):
            rows.append(t)
            normals.append(hull.equations[r, :n])
    s = np.array(rows, dtype=np.int64)
    cross = generalized_cross(p[s[:, 1:]] - p[s[:, :1]])
    inward = np.einsum("ij,ij->i", cross, np.array(normals)) < 0
    s[inward, 0], s[inward, 1] = s[inward, 1], s[inward, 0]
    used, inverse = np.unique(s, return_inverse=True)
    return p[used], inverse.reshape(s.shape).astype(np.int64)


def orient(vertices, simplices) -> tuple[np.ndarray, np.ndarray]:
    """The mesh with its simplices consistently oriented: ``(vertices, simplices)`` with some
    rows of ``simplices`` having their first two indices swapped.

    Each connected piece (simplices linked through shared ridges) is walked breadth-first from
    its first simplex, every neighbour taking the orientation that agrees with the simplex it
    was reached from; then a closed piece is turned outward (positive enclosed volume) and a
    piece with a boundary keeps the orientation most of its simplices had. Simplices with a
    repeated index are left as they are. Raises ValueError when a ridge belongs to more than
    two simplices or a piece is not orientable (a Möbius strip).
    """
    v, s = _mesh(vertices, simplices)
    flips = _ndtrace.orient_flips(v, s.astype(np.uint32))
    out = s.copy()
    out[flips, 0], out[flips, 1] = s[flips, 1], s[flips, 0]
    return v, out


def _points(name: str, points, dim: int) -> np.ndarray:
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2:
        raise ValueError(f"{name}: expected points of shape (V, d), got {p.shape}")
    if p.shape[1] < dim:
        p = np.pad(p, ((0, 0), (0, dim - p.shape[1])))
    elif p.shape[1] > dim:
        extra = p[:, dim:]
        if np.any(extra != 0):
            raise ValueError(f"{name}: the points have {p.shape[1]} coordinates, but the scene "
                             f"has dim = {dim} (and coordinates {dim}… are not all zero)")
        p = p[:, :dim]
    return p


def _cell_blocks(cells) -> list[tuple[str, np.ndarray]]:
    """meshio's cells (CellBlocks, (type, data) pairs or a {type: data} dict) as pairs."""
    if isinstance(cells, dict):
        return [(str(t), np.asarray(d)) for t, d in cells.items()]
    out = []
    for block in cells:
        if hasattr(block, "type") and hasattr(block, "data"):
            out.append((str(block.type), np.asarray(block.data)))
        else:
            t, d = block
            out.append((str(t), np.asarray(d)))
    return out


def _from_cells(points, cells, dim: int | None, what: str) -> tuple[np.ndarray, np.ndarray]:
    blocks = _cell_blocks(cells)
    types = [t for t, _ in blocks]
    if dim is None:
        dim = next((d for d in (4, 3, 2) if any(t in CELL_TYPES[d] for t in types)), None)
        if dim is None:
            raise ValueError(f"{what}: no line, triangle, quad or tetra cells (cells: "
                             f"{', '.join(types) or 'none'})")
    if dim not in CELL_TYPES:
        raise ValueError(f"{what}: mesh files hold lines, triangles or tetrahedra (N = 2, 3, 4); "
                         f"for dim = {dim} write an .npz with arrays vertices and simplices")
    parts = []
    for t, data in blocks:
        if t not in CELL_TYPES[dim]:
            continue
        data = np.asarray(data, dtype=np.int64)
        if t == "quad":  # [a, b, c, d] → [a, b, c], [a, c, d]: the same orientation
            data = np.concatenate([data[:, [0, 1, 2]], data[:, [0, 2, 3]]])
        parts.append(data.reshape(-1, dim))
    if not parts:
        raise ValueError(f"{what}: no {' or '.join(CELL_TYPES[dim])} cells for a dim = {dim} "
                         f"scene (cells: {', '.join(types) or 'none'})")
    vertices = _points(f"{what}: points", points, dim)
    return _mesh(vertices, np.concatenate(parts), dim)


def from_object(obj, dim: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices, simplices)`` from a mesh object: anything with ``.vertices`` and ``.faces``
    (a ``trimesh.Trimesh``: triangles, dim 3), anything with ``.points`` and ``.cells`` (a
    ``meshio.Mesh``: the cells of ``dim``, see :data:`CELL_TYPES`), or a pair ``(vertices,
    simplices)``. ``dim`` (the scene's) is checked, or inferred when None."""
    if hasattr(obj, "vertices") and hasattr(obj, "faces"):
        return _from_cells(np.asarray(obj.vertices), [("triangle", np.asarray(obj.faces))], dim,
                           f"mesh ({type(obj).__name__})")
    if hasattr(obj, "points") and hasattr(obj, "cells"):
        return _from_cells(obj.points, obj.cells, dim, f"mesh ({type(obj).__name__})")
    if isinstance(obj, (tuple, list)) and len(obj) == 2:
        return _mesh(obj[0], obj[1], dim)
    raise TypeError(f"mesh: expected an object with .vertices and .faces (trimesh), .points "
                    f"and .cells (meshio), or a pair (vertices, simplices), got "
                    f"{type(obj).__name__}")


def _npz_array(path: str, name: str | None) -> tuple[np.ndarray, str]:
    """An array of an ``.npy`` or ``.npz`` file read by the core's reader (the one the scene
    loaders use): header first, the memory its shape needs checked by the guard before the data
    is read or inflated, an archive member's CRC-32 checked; ``(float64 array, stored dtype)``.
    Every problem is a ValueError naming the file."""
    return _ndtrace.read_array(path, name)


#: How many bytes of a PLY file may precede its ``end_header`` line.
PLY_HEADER_LIMIT = 1 << 20


def _precheck(path: str, ext: str) -> None:
    """Refuses files on which a meshio reader would loop forever (it reads lines until it
    finds what it looks for, and at the end of the file gets empty lines for ever): a PLY
    file's header must end with ``end_header``, an OFF file must have its counts line after
    ``OFF``, a Nastran file its ``ENDDATA``, and every ``Begin …`` block of an MDPA file its
    ``End …``. A ValueError names the file and what is missing."""
    if ext == ".ply":
        with open(path, "rb") as f:
            head = f.read(PLY_HEADER_LIMIT)
        if not any(line.strip() == b"end_header" for line in head.splitlines()):
            raise ValueError(f"{path}: not a PLY file meshio can read: no end_header line in its "
                             f"header (the first {PLY_HEADER_LIMIT} bytes)")
    elif ext == ".off":
        with open(path, "rb") as f:
            f.readline()  # "OFF" (meshio checks it)
            for line in f:
                line = line.strip()
                if line and not line.startswith(b"#"):
                    return
        raise ValueError(f"{path}: not an OFF file meshio can read: no line of counts "
                         "(vertices, faces, edges) after OFF")
    elif ext in (".nas", ".bdf", ".fem"):
        with open(path, "rb") as f:
            if not any(line.startswith(b"ENDDATA") for line in f):
                raise ValueError(f"{path}: not a Nastran file meshio can read: no ENDDATA line")
    elif ext == ".mdpa":
        with open(path, "rb") as f:
            open_blocks: list[bytes] = []
            for line in f:
                words = line.split()
                if len(words) >= 2 and words[0] == b"Begin":
                    open_blocks.append(words[1])
                elif len(words) >= 2 and words[0] == b"End" and open_blocks:
                    open_blocks.pop()
            if open_blocks:
                raise ValueError(f"{path}: not an MDPA file meshio can read: its Begin "
                                 f"{open_blocks[-1].decode(errors='replace')} block has no End")


def _meshio_read(meshio, path: str):
    """``meshio.read(path)`` as a well-behaved reader: whatever goes wrong is a ValueError naming
    the file, with what meshio printed or raised (meshio prints its readers' errors and then
    calls ``sys.exit(1)``, a SystemExit that ``except Exception`` does not catch); Ctrl-C
    (KeyboardInterrupt) still stops it."""
    printed = io.StringIO()
    try:
        with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(printed):
            return meshio.read(path)
    except (Exception, SystemExit, RecursionError) as e:  # noqa: BLE001 - meshio raises many kinds
        said = [line.strip() for line in printed.getvalue().splitlines() if line.strip()]
        reason = str(e).strip() if not isinstance(e, SystemExit) else ""
        if isinstance(e, MemoryError):
            reason = "it asks for more memory than there is"
        elif isinstance(e, RecursionError):
            reason = "it is nested too deeply"
        reason = (reason or "; ".join(said[:2]) or type(e).__name__).splitlines()[0]
        raise ValueError(f"{path}: meshio cannot read it: {reason}") from None


def read(path: str | os.PathLike, dim: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Reads a mesh file into ``(vertices, simplices)``: an ``.npz`` with arrays ``vertices``
    (V, N) and ``simplices`` (S, N), or any file meshio reads (see the module docs), for a
    scene of dimension ``dim`` (None: from the file). Raises FileNotFoundError for a missing
    file, ImportError naming the ``mesh`` extra when meshio is needed and missing, and
    ValueError naming the file for a file that holds no mesh of that dimension or cannot be
    read (broken, hostile, or too big for the memory guard)."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(errno.ENOENT, "no such mesh file", path)
    ext = os.path.splitext(path)[1].lower()
    if ext == ".npz":
        vertices, _ = _npz_array(path, "vertices")
        simplices, dtype = _npz_array(path, "simplices")
        if np.dtype(dtype).kind not in "iu":
            raise ValueError(f"{path}: simplices: expected integer vertex indices, got dtype "
                             f"{np.dtype(dtype)}")
        if simplices.size and not np.all(np.abs(simplices) < 2.0**53):
            raise ValueError(f"{path}: simplices: vertex indices out of range")
        return _mesh(vertices, simplices.astype(np.int64), dim)
    meshio = need("meshio", extra="mesh", what=f"reading {ext or 'extensionless'} mesh files")
    _precheck(path, ext)
    m = _meshio_read(meshio, path)
    try:
        return _from_cells(m.points, m.cells, dim, path)
    except (TypeError, OverflowError, MemoryError) as e:
        raise ValueError(f"{path}: meshio read a mesh ndtrace cannot use: {e}") from None


def read_field(path: str | os.PathLike, key: str | None = None) -> np.ndarray:
    """Reads a 3D scalar field, indexed ``[x, y, z]``, as a float64 array: ``.npy``, ``.npz``
    (the array ``key``, or its only array) or NIfTI ``.nii`` / ``.nii.gz`` through nibabel
    (``pip install "ndtrace[nifti]"``; the voxel array as stored, its affine ignored). Raises
    FileNotFoundError for a missing file, ImportError naming the extra, ValueError naming the
    file otherwise (including a field too big for the memory guard)."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise FileNotFoundError(errno.ENOENT, "no such field file", path)
    lower = path.lower()
    if lower.endswith((".nii", ".nii.gz")):
        nibabel = need("nibabel", extra="nifti", what="reading NIfTI fields")
        try:
            img = nibabel.load(path)
            shape = tuple(int(k) for k in img.shape)
            check_memory(float(np.prod(shape, dtype=np.float64)) * 8.0 * 2,
                         f"{path}: a field of shape {shape}")
            data = np.asanyarray(img.dataobj)
        except ValueError as e:
            if str(e).startswith(path + ": "):
                raise
            raise ValueError(f"{path}: nibabel cannot read it: {str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__}") from None
        except (Exception, SystemExit) as e:  # noqa: BLE001 - nibabel raises many kinds; say which file
            reason = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
            raise ValueError(f"{path}: nibabel cannot read it: {reason}") from None
        if data.ndim == 4 and data.shape[3] == 1:
            data = data[..., 0]
        return field_array(path, data)
    if lower.endswith(".npy"):
        return field_array(path, _npz_array(path, None)[0])
    if lower.endswith(".npz"):
        return field_array(path, _npz_array(path, key)[0])
    raise ValueError(f"{path}: not a field file: expected .npy, .npz, .nii or .nii.gz")


def elevation_map(field, extent=None, height: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """The 4D elevation map of a 3D scalar field (course notes, Part II(B)): the graph
    ``w = height·f(x, y, z)`` of ``field`` (a 3D array indexed ``[x, y, z]``, one value per
    grid point) over the box ``extent = ((x0, x1), (y0, y1), (z0, z1))`` — by default the
    longest side spans [−1, 1], centred, with cubic voxels.

    Returns ``(vertices (V, 4) float64, simplices (S, 4) int64)``: one vertex per grid point,
    ``w`` exactly ``height·field``, and six tetrahedra per grid cube (Kuhn's split, conforming
    across cubes, so their projections to xyz tile the box with no gaps or overlaps), oriented
    so that the normal's w component is positive. Cubes touching a NaN value (masked data) are
    left out as holes, with a warning that counts them. Without holes vertex ``i`` is grid point
    ``np.unravel_index(i, field.shape)``; with holes, the grid points no kept cube uses are
    dropped and the others keep that order."""
    f = field_array("field", field)
    if isinstance(height, bool) or not isinstance(height, numbers.Real):
        raise ValueError(f"height: expected a number, got {height!r}")
    box = None
    if extent is not None:
        try:
            box = np.asarray(extent, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError(f"extent: expected ((x0, x1), (y0, y1), (z0, z1)), got {extent!r}") from None
        if box.shape != (3, 2):
            raise ValueError(f"extent: expected ((x0, x1), (y0, y1), (z0, z1)), shape (3, 2), "
                             f"got shape {box.shape}")
        for axis, (lo, hi) in zip("xyz", box):
            if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
                raise ValueError(f"extent: the {axis} range [{lo:g}, {hi:g}] must be finite with "
                                 f"{axis}1 > {axis}0")
        box = [[float(a), float(b)] for a, b in box]
    if not (np.isfinite(height) and height != 0):
        raise ValueError(f"height: must be a finite non-zero number, got {height!r}")
    vertices, simplices, holes = _ndtrace.elevation_map(f, box, float(height))
    if holes:
        warnings.warn(f"field: {holes} grid cube{'s' if holes != 1 else ''} touching NaN "
                      f"values left out as holes", stacklevel=2)
    return vertices, simplices


def feature_edges(vertices, simplices, angle: float = 20.0) -> np.ndarray:
    """The 1-dimensional edges of a mesh's polytope structure: an int64 array ``(E, 2)``, each
    row a vertex pair ``i < j``, rows sorted.

    ``vertices`` is ``(V, N)`` and ``simplices`` ``(S, N)`` (each row the N vertex indices of
    an (N−1)-simplex), N = 2…8. A ridge (an (N−2)-face) is a *crease* when two simplices
    sharing it have unit normals more than ``angle`` degrees apart — comparing lines, not signs,
    so the orientation of the input does not matter — or when only one simplex has it; an edge
    is a feature edge when the creases through it do not all lie in one 2-plane (for N = 3 the
    creases are the edges; for N ≥ 5 the same rule is applied down the face dimensions). A
    tesseract gives its 32 edges, the 16-cell 24, a finely tessellated 3-sphere none.

    Vertices with identical coordinates are welded (the smallest index is returned), and
    zero-volume simplices — Qhull's triangulated facets contain some — do not break a flat cell
    or a crease. Runs in parallel in the core; a million simplices take seconds.
    """
    v = np.asarray(vertices)
    s = np.asarray(simplices)
    if v.ndim != 2 or not (_ndtrace.MIN_DIM <= v.shape[1] <= _ndtrace.MAX_DIM):
        raise ValueError(f"vertices: expected shape (V, N) with N in 2…8, got {v.shape}")
    n = v.shape[1]
    if not (np.issubdtype(v.dtype, np.floating) or np.issubdtype(v.dtype, np.integer)):
        raise ValueError(f"vertices: expected real numbers, got dtype {v.dtype}")
    if s.ndim != 2 or s.shape[1] != n:
        raise ValueError(f"simplices: expected shape (S, {n}) (N vertex indices per simplex), "
                         f"got {s.shape}")
    if s.size and not np.issubdtype(s.dtype, np.integer):
        raise ValueError(f"simplices: expected integer indices, got dtype {s.dtype}")
    if s.size and (s.min() < 0 or s.max() >= len(v)):
        bad = int(np.argmax((s < 0).any(1) | (s >= len(v)).any(1)))
        raise ValueError(f"simplices: row {bad} names a vertex outside 0…{len(v) - 1}: "
                         f"{s[bad].tolist()}")
    out = _ndtrace.feature_edges(
        n,
        np.ascontiguousarray(v, dtype=np.float64).reshape(-1),
        np.ascontiguousarray(s, dtype=np.uint32).reshape(-1),
        angle_degrees(angle),
    )
    return np.asarray(out, dtype=np.int64).reshape(-1, 2)


def _normal(normal, dim: int) -> np.ndarray:
    n = np.asarray(normal)
    if n.dtype.kind not in "biuf":
        raise ValueError(f"normal: expected {dim} real numbers, got dtype {n.dtype}")
    n = n.astype(np.float64)
    if n.shape != (dim,):
        raise ValueError(f"normal: expected shape ({dim},) (dim = {dim}), got {n.shape}")
    if not np.all(np.isfinite(n)) or not np.any(n != 0):
        raise ValueError(f"normal: must be a finite non-zero vector, got {n.tolist()}")
    return n


def _offset(offset) -> float:
    if isinstance(offset, bool) or not isinstance(offset, numbers.Real):
        raise ValueError(f"offset: expected a real number, got {offset!r}")
    value = float(offset)
    if not np.isfinite(value):
        raise ValueError(f"offset: must be finite, got {offset}")
    return value


def slice_with_values(vertices, simplices, normal, offset, values=None):
    """:func:`slice`, with per-vertex ``values`` (V,) interpolated at the new vertices and the
    index of the simplex each piece was cut from: ``(vertices, simplices, basis, origin,
    values (V',) or None, parents (S',))``."""
    v, s = _mesh(vertices, simplices)
    if v.shape[1] < 3:
        raise ValueError(f"vertices: slices need N ≥ 3 (a mesh of (N−1)-simplices in R^N), "
                         f"got shape {v.shape}")
    n = _normal(normal, v.shape[1])
    c = _offset(offset)
    vals = None
    if values is not None:
        vals = np.ascontiguousarray(values, dtype=np.float64)
        if vals.shape != (len(v),):
            raise ValueError(f"values: expected shape ({len(v)},), one per vertex, got "
                             f"{vals.shape}")
    coords, pieces, basis, origin, out_values, parents = _ndtrace.slice_mesh(
        v, s.astype(np.uint32), n.tolist(), c, vals)
    return coords, pieces, basis, origin, (out_values if vals is not None else None), parents


def slice(vertices, simplices, normal, offset) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                        np.ndarray]:
    """The intersection of the mesh with the hyperplane ``n̂·x = offset``: ``(vertices (V', N−1),
    simplices (S', N−1), basis (N−1, N), origin (N,))``, an (N−2)-simplex mesh in the
    hyperplane's own orthonormal coordinates, ``x = origin + coords @ basis``.

    ``normal`` (N numbers) need not be unit length; it is normalized, so ``offset`` is the
    hyperplane's signed distance from the origin and ``origin = offset·n̂``. ``basis`` holds the
    coordinate axes but the one most aligned with n̂, in order, made orthonormal to n̂ (for an
    axis normal the other axes: ``normal = [0, 0, 0, 1]`` gives x, y, z).

    Each simplex is cut with the course's clipping formulas (the side of each vertex from
    eq. 1, the crossing of each edge at ``t = n̂·(x_a − x_0) / n̂·(x_a − x_b)``, eq. 10): a
    tetrahedron gives a triangle or a quadrilateral (two triangles), an (N−1)-simplex with a
    vertices above and b below the product Δ^{a−1}×Δ^{b−1}, cut by its staircase triangulation
    with the vertices ordered by index, so that shared faces are cut alike and a closed mesh
    gives a closed slice. Each piece is oriented along its simplex's normal projected into the
    hyperplane: a closed, outward mesh gives a closed slice oriented outward in the slice.

    Degenerate cuts: a vertex on the hyperplane counts as above it (the slice is the limit of
    the slices by ``n̂·x = offset − ε``), and is one output vertex however many edges reach it;
    pieces that collapse are dropped, and pieces with the same vertices and opposite
    orientations cancel. So a cut along a facet gives that facet's outline, a cut that only
    touches the mesh from outside gives nothing, and no piece is duplicated or of zero area.

    Raises ValueError naming the argument for a zero, non-finite or wrongly sized ``normal``,
    a non-finite ``offset``, and the checks of :func:`orient` on the mesh (N ≥ 3).
    """
    coords, pieces, basis, origin, _, _ = slice_with_values(vertices, simplices, normal, offset)
    return coords, pieces, basis, origin
