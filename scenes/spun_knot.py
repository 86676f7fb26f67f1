"""Artin's spun trefoil: a knotted 2-sphere in R^4 (course notes Part II(B), "4D knotted
surfaces"). A trefoil arc in the half-space y ≥ y0 of R^3, its two ends on the plane y = y0, is
spun about that plane through the fourth dimension; the swept sphere is knotted in R^4 as the
arc is in R^3. It is tubed with small circles (``ndtrace.mesh.thicken_surface``) and coloured by
the spin angle θ (warm near θ = 0, cool near θ = π), so the 3D projection's self-crossings —
where the 4D sphere passes behind itself — show as colour changes, not as intersections. The
camera looks along the knot's thin axis, so the 3D picture is the knot diagram's arc spun
about an axis (a surface of revolution); the near half of the retina is cut away
(``composite.cutaway``) so the nested shells the crossings make show inside.

Render it with:  ndtrace scenes/spun_knot.py -o spun_knot.png
"""

import numpy as np

import ndtrace
from ndtrace import surfaces

SAMPLES, SECTORS = 120, 36


def scene(hair: bool = False) -> ndtrace.Scene:
    """The thickened surface; with ``hair``, the surface itself (shape \"surface\", bear hair)."""
    v, t = surfaces.spun_knot(SAMPLES, SECTORS)
    theta = np.arctan2(v[:, 3], v[:, 2])
    s = (
        ndtrace.Scene(4, background=[0.03, 0.03, 0.05], ambient=[0.15, 0.15, 0.18])
        .set_camera([0.6, 7.0, 1.8, 1.2], look_at=[0, 0, 0, 0], up=[[0, 0, 1, 0], [0, 0, 0, 1]], fov=40,
                    resolution=96)
        .add_light("point", position=[2.0, 5.0, 3.0, 2.0])
        .add_light("directional", direction=[-0.5, 0.2, 0.3, 1.0], color=[0.3, 0.3, 0.35])
    )
    near = np.abs(theta[t]).mean(axis=1) < np.pi / 2  # the half of the sphere with cos θ > 0
    for keep, color, label in ((near, [0.95, 0.55, 0.2], "spin angle θ near 0"),
                               (~near, [0.3, 0.55, 0.95], "θ near π")):
        if hair:
            s.add_object("surface", vertices=v, triangles=t[keep], label=label,
                         material={"color": color, "specular": 0.5, "shininess": 40, "smooth": True})
            continue
        tv, ts = ndtrace.mesh.thicken_surface(v, t[keep], radius=0.035, segments=10)
        s.add_object("mesh", vertices=tv, simplices=ts, label=label,
                     material={"color": color, "specular": 0.5, "shininess": 40})
    # Cut away the near half of the retina volume so the profile — the knotted arc — shows inside.
    return s.set_render(samples=4).set_composite(mode="first_hit", cutaway={"shape": "half_space", "normal": [0, 0, -1], "offset": 0.0})
