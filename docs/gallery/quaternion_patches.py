"""The quaternion patches figure of issue 51 (course notes Part II(A), "Optimal Quaternion Frame
on a Patch"): the frames of a spherical patch, whose third axis is the normal, mapped into
S³ ⊂ R⁴ by the three methods of ``ndtrace.frames.surface_frames`` and drawn by ndtrace's 4D
surface renderer (``shape = "surface"``), the grid's rows in two colours.

    python docs/gallery/quaternion_patches.py   # writes docs/gallery/quaternion_patches.png
"""

import os

import numpy as np
from PIL import Image, ImageDraw, ImageFont

import ndtrace
from ndtrace import frames as fr
from ndtrace.files import to_srgb8

HERE = os.path.dirname(os.path.abspath(__file__))
PANEL = 360
GRID = 24
METHODS = [("geodesic_reference", "geodesic reference"),
           ("parallel_transport", "parallel transport (one edge, then across)"),
           ("minimal_area", "minimal area")]


def picture(vertices, triangles, centre):
    # Triangles come as two halves, each cell by cell in row order: bands of three grid rows.
    rows = (np.arange(len(triangles)) % ((GRID - 1) ** 2) // (GRID - 1)) // 3 % 2 == 0
    eye = centre + 2.6 * np.array([0.25, 0.35, 0.45, 0.78])
    scene = (ndtrace.Scene(4, background=[0.03, 0.03, 0.05], ambient=[0.18, 0.18, 0.2])
             .set_camera(eye.tolist(), look_at=centre.tolist(),
                         up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=40, resolution=96)
             .add_light("point", position=(centre + [2.0, 3.0, 2.0, 2.5]).tolist())
             .add_light("directional", direction=[-0.5, 0.2, 0.3, 1.0], color=[0.3, 0.3, 0.35]))
    for keep, color in ((rows, [0.95, 0.6, 0.2]), (~rows, [0.25, 0.5, 0.95])):
        scene.add_object("surface", vertices=vertices, triangles=triangles[keep],
                         material={"color": color, "specular": 0.4, "smooth": True})
    scene.set_render(samples=4)
    p = ndtrace.composite(ndtrace.trace(scene), mode="first_hit", size=(PANEL, PANEL),
                          background=[0.03, 0.03, 0.05])
    return Image.fromarray(to_srgb8(p, opaque=True))


def main() -> None:
    points = fr.spherical_patch(GRID, 1.0)
    patches = [(fr.quaternion_patch(points, m), title) for m, title in METHODS]
    centre = np.mean(np.vstack([v for (v, _), _ in patches]), axis=0)
    font = ImageFont.load_default(size=16)
    label = 46
    sheet = Image.new("RGB", (len(METHODS) * PANEL, PANEL + label + 28), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for k, ((vertices, triangles), title) in enumerate(patches):
        q = vertices.reshape(GRID, GRID, 4)
        sheet.paste(picture(vertices, triangles, centre), (k * PANEL, label))
        draw.text((k * PANEL + 8, 4), title, fill=(0, 0, 0), font=font)
        draw.text((k * PANEL + 8, 24), f"area in S3: {fr.patch_area(q):.4f}", fill=(0, 0, 0),
                  font=font)
    draw.text((8, PANEL + label + 6),
              "The frames of a spherical patch (third axis = normal) as quaternions: the "
              "patch's image in S3, seen by a 4D camera.", fill=(0, 0, 0),
              font=ImageFont.load_default(size=15))
    sheet.save(os.path.join(HERE, "quaternion_patches.png"))


if __name__ == "__main__":
    main()
