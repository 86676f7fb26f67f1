"""A Python scene script: the (3, 5) torus knot of the course notes ("Motivating Problems:
Curves") tubed with three frames — Frenet (top left), parallel transport (Bishop, top right) and
the closed minimal-quaternion-length frame (bottom) (``ndtrace.frames.optimal_periodic``). Each tube is a
flat ribbon (``aspect``) whose two faces are coloured differently, so the frame's turning about
the tangent shows as the ribbon twisting. The Frenet ribbon twists with the torsion; parallel
transport turns least but does not close — the mismatch shows as a kink at the seam (the knot's
rightmost point, sample 0); the optimal frame spreads that holonomy along the knot and closes.

Render it with:  ndtrace scenes/torus_knot_frames.py -o torus_knot_frames.png
"""

import numpy as np

import ndtrace
from ndtrace import frames

SIDES = 12  # ribbon cross-section: an ellipse of 12 sides, flattened along the binormal
FRONT = {"color": [0.95, 0.62, 0.2], "specular": 0.3, "shininess": 30}  # the +B face
BACK = {"color": [0.25, 0.45, 0.9], "specular": 0.3, "shininess": 30}  # the −B face


def ribbons(samples: int = 300):
    """[(vertices, triangles of the +B face, triangles of the −B face)] for the three frames."""
    points = frames.torus_knot(3, 5, samples)
    out = []
    for shift, frame in (([-1.65, 1.5, 0], frames.frenet), ([1.65, 1.5, 0], frames.parallel_transport),
                         ([0, -1.5, 0], frames.optimal_periodic)):
        T, N, B = frame(points) if frame is frames.optimal_periodic else frame(points, closed=True)
        vertices, triangles = frames.tube_3d(points, T, N, B, radius=0.16, sides=SIDES, closed=True, aspect=0.3)
        side = np.arange(len(triangles)) // 2 % SIDES  # tube_3d's layout: side j spans θ_j … θ_{j+1}
        front = np.sin(2 * np.pi * (side + 0.5) / SIDES) > 0
        out.append((vertices + shift, triangles[front], triangles[~front]))
    return out


def scene() -> ndtrace.Scene:
    s = (
        ndtrace.Scene(3, background=[0.03, 0.03, 0.04], ambient=[0.25, 0.25, 0.28])
        .set_camera([0.0, -3.0, 9.0], look_at=[0, -0.1, 0], up=[0, 1, 0], fov=45, resolution=256)
        .add_light("directional", direction=[0.3, -0.4, 1.0], color=[0.85, 0.85, 0.8])
    )
    for vertices, front, back in ribbons():
        s.add_object("mesh", vertices=vertices, simplices=front, material=FRONT, label="+B face")
        s.add_object("mesh", vertices=vertices, simplices=back, material=BACK, label="−B face")
    return s.set_render(samples=4).set_composite(
        title="Frenet, parallel transport (top); minimal quaternion (bottom)")
