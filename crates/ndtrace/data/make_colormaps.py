"""Writes colormaps.txt, the colour tables behind `material.colormap`, from matplotlib's own
colormaps (sampled at 256 points, as matplotlib's lookup tables are): one line per map, its name
then 256 RGB triples. Run it again after adding a name to MAPS:

    pip install matplotlib && python crates/ndtrace/data/make_colormaps.py

matplotlib is under its PSF-style licence (https://matplotlib.org/stable/users/project/license.html);
viridis, magma, inferno, plasma and cividis are CC0; turbo is Apache-2.0 (Google LLC).
"""

import os

import matplotlib
import numpy as np

MAPS = ["viridis", "plasma", "inferno", "magma", "cividis", "turbo", "twilight", "coolwarm",
        "RdBu", "Spectral", "terrain", "gist_earth", "gray", "bone", "hot"]


def main() -> None:
    out = os.path.join(os.path.dirname(os.path.abspath(__file__)), "colormaps.txt")
    lines = [
        f"# Written by make_colormaps.py from matplotlib {matplotlib.__version__}: a name, then the",
        "# map's 256 RGB triples (components in [0, 1]) at k / 255, k = 0, ..., 255. Do not edit.",
    ]
    for name in MAPS:
        rgb = matplotlib.colormaps[name].resampled(256)(np.linspace(0.0, 1.0, 256))[:, :3]
        lines.append(name + " " + " ".join(f"{x:.7g}" for x in rgb.ravel()))
    tmp = out + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(lines) + "\n")
    os.replace(tmp, out)
    print(f"wrote {len(MAPS)} maps to {out}")


if __name__ == "__main__":
    main()
