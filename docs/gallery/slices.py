"""The slices figure of issue 51: the tesseract and the 16-cell cut by the hyperplane w = c at
three offsets, each slice (a 3D object, traced as a 3D scene) beside the 4D projection with the
hyperplane marked in orange where it crosses the polytope (``[composite] layout = "slice"``),
and the tesseract swept through w as a GIF (``[animation] slice = {...}``).

    python docs/gallery/slices.py    # writes docs/gallery/slices.png and tesseract_sweep.gif
"""

import os

import numpy as np
from PIL import Image, ImageDraw, ImageFont

import ndtrace
from ndtrace.files import to_srgb8

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = os.path.join(HERE, "..", "..", "scenes")
ROWS = [("tesseract.toml", "tesseract", (-0.9, 0.0, 0.6)),
        ("cell16.toml", "16-cell", (-0.6, 0.0, 0.45))]
PANEL = 280


def pair(scene: ndtrace.Scene, offset: float) -> np.ndarray:
    """The projection with the hyperplane w = offset marked, beside the slice."""
    s = scene.copy().set_slice([0, 0, 0, 1], offset)
    options = {"layout": "slice", "size": (2 * PANEL, PANEL),
               "background": s.to_dict()["background"]}
    return ndtrace.slicing.picture(s, ndtrace.trace(s), options)


def main() -> None:
    font = ImageFont.load_default(size=18)
    label = 30
    width = 3 * 2 * PANEL
    caption = 34
    sheet = Image.new("RGB", (width, len(ROWS) * (PANEL + label) + caption), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for row, (file, name, offsets) in enumerate(ROWS):
        scene = ndtrace.load_file(os.path.join(SCENES, file))
        for col, c in enumerate(offsets):
            picture = Image.fromarray(to_srgb8(pair(scene, c), opaque=True))
            x, y = col * 2 * PANEL, row * (PANEL + label)
            sheet.paste(picture, (x, y + label))
            draw.text((x + 8, y + 6), f"{name}, w = {c:g}: 4D projection | its 3D slice",
                      fill=(0, 0, 0), font=font)
            draw.line([(x + PANEL, y + label), (x + PANEL, y + label + PANEL)],
                      fill=(255, 255, 255), width=1)
    draw.text((8, len(ROWS) * (PANEL + label) + 8),
              "Left of each pair: the 4D object projected to its 3D retina, the hyperplane w = c "
              "marked in cyan where it cuts the surface seen; right: the 3D slice, traced as a "
              "3D scene.", fill=(0, 0, 0), font=ImageFont.load_default(size=16))
    sheet.save(os.path.join(HERE, "slices.png"))

    scene = ndtrace.load_file(os.path.join(SCENES, "tesseract.toml"))
    scene.set_slice([0, 0, 0, 1], 0.0)
    data = scene.to_dict()
    data["camera"]["resolution"] = 64
    data["composite"] = {"layout": "slice", "size": [400, 200]}
    data["animation"] = {"frames": 30, "fps": 10,
                         "slice": {"normal": [0, 0, 0, 1], "from": -1.35, "to": 1.35}}
    ndtrace.animate(ndtrace.load_dict(data), os.path.join(HERE, "tesseract_sweep.gif"))


if __name__ == "__main__":
    main()
