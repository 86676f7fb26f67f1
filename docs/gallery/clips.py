"""The clips figure of issue 51: the 3-sphere and the tesseract cut open by a clip hyperplane
(``clip = [{ normal, offset }]``), without and with a cap (``cap = true``), in the illustrative
(top) and first-hit (bottom) composites.

    python docs/gallery/clips.py    # writes docs/gallery/clips.png
"""

import os

from PIL import Image, ImageDraw, ImageFont

import ndtrace
from ndtrace.files import to_srgb8

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = os.path.join(HERE, "..", "..", "scenes")
PANEL = 300
SPHERE_CUT = [{"normal": [1, 0, 0, 0], "offset": 0.2}]
TESSERACT_CUT = [{"normal": [0, 1, 0, 0.5], "offset": 0.3}]
COLUMNS = [("sphere3.toml", [], False, "3-sphere"),
           ("sphere3.toml", SPHERE_CUT, False, "3-sphere, clip x <= 0.2"),
           ("sphere3.toml", SPHERE_CUT, True, "the same, cap = true"),
           ("tesseract.toml", TESSERACT_CUT, True, "tesseract, clip y + w/2 <= 0.3, capped")]


def main() -> None:
    font = ImageFont.load_default(size=17)
    label = 28
    modes = ("illustrative", "first_hit")
    sheet = Image.new("RGB", (len(COLUMNS) * PANEL, label + len(modes) * PANEL + 30),
                      (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for col, (file, clip, cap, title) in enumerate(COLUMNS):
        data = ndtrace.load_file(os.path.join(SCENES, file)).to_dict()
        data["objects"] = [dict(o, clip=clip, cap=cap) for o in data["objects"]]
        scene = ndtrace.load_dict(data)
        retina = ndtrace.trace(scene)
        options = dict(data.get("composite") or {})
        options.update(size=(PANEL, PANEL), background=data["background"])
        for row, mode in enumerate(modes):
            picture = ndtrace.composite(retina, **{**options, "mode": mode})
            tile = Image.fromarray(to_srgb8(picture, opaque=True))
            sheet.paste(tile, (col * PANEL, label + row * PANEL))
        draw.text((col * PANEL + 8, 6), title, fill=(0, 0, 0), font=font)
    draw.text((8, label + len(modes) * PANEL + 7),
              "Top: illustrative composite; bottom: first-hit surface. Hits beyond the clip "
              "hyperplane are ignored; the cap fills the cut with the object's slice.",
              fill=(0, 0, 0), font=ImageFont.load_default(size=15))
    sheet.save(os.path.join(HERE, "clips.png"))


if __name__ == "__main__":
    main()
