"""The Clifford torus (cos u, sin u, cos v, sin v)/√2 — the flat torus that splits the 3-sphere
into two solid tori — made visible by "tubing" (course notes Part II(B)): a small circle in the
normal plane at every point (``ndtrace.mesh.thicken_surface``). Seen from a 4D camera the
torus projects to a doughnut in the 3D retina; the stripes along u and v (two colours,
alternating bands of the u angle) show the two circle families, and the thin 3-manifold casts
light like a shiny surface.

Render it with:  ndtrace scenes/clifford_torus.py -o clifford_torus.png
"""

import numpy as np

import ndtrace
from ndtrace import surfaces

SAMPLES = 48
BANDS = 8  # colour bands along u


def scene(hair: bool = False) -> ndtrace.Scene:
    """The thickened surface; with ``hair``, the surface itself (shape \"surface\", bear hair)."""
    v, t = surfaces.clifford_torus(SAMPLES)
    s = (
        ndtrace.Scene(4, background=[0.03, 0.03, 0.05], ambient=[0.15, 0.15, 0.18])
        .set_camera([0.4, 0.9, 1.6, 2.6], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=42,
                    resolution=80)
        .add_light("point", position=[2.0, 3.0, 2.0, 2.5])
        .add_light("directional", direction=[-0.5, 0.2, 0.3, 1.0], color=[0.3, 0.3, 0.35])
    )
    u_band = (np.arange(len(t)) % (SAMPLES * SAMPLES) // SAMPLES * BANDS // SAMPLES) % 2 == 0
    for keep, color, label in ((u_band, [0.95, 0.6, 0.2], "u in eighths 1, 3, 5, 7"),
                               (~u_band, [0.25, 0.5, 0.95], "u in eighths 2, 4, 6, 8")):
        if hair:
            s.add_object("surface", vertices=v, triangles=t[keep], label=label,
                         material={"color": color, "specular": 0.5, "shininess": 40, "smooth": True})
            continue
        tv, ts = ndtrace.mesh.thicken_surface(v, t[keep], radius=0.035, segments=12)
        s.add_object("mesh", vertices=tv, simplices=ts, label=label,
                     material={"color": color, "specular": 0.5, "shininess": 40})
    return s.set_render(samples=4).set_composite(mode="first_hit")
