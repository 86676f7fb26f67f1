"""The exact N-D visibility of feature edges (``ndtrace.mesh.feature_edges``):
``ndtrace.visible_edges`` and ``ndtrace.edge_segments``.

The tesseract's boundary is 48 tetrahedra, but its polytope structure is 8 cubes, 24 squares
and 32 edges; ``feature_edges`` recovers those edges from the simplices alone (creases between
simplices whose normals differ by more than ``angle``, then down the face dimensions), and
``visible_edges`` splits them where the N-D camera's view of them is blocked by any simplex of
the scene (hidden-line removal in N dimensions).
"""

from __future__ import annotations

import numpy as np

from ._util import angle_degrees
from .scene import Scene

__all__ = ["visible_edges", "edge_segments"]


def edge_segments(scene: Scene, angle: float = 20.0) -> dict[str, np.ndarray]:
    """Every object's feature edges split by what the N-D camera sees: a dict with

    * ``visible`` (K, 2, N) float64 — world-space endpoints of the visible pieces;
    * ``hidden`` (M, 2, N) float64 — the pieces hidden in N-D or outside the field of view;
    * ``visible_object``, ``hidden_object`` (K,), (M,) int32 — the object of each piece.

    See :func:`visible_edges` for how visibility is decided.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected an ndtrace.Scene, got {type(scene).__name__}")
    out = scene.compiled().edge_segments(angle_degrees(angle))
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
