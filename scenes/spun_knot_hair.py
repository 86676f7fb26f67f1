"""The spun trefoil (a knotted 2-sphere in R^4) rendered directly, without thickening: the ``surface`` shape ("bear
hair", course notes Part II(B)) projects the triangulated surface into the retina and lights each
point by the limit of its tube's lighting as the tube shrinks (``ndtrace.surface`` in the core).
The same scene as ``spun_knot.py`` otherwise, for side-by-side comparison.

Render it with:  ndtrace scenes/spun_knot_hair.py -o spun_knot_hair.png
"""

import os
import runpy

_thickened = runpy.run_path(os.path.join(os.path.dirname(os.path.abspath(__file__)), "spun_knot.py"))


def scene():
    return _thickened["scene"](hair=True)
