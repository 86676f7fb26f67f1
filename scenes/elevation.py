"""A Python scene script: a 3D scalar field seen as a 4D elevation map (course notes, Part
II(B): "any volume-renderable 3D scalar field ... is indistinguishable mathematically from a 4D
elevation map"). The field is a sum of three Gaussians of known centres, widths and heights,

    f(x, y, z) = Σ_k a_k · exp(−|x − c_k|² / (2 σ_k²)),

sampled on a 48³ grid over [−1, 1]³ and drawn as the hypersurface w = 0.6·f of R^4, lit by a
light from a 4D direction so that its three bumps read by shading, coloured by f (coolwarm,
keyed by the colour bar) with isosurface markings at f = 0.25, 0.5 and 0.75 (the course's
"isosurface markings", marked on the colour bar). The camera is the course's: orthographic,
looking down the w axis, so the retina's x, y, z are the field's and the terrain's heights
show only through its 4D shading. The picture is the retina (a 3D image of the terrain) with
the octant toward the viewer cut away, beside three orthogonal sections through it, titled by
the plane each lies in (x = 0 …).

Render it with:  ndtrace scenes/elevation.py -o elevation.png
"""

import numpy as np

import ndtrace

#: (centre, σ, amplitude) of each Gaussian.
BUMPS = [((0.35, 0.2, -0.1), 0.30, 1.0), ((-0.45, -0.3, 0.2), 0.22, 0.7), ((0.0, 0.5, 0.5), 0.18, 0.5)]


def field(n: int = 48) -> np.ndarray:
    """The field on an n³ grid over [−1, 1]³, indexed [x, y, z]."""
    axis = np.linspace(-1.0, 1.0, n)
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    f = np.zeros_like(x)
    for (cx, cy, cz), sigma, a in BUMPS:
        f += a * np.exp(-((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / (2 * sigma**2))
    return f


def scene() -> ndtrace.Scene:
    return (
        ndtrace.Scene(4, ambient=[0.2, 0.2, 0.22])
        .set_camera([0, 0, 0, 4], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]],
                    projection="orthographic", extent=1.05, resolution=64)
        .add_light("directional", direction=[0.9, 0.7, 0.3, 0.45])
        .add_object("elevation", field=field(), height=0.6, smooth=True, label="f(x, y, z)",
                    material={"colormap": "coolwarm", "range": [-1.0, 1.0], "specular": 0.2,
                              "isolines": {"values": [0.25, 0.5, 0.75], "width": 0.07,
                                           "color": [0.05, 0.05, 0.2]}})
        # The retina is a solid block (every ray meets the terrain): show it as an opaque
        # volume with the octant toward the viewer cut away, beside three orthogonal sections,
        # each a relief map of the terrain lit in 4D.
        .set_composite(mode="volume", layout="sections",
                       cutaway={"shape": "box", "min": [0, 0, -1.5], "max": [1.5, 1.5, 0]},
                       title="A 3D field f as the 4D elevation map w = 0.6 f")
    )
