"""A Python scene script: the quaternion frame curve of the (3, 5) torus knot — the closed
minimal-length frame of ``ndtrace.frames.optimal_periodic`` as a curve q(s) on the unit 3-sphere
S³ ⊂ R⁴ (course notes, "Quaternion Frames": a frame along a curve is a quaternion curve, Tait's
equation its derivative; "Minimizing Quaternion Length Solves Periodic Tube"). A curve is
invisible to a 4D camera, so it is thickened as the notes' "Extensions to 4D rendering" suggest:
a small 2-sphere in its 3D normal space at each point (``ndtrace.frames.tube_4d``), a
3-manifold of tetrahedra that the 4D camera images on its 3D retina. The tube is coloured
in bands from orange (the knot's sample 0) through green to blue along the curve.

Render it with:  ndtrace scenes/quaternion_frame_curve.py -o quaternion_frame_curve.png
"""

import numpy as np

import ndtrace
from ndtrace import frames


def quaternion_curve(samples: int = 320) -> np.ndarray:
    """The knot's optimal frame as a closed curve on S³ (twice around the knot if the spin lift
    needs it)."""
    points = frames.torus_knot(3, 5, samples)
    return frames.quaternion_loop(frames.frame_quaternions(*frames.optimal_periodic(points)))


BANDS = 8
WARM, MID, COOL = np.array([0.95, 0.55, 0.2]), np.array([0.45, 0.85, 0.4]), np.array([0.3, 0.55, 0.95])


def scene() -> ndtrace.Scene:
    q = quaternion_curve()
    vertices, simplices = frames.tube_4d(q, radius=0.04, closed=True)
    s = (
        ndtrace.Scene(4, ambient=[0.15, 0.15, 0.18])
        .set_camera([0.5, 0.8, 1.2, 3.5], look_at=[0, 0, 0, 0],
                    up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=30, resolution=96)
        .add_light("point", position=[2, 3, 1.5, 2.5])
        # A thin tube is a smooth solid: its shaded first hit reads; the illustrative mode
        # marks nearly every cell of it as a silhouette and shows a glowing wire.
        .set_composite(mode="first_hit")
    )
    segment = np.arange(len(simplices)) * len(q) // len(simplices)  # tube_4d's layout: by segment
    band = segment * BANDS // len(q)
    for k in range(BANDS):
        t = 2 * k / (BANDS - 1)
        color = (1 - t) * WARM + t * MID if t <= 1 else (2 - t) * MID + (t - 1) * COOL
        label = {0: "start (knot sample 0)", BANDS // 2: "halfway", BANDS - 1: "end"}.get(k)
        s.add_object("mesh", vertices=vertices, simplices=simplices[band == k], label=label,
                     material={"color": color, "specular": 0.4, "shininess": 40, "smooth": True})
    return s
