"""``ndtrace.widget(scene)``: the viewer inside Jupyter, as an anywidget (``ndtrace[notebook]``).

The widget runs the page's own JS (``static/viewer.js``, with a transport over the widget's
custom messages instead of the websocket) and the same :class:`ViewSession` and
:class:`FrameWorker` as ``ndtrace view``, in the kernel::

    w = ndtrace.widget(ndtrace.load_file("scenes/tesseract.toml"))
    w                      # drag in the picture; w.rotation is the current rotation
"""

from __future__ import annotations

from importlib import resources
from typing import Any

import numpy as np

from .._optional import need
from ..scene import Scene
from .server import dispatch
from .session import ViewSession
from .worker import FrameWorker

__all__ = ["widget", "widget_esm"]

_ADAPTER = """
// --- ndtrace.widget: the viewer over the widget's custom messages ---
export default {
  render({ model, el }) {
    const transport = {
      send: (msg) => model.send(msg),
      onMessage(callback) {
        model.on("msg:custom", (msg, buffers) => {
          const b = buffers && buffers.length ? buffers[0] : null;
          callback(msg, b ? new Uint8Array(b.buffer, b.byteOffset, b.byteLength) : null);
        });
      },
      onClose() {},
    };
    el.classList.add("ndv-widget");
    window.ndtraceViewer = mount(el, transport);
  },
};
"""


def _static(name: str) -> str:
    return resources.files("ndtrace.viewer").joinpath("static", name).read_text(encoding="utf-8")


def widget_esm() -> str:
    """The widget's ES module: the page's viewer.js followed by the anywidget entry point."""
    return _static("viewer.js") + _ADAPTER


def _widget_class():
    anywidget = need("anywidget", extra="notebook", what="ndtrace.widget")
    base: Any = anywidget.AnyWidget  # imported here: an optional dependency

    class ViewerWidget(base):
        """The ndtrace viewer of one scene in a notebook (see :func:`ndtrace.widget`)."""

        _esm = widget_esm()
        _css = _static("viewer.css")

        def __init__(self, session: ViewSession) -> None:
            super().__init__()
            self._session = session
            self._worker = FrameWorker(session.render, self._emit)
            self.on_msg(self._on_message)

        def _emit(self, meta: dict, payload: bytes | None) -> None:
            self.send(meta, buffers=[payload] if payload is not None else None)

        def _on_message(self, _widget, content, buffers) -> None:
            try:
                reply, frame = self._session.handle(content)
            except (ValueError, TypeError, OverflowError, RecursionError, MemoryError) as e:
                seq = content.get("seq") if isinstance(content, dict) else None
                seq = seq if isinstance(seq, int) and not isinstance(seq, bool) else None
                self.send({"type": "error", "seq": seq, "message": (str(e) or type(e).__name__).splitlines()[0]})
                return
            if reply is not None:
                self.send(reply)
            dispatch(self._worker, self._session, frame)

        @property
        def rotation(self) -> np.ndarray:
            """The current object rotation (N×N)."""
            return self._session.rotation.copy()

        @property
        def session(self) -> ViewSession:
            return self._session

        def to_toml(self) -> str:
            """The current view as a TOML scene (what the page's "Copy TOML" gives)."""
            return self._session.view_toml()

        def close(self) -> None:
            self._worker.close(timeout=1.0)
            super().close()

    return ViewerWidget


_CLASS = None


def widget(scene: Scene, *, size: tuple[int, int] | None = None, threads: int | None = None,
           draft_cells: int | None = None, name: str | None = None):
    """The interactive viewer of ``scene`` as a Jupyter widget (anywidget): the same page,
    controls and frames as ``ndtrace view``, rendered in the kernel. ``size`` (W, H) is the
    picture's size; ``draft_cells`` the retina cells of a draft frame while the mouse moves."""
    global _CLASS
    if _CLASS is None:
        _CLASS = _widget_class()
    kwargs: dict[str, Any] = {"size": size, "threads": threads, "name": name or "scene"}
    if draft_cells is not None:
        kwargs["draft_cells"] = draft_cells
    return _CLASS(ViewSession(scene, **kwargs))
