"""Feature edges of meshes and their exact N-D visibility: ``ndtrace.mesh.feature_edges``,
``ndtrace.visible_edges`` and ``ndtrace.edge_segments``.

The tesseract's boundary is 48 tetrahedra, but its polytope structure is 8 cubes, 24 squares
and 32 edges; ``feature_edges`` recovers those edges from the simplices alone (creases between
simplices whose normals differ by more than ``angle``, then down the face dimensions), and
``visible_edges`` splits them where the N-D camera's view of them is blocked by any simplex of
the scene (hidden-line removal in N dimensions).
"""

from __future__ import annotations

import numbers

import numpy as np

from . import _ndtrace
from .scene import Scene

__all__ = ["feature_edges", "visible_edges", "edge_segments"]


def _angle(angle) -> float:
    if isinstance(angle, bool) or not isinstance(angle, numbers.Real):
        raise ValueError(f"angle: expected a number of degrees, got {angle!r}")
    return float(angle)


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
        _angle(angle),
    )
    return np.asarray(out, dtype=np.int64).reshape(-1, 2)


def edge_segments(scene: Scene, angle: float = 20.0) -> dict[str, np.ndarray]:
    """Every object's feature edges split by what the N-D camera sees: a dict with

    * ``visible`` (K, 2, N) float64 — world-space endpoints of the visible pieces;
    * ``hidden`` (M, 2, N) float64 — the pieces hidden in N-D or outside the field of view;
    * ``visible_object``, ``hidden_object`` (K,), (M,) int32 — the object of each piece.

    See :func:`visible_edges` for how visibility is decided.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected an ndtrace.Scene, got {type(scene).__name__}")
    out = scene.compiled().edge_segments(_angle(angle))
    n = scene.dim
    return {
        "visible": np.asarray(out["visible"]).reshape(-1, 2, n),
        "hidden": np.asarray(out["hidden"]).reshape(-1, 2, n),
        "visible_object": np.asarray(out["visible_object"], dtype=np.int32),
        "hidden_object": np.asarray(out["hidden_object"], dtype=np.int32),
    }


def visible_edges(scene: Scene, angle: float = 20.0) -> np.ndarray:
    """World-space endpoints ``(K, 2, N)`` (float64) of the parts of every object's feature
    edges (:func:`ndtrace.mesh.feature_edges` with ``angle``) that the N-D camera sees: within
    its field of view and not occluded in N-D by any simplex of the scene (an edge is not
    occluded by the simplices it lies on).

    Exact up to a tolerance: each edge's visible part is split exactly at its occluders'
    boundaries (each simplex meets the edge's visibility 2-plane in a segment, found from the
    course's hyperplane and barycentric equations); occluders are found with the BVH by rays
    toward points of the edge spaced an eighth of a retina cell apart, so an occluder narrower
    than that in projection can be missed; pieces within 1e-6 (relative) of the edge along the
    eye's ray count as on it. Back-face-culled simplices (``render.cull_backfaces``) do not
    occlude, as in the traced retina.
    """
    return edge_segments(scene, angle)["visible"]
