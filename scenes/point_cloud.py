"""A point cloud in 4D: 3,000 random points on the Clifford torus (cos a, sin a, cos b, sin b)/√2
of the unit 3-sphere, each a tiny 3-sphere (course notes Part II(B): "even points can be made
structurally visible in 4D by making them tiny 3-spheres"; ``ndtrace.mesh.thicken_points``,
one mesh and one BVH per colour). Seen as in ``clifford_torus.py``, the cloud fills out the same
doughnut; colour = the quarter of the angle a the point has, so the bands run around the
doughnut like those of the tubed torus.

Render it with:  ndtrace scenes/point_cloud.py -o point_cloud.png
"""

import numpy as np

import ndtrace

COUNT = 3000
COLORS = [[0.95, 0.45, 0.25], [0.95, 0.8, 0.3], [0.35, 0.8, 0.45], [0.3, 0.55, 0.95]]


def scene() -> ndtrace.Scene:
    rng = np.random.default_rng(3)
    a, b = rng.uniform(0, 2 * np.pi, (2, COUNT))
    p = np.stack([np.cos(a), np.sin(a), np.cos(b), np.sin(b)], 1) / np.sqrt(2)
    s = (
        ndtrace.Scene(4, background=[0.03, 0.03, 0.05], ambient=[0.2, 0.2, 0.22])
        .set_camera([0.4, 0.9, 1.6, 2.6], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=42,
                    resolution=80)
        .add_light("point", position=[2.0, 3.0, 2.0, 2.5])
    )
    quarter = (a // (np.pi / 2)).astype(int)
    for q, color in enumerate(COLORS):
        v, t = ndtrace.mesh.thicken_points(p[quarter == q], radius=0.035, subdivisions=3)
        s.add_object("mesh", vertices=v, simplices=t, label=f"a {90 * q}–{90 * (q + 1)}°",
                     material={"color": color, "specular": 0.4, "shininess": 30, "smooth": True})
    return s.set_render(samples=4).set_composite(mode="first_hit")
