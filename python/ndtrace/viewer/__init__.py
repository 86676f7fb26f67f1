"""Interactive viewing: ``ndtrace view SCENE`` (a local web page) and ``ndtrace.widget(scene)``
(the same viewer in Jupyter).

The page drives the course's controllers with the mouse (Part I(B)): a drag is the N-D rolling
ball (eq. 5), turning the object in the (x, N−1) and (y, N−1) planes; shift-drag orbits the
compositing camera of the retina; the 4D arcball (eq. 10) is a mode for N = 4; the wheel
zooms. While the mouse moves, frames trace at a draft retina resolution; at rest a full frame
follows. See :mod:`ndtrace.viewer.controls` for the exact mappings and
:mod:`ndtrace.viewer.worker` for how inputs supersede frames in flight.

    ndtrace view scenes/tesseract.toml             # prints http://127.0.0.1:PORT/?token=…
    ndtrace view scenes/penteract.toml --port 8765 --no-browser

The server needs ``pip install "ndtrace[view]"`` (aiohttp), the widget ``ndtrace[notebook]``
(anywidget).
"""

from __future__ import annotations

from .server import serve as _serve
from .session import ViewSession
from .widget import widget as _widget

__all__ = ["ViewSession", "serve", "widget"]


# The functions below are defined after the imports above on purpose: importing the submodule
# ``widget`` binds the package's attribute ``widget`` to the module, and the ``def`` then binds it
# to the function for good (a submodule is bound once, when it is first imported).


def serve(scene, **kwargs) -> None:
    """Serves the viewer of ``scene`` until Ctrl-C: see :func:`ndtrace.viewer.server.serve`."""
    _serve(scene, **kwargs)


def widget(scene, **kwargs):
    """The viewer of ``scene`` as a Jupyter widget: see :func:`ndtrace.viewer.widget.widget`."""
    return _widget(scene, **kwargs)
