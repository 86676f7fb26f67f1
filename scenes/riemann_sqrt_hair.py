"""The Riemann surface of √z rendered directly, without thickening: the ``surface`` shape ("bear
hair", course notes Part II(B)) projects the triangulated surface into the retina and lights each
point by the limit of its tube's lighting as the tube shrinks (``ndtrace.surface`` in the core).
The same scene as ``riemann_sqrt.py`` otherwise, for side-by-side comparison.

Render it with:  ndtrace scenes/riemann_sqrt_hair.py -o riemann_sqrt_hair.png
"""

import os
import runpy

_thickened = runpy.run_path(os.path.join(os.path.dirname(os.path.abspath(__file__)), "riemann_sqrt.py"))


def scene():
    return _thickened["scene"](hair=True)
