"""Writes python/ndtrace/fonts/DejaVuSans-subset.ttf, the font of every label ndtrace draws
(ndtrace.annotate: captions, panel titles, legends, the axes glyph): DejaVu Sans cut down to the
characters the labels use (ASCII and Latin-1, Greek, the general punctuation, super- and
subscripts, arrows and a few mathematical signs), about 65 kB. DejaVu Sans is free (Bitstream
Vera licence with the DejaVu changes in the public domain; fonts/LICENSE_DEJAVU). It is taken
from matplotlib, which ships it:

    pip install matplotlib fonttools && python tools/make_font.py
"""

import os
import shutil
import subprocess
import sys

import matplotlib

UNICODES = ",".join([
    "U+0020-007E", "U+00A0-00FF",          # ASCII, Latin-1 (°, ±, ×, ·)
    "U+0391-03C9",                         # Greek
    "U+2010-2027", "U+2030-203A",          # dashes, quotes, ellipsis, primes
    "U+2070-209C",                         # super- and subscripts (u₁, x²)
    "U+2190-2195", "U+21D2",               # arrows
    "U+2212", "U+2213", "U+2218", "U+221A", "U+221E", "U+2225", "U+2248", "U+2260",
    "U+2264", "U+2265", "U+2297", "U+2299", "U+22A5", "U+22C5",  # − ∓ ∘ √ ∞ ∥ ≈ ≠ ≤ ≥ ⊗ ⊙ ⊥ ⋅
    "U+25A0", "U+25CF",                    # ■ ●
])


def main() -> None:
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    fonts = os.path.join(root, "python", "ndtrace", "fonts")
    source = os.path.join(os.path.dirname(matplotlib.__file__), "mpl-data", "fonts", "ttf")
    out = os.path.join(fonts, "DejaVuSans-subset.ttf")
    subprocess.run([sys.executable, "-m", "fontTools.subset", os.path.join(source, "DejaVuSans.ttf"),
                    f"--unicodes={UNICODES}", "--layout-features=kern", f"--output-file={out}"], check=True)
    shutil.copyfile(os.path.join(source, "LICENSE_DEJAVU"), os.path.join(fonts, "LICENSE_DEJAVU"))
    print(f"wrote {out} ({os.path.getsize(out)} bytes)")


if __name__ == "__main__":
    main()
