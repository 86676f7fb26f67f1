"""The frame worker: renders a view's frames on its own thread, newest input first.

Inputs never queue behind a frame. ``request(snapshot)`` replaces whatever was waiting; the
worker then traces a **draft** of the newest snapshot (low retina resolution) as soon as it is
free. When no input has come for ``rest`` seconds (or on ``release()``, the mouse let go), it
traces the **full** frame of the newest snapshot. A full frame in flight is cancelled by the
next input through the trace's progress callback (the core stops within its 50 ms polling
interval) and its result, stale by then, is dropped. A draft in flight is not cancelled: drafts
take a few tens of milliseconds, and cancelling each one for the next mouse move would leave
nothing on the screen while the mouse moves; the next draft starts from the newest input the
moment it is done, so the screen lags the mouse by at most one draft.

The rendering itself (``render(snapshot, quality, cancelled) -> (meta, payload)``) releases
the GIL in the core, so the server's event loop (or the notebook kernel) stays responsive.
"""

from __future__ import annotations

import threading
import time
import traceback
from collections.abc import Callable
from typing import Any

__all__ = ["FrameWorker", "Superseded", "DRAFT", "FULL"]

DRAFT = "draft"
FULL = "full"


class Superseded(Exception):
    """Raised from the progress callback to cancel a frame that a newer input made stale."""


class FrameWorker:
    """Renders frames of the newest snapshot on a daemon thread and hands each finished one
    to ``emit(meta, payload)`` (called on the worker thread)."""

    def __init__(
        self,
        render: Callable[[Any, str, Callable[[], bool]], tuple[dict, bytes]],
        emit: Callable[[dict, bytes | None], None],
        *,
        rest: float = 0.25,
    ) -> None:
        self._render = render
        self._emit = emit
        self._rest = rest
        self._cond = threading.Condition()
        self._version = 0  # bumped by every input
        self._snapshot: Any = None
        self._draft_due = False  # a draft of the newest version is wanted
        self._full_done = -1  # the version whose full frame was delivered
        self._last_input = 0.0
        self._release = False
        self._closed = False
        #: Counts for tests and the benchmark: frames emitted per quality, cancelled full frames.
        self.stats = {DRAFT: 0, FULL: 0, "cancelled": 0, "dropped": 0}
        self._thread = threading.Thread(target=self._run, name="ndtrace-view-frames", daemon=True)
        self._thread.start()

    # -- inputs (any thread) -------------------------------------------------------------
    def request(self, snapshot: Any, *, draft: bool = True) -> None:
        """A new view to show: a draft now (unless ``draft=False``), the full frame at rest."""
        with self._cond:
            self._version += 1
            self._snapshot = snapshot
            self._draft_due = draft
            self._last_input = time.monotonic()
            self._release = not draft
            self._cond.notify_all()

    def release(self) -> None:
        """The interaction ended: render the full frame of the newest view without waiting."""
        with self._cond:
            self._release = True
            self._cond.notify_all()

    def close(self, timeout: float = 5.0) -> None:
        with self._cond:
            self._closed = True
            self._cond.notify_all()
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout)

    @property
    def closed(self) -> bool:
        return self._closed

    # -- the worker thread ---------------------------------------------------------------
    def _next_job(self) -> tuple[Any, int, str] | None:
        """Waits for the next frame to render: (snapshot, version, quality), None when closed."""
        with self._cond:
            while not self._closed:
                if self._snapshot is not None:
                    if self._draft_due:
                        self._draft_due = False
                        return self._snapshot, self._version, DRAFT
                    if self._full_done != self._version:
                        wait = self._last_input + self._rest - time.monotonic()
                        if self._release or wait <= 0:
                            self._release = False
                            return self._snapshot, self._version, FULL
                        self._cond.wait(wait)
                        continue
                self._cond.wait()
            return None

    def _run(self) -> None:
        while True:
            job = self._next_job()
            if job is None:
                return
            snapshot, version, quality = job

            def cancelled(version=version, quality=quality) -> bool:
                return self._closed or (quality == FULL and self._version != version)

            try:
                meta, payload = self._render(snapshot, quality, cancelled)
            except Superseded:
                self.stats["cancelled"] += 1
                continue
            except Exception as e:  # noqa: BLE001 - shown on the page, the worker goes on
                with self._cond:
                    if quality == FULL:
                        self._full_done = version  # do not retry the same failing view
                self._emit({"type": "error", "message": str(e) or type(e).__name__,
                            "detail": traceback.format_exc(limit=3)}, None)
                continue
            with self._cond:
                if self._closed:
                    return
                if quality == FULL:
                    if self._version != version:
                        self.stats["dropped"] += 1
                        continue
                    self._full_done = version
            self.stats[quality] += 1
            self._emit(meta, payload)
