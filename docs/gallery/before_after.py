"""Puts the gallery's 4D and 5D pictures beside what the same scenes gave before the
illustrative composite (issue 19) and before pictures were drawn at their own resolution
(issue 47): docs/gallery/before/<name>.png (rendered at the earlier default, an opaque volume
composite), docs/gallery/before/<name>_issue46.png (the illustrative composite from the
retina's cells) and docs/gallery/<name>.png (now) in three rows, docs/gallery/before_after.png;
and the elevation map's three stages (issue 20: the opaque cube, the illustrative fog of a
hand-built mesh, the elevation shape with colour, isolines, shadows, cutaway and sections) in
docs/gallery/elevation_before_after.png.

    python docs/gallery/render_gallery.py && python docs/gallery/before_after.py
"""

import os

from PIL import Image, ImageDraw

HERE = os.path.dirname(os.path.abspath(__file__))
NAMES = ["tesseract", "cell16", "sphere3", "elevation", "penteract"]
TILE = 256


def main() -> None:
    rows = ["before/{}.png", "before/{}_issue46.png", "{}.png"]
    strip = Image.new("RGB", (TILE * len(NAMES), len(rows) * TILE + 40), (24, 24, 24))
    draw = ImageDraw.Draw(strip)
    for i, name in enumerate(NAMES):
        for row, path in enumerate(os.path.join(HERE, r.format(name)) for r in rows):
            tile = Image.open(path).convert("RGB").resize((TILE, TILE), Image.LANCZOS)
            strip.paste(tile, (i * TILE, 20 + row * TILE))
        draw.text((i * TILE + 6, 4), name, fill=(230, 230, 230))
    draw.text((4, len(rows) * TILE + 24),
              "top: opaque volume composite   middle: illustrative from the retina's cells   "
              "bottom: now (drawn from the scene at the picture's resolution)",
              fill=(230, 230, 230))
    strip.save(os.path.join(HERE, "before_after.png"))

    stages = [("before/elevation.png", "opaque volume"), ("before/elevation_issue19.png", "illustrative, a mesh"),
              ("elevation.png", "elevation shape: colour, isolines, cutaway, sections"), ("mr_head.png", "a real MR volume")]
    strip = Image.new("RGB", (TILE * len(stages), TILE + 24), (24, 24, 24))
    draw = ImageDraw.Draw(strip)
    for i, (path, label) in enumerate(stages):
        tile = Image.open(os.path.join(HERE, path)).convert("RGB").resize((TILE, TILE), Image.LANCZOS)
        strip.paste(tile, (i * TILE, 24))
        draw.text((i * TILE + 6, 6), label, fill=(230, 230, 230))
    strip.save(os.path.join(HERE, "elevation_before_after.png"))


if __name__ == "__main__":
    main()
