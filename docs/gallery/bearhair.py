"""The side-by-side figure of issue 21: each surface of the gallery thickened (a tube of circles,
traced as tetrahedra) above, drawn directly as a surface ("bear hair") below.

    python docs/gallery/render_gallery.py   # renders <name>.png and <name>_hair.png first
    python docs/gallery/bearhair.py          # then writes docs/gallery/bearhair.png
"""

import os

from PIL import Image, ImageDraw

HERE = os.path.dirname(os.path.abspath(__file__))
NAMES = [("clifford_torus", "Clifford torus"), ("spun_knot", "spun trefoil (cut away)"),
         ("riemann_sqrt", "Riemann surface of sqrt(z)")]
SIZE = 384


def main() -> None:
    label = 28
    sheet = Image.new("RGB", (SIZE * len(NAMES), 2 * (SIZE + label)), (255, 255, 255))
    draw = ImageDraw.Draw(sheet)
    for col, (name, title) in enumerate(NAMES):
        for row, (suffix, how) in enumerate((("", "thickened"), ("_hair", "bear hair"))):
            with Image.open(os.path.join(HERE, f"{name}{suffix}.png")) as im:
                tile = im.convert("RGB").resize((SIZE, SIZE), Image.LANCZOS)
            y = row * (SIZE + label)
            sheet.paste(tile, (col * SIZE, y + label))
            draw.text((col * SIZE + 8, y + 8), f"{title}: {how}", fill=(0, 0, 0))
    sheet.save(os.path.join(HERE, "bearhair.png"))


if __name__ == "__main__":
    main()
