"""Meshes of (N−1)-simplices in R^N: their polytope structure (``feature_edges``)."""

from .edges import feature_edges

__all__ = ["feature_edges"]
