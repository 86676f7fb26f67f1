"""The Riemann surface of w = √z: the graph {(z, w) : w² = z} ⊂ C² = R^4, a smooth disk
parametrised by ζ as (z, w) = (ζ², ζ) (``ndtrace.surfaces.riemann_root``). Its projection to
the z plane covers every z twice and crosses itself along the negative real axis (the "branch
cut" of a 3D picture); in 4D the two sheets are apart (w and −w), so the tubed surface
(``ndtrace.mesh.thicken_surface``) has no self-intersection. The camera looks along a direction
mixing Im w into the retina; colour = the sheet (Re w > 0 warm, < 0 cool).

Render it with:  ndtrace scenes/riemann_sqrt.py -o riemann_sqrt.png
"""

import numpy as np

import ndtrace
from ndtrace import surfaces


def scene(hair: bool = False) -> ndtrace.Scene:
    """The thickened surface; with ``hair``, the surface itself (shape \"surface\", bear hair)."""
    v, t = surfaces.riemann_root(2, radius=1.0, rings=14, sectors=40)
    s = (
        ndtrace.Scene(4, background=[0.03, 0.03, 0.05], ambient=[0.15, 0.15, 0.18])
        .set_camera([0.6, -1.6, 1.8, 2.4], look_at=[0, 0, 0, 0], up=[[0, 0, 1, 0], [0, 1, 0, 0]], fov=42,
                    resolution=80)
        .add_light("point", position=[2.0, -3.0, 3.0, 2.0])
        .add_light("directional", direction=[-0.5, 0.2, 0.3, 1.0], color=[0.3, 0.3, 0.35])
    )
    sheet = v[t, 2].mean(axis=1) > 0
    for keep, color, label in ((sheet, [0.95, 0.55, 0.2], "sheet Re w > 0"),
                               (~sheet, [0.3, 0.55, 0.95], "sheet Re w < 0")):
        if hair:
            s.add_object("surface", vertices=v, triangles=t[keep], label=label,
                         material={"color": color, "specular": 0.5, "shininess": 40, "smooth": True})
            continue
        tv, ts = ndtrace.mesh.thicken_surface(v, t[keep], radius=0.02, segments=10)
        s.add_object("mesh", vertices=tv, simplices=ts, label=label,
                     material={"color": color, "specular": 0.5, "shininess": 40})
    return s.set_render(samples=4).set_composite(mode="first_hit")
