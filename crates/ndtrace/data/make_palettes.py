"""Writes palettes.txt, the qualitative colour lists behind `material.palette` (`color_by`,
`composite.edge_color_by = "direction"`), from matplotlib's own qualitative colormaps: one line
per palette, its name then its RGB triples (sRGB, components in [0, 1]). Run it again after
adding a name to PALETTES:

    pip install matplotlib && python crates/ndtrace/data/make_palettes.py

matplotlib is under its PSF-style licence (https://matplotlib.org/stable/users/project/license.html);
the tab10/tab20 palettes are Tableau's (as shipped by matplotlib), Set1, Set2, Set3, Dark2, Paired,
Accent, Pastel1 and Pastel2 are ColorBrewer's (Apache-2.0, Cynthia Brewer).
"""

import os

import matplotlib

PALETTES = ["tab10", "tab20", "Set1", "Set2", "Set3", "Dark2", "Paired", "Accent", "Pastel1", "Pastel2"]


def main() -> None:
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "palettes.txt")
    lines = [
        f"# Written by make_palettes.py from matplotlib {matplotlib.__version__}: a name, then the",
        "# palette's colours as sRGB triples (components in [0, 1]), in matplotlib's order. Do not edit.",
    ]
    for name in PALETTES:
        colors = matplotlib.colormaps[name].colors
        lines.append(name + " " + " ".join(f"{x:.7g}" for c in colors for x in c[:3]))
    tmp = out + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, out)
    print(f"wrote {len(PALETTES)} palettes to {out}")


if __name__ == "__main__":
    main()
