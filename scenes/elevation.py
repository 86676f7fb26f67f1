"""A Python scene script: the 3D scalar field w = 0.8·exp(−3 r²) on [−1, 1]³ as a 4D elevation
map (course notes: "3D scalar fields as 4D elevation maps"), tessellated into tetrahedra.

Render it with:  ndtrace scenes/elevation.py -o elevation.png
"""

import itertools

import numpy as np

import ndtrace


def elevation_mesh(n: int = 8):
    """Vertices (x, y, z, f(x, y, z)) on an n³ grid, each cube split into 6 tetrahedra."""
    axis = np.linspace(-1.0, 1.0, n + 1)
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    w = 0.8 * np.exp(-3.0 * (x**2 + y**2 + z**2))
    vertices = np.stack([x, y, z, w], axis=-1).reshape(-1, 4)
    index = np.arange((n + 1) ** 3).reshape(n + 1, n + 1, n + 1)
    simplices = []
    for i, j, k in itertools.product(range(n), repeat=3):
        corner = np.array([i, j, k])
        for perm in itertools.permutations(range(3)):  # Kuhn triangulation of each cube
            p = corner.copy()
            tet = [index[tuple(p)]]
            for axis_ in perm:
                p[axis_] += 1
                tet.append(index[tuple(p)])
            simplices.append(tet)
    return vertices, np.array(simplices)


def scene() -> ndtrace.Scene:
    vertices, simplices = elevation_mesh()
    return (
        ndtrace.Scene(4, ambient=[0.15, 0.15, 0.18])
        .set_camera([0.4, 0.6, 0.9, 3.5], look_at=[0, 0, 0, 0.3],
                    up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=55, resolution=64)
        .add_light("directional", direction=[0.2, 0.5, 0.3, 1.0])
        .add_object("mesh", vertices=vertices, simplices=simplices,
                    material={"color": [0.95, 0.5, 0.35], "specular": 0.2})
    )
