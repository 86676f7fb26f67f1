"""Renders every scene of scenes/ to docs/gallery/<name>.png with the ndtrace command line,
at the scenes' own defaults, and prints how long each took.

    python docs/gallery/render_gallery.py
"""

import glob
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
OUT = os.path.join(ROOT, "docs", "gallery")


def main() -> None:
    scenes = sorted(glob.glob(os.path.join(ROOT, "scenes", "*.toml")) + glob.glob(os.path.join(ROOT, "scenes", "*.py")))
    for path in scenes:
        name = os.path.splitext(os.path.basename(path))[0]
        out = os.path.join(OUT, f"{name}.png")
        t = time.perf_counter()
        subprocess.run([sys.executable, "-m", "ndtrace.cli", path, "-o", out, "--quiet"], check=True)
        print(f"{name:<12} {time.perf_counter() - t:6.2f} s  {os.path.relpath(out, ROOT)}", flush=True)


if __name__ == "__main__":
    main()
