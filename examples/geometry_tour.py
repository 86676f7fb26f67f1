"""A short tour of ndtrace.geometry: the course notes' formulas, in four dimensions.

Run:  python examples/geometry_tour.py
"""

import math

import numpy as np

import ndtrace
from ndtrace import geometry as g

np.set_printoptions(precision=4, suppress=True)
print(f"ndtrace {ndtrace.__version__}: geometry in R^4\n")

# A tetrahedron (a 3-simplex) living in R^4: one cell of a 4D boundary mesh.
tet = np.array([[0, 0, 0, 0], [2, 0, 0, 0], [0, 2, 0, 0], [0, 0, 2, 1]], dtype=float)
edges = tet[1:] - tet[0]
normal = g.generalized_cross(edges)
print("cell vertices:\n", tet)
print("generalized cross product of its edges (eq. 6):", normal)
print("  orthogonal to every edge:", edges @ normal)
print("  |N|^2 =", normal @ normal, "= Gram determinant", np.linalg.det(edges @ edges.T))
print("  3-volume of the cell (eq. 5):", g.gram_volume(tet), "=", math.sqrt(normal @ normal) / 6)

n_hat, c = g.hyperplane(tet)
print("\nits hyperplane n.x = c (eq. 1): n =", n_hat, " c =", c)
eye = np.array([0.5, 0.5, 0.5, 3.0])
h, foot = g.point_hyperplane_distance(eye, tet)
print("distance of", eye, "from it (eq. 11):", h, " foot point:", foot)
print("side of the eye:", g.side(eye, tet), "(+1: the normal points toward it)")

# A 4-simplex: the cell plus the eye point. Its signed volume (eqs. 2-3).
print("\nsigned 4-volume of (cell, eye):", g.signed_volume(np.vstack([tet, eye])))

# Cast a ray from the eye toward the cell's centroid and find where it hits (section "Ray Tracing").
centroid = tet.mean(axis=0)
t = g.ray_hyperplane(eye, centroid - eye, tet)
hit = eye + t * (centroid - eye)
bary = g.barycentric(hit, tet)
print("\nray from the eye to the centroid hits at t =", t, "point", hit)
print("barycentric coordinates of the hit:", bary, " inside:", bool(np.all(bary >= 0)))

# Normals are pseudotensors: a reflection flips them relative to R.N.
reflect = np.diag([1.0, 1.0, 1.0, -1.0])
print("\nnormal after reflecting w -> -w:", g.transform_normal(reflect, normal),
      " (R.N would be", reflect @ normal, ")")
