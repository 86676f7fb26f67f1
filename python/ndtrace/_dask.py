"""The Dask machinery of :mod:`ndtrace.cluster` (how it stays exact, Ctrl-C and dying workers
are described there): tasks on a client's workers gathered in order with progress and
cancellation, the retina traced in slabs (``ndtrace.trace(scene, client=…)``) and an
animation's frames rendered by a function the caller hands in (``ndtrace.animate``).

It uses no other ndtrace module: scenes are duck-typed (``scene.compiled()``), so the tracer
(:mod:`ndtrace.retina`) and the animations (:mod:`ndtrace.animation`) can both build on it.
``distributed`` itself is imported when first needed.
"""

from __future__ import annotations

import contextlib
import signal
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from ._optional import need

__all__ = ["distributed_module", "trace_slabs", "render_frames", "SLABS_PER_THREAD"]

#: Slabs per worker thread of a distributed trace: enough for even load and steady progress,
#: few enough that a slab's fixed cost (a task, culling, a thread pool) stays small.
SLABS_PER_THREAD = 4

_FIELDS = ("rgba", "depth", "normal", "object_id", "primitive_id")


def distributed_module():
    """The ``distributed`` module (ImportError naming the ``dask`` extra without it)."""
    return need("distributed", extra="dask", what="rendering on Dask", package="dask.distributed")


def _check_client(client: Any):
    distributed = distributed_module()
    if not isinstance(client, distributed.Client):
        raise TypeError(f"client: expected a dask.distributed.Client, got {type(client).__name__}")
    if client.asynchronous:
        raise ValueError("client: expected a synchronous Dask client, got an asynchronous one "
                         "(Client(asynchronous=True))")
    if client.status not in ("running", "connecting", "newly-created"):
        raise ValueError(f"client: the Dask client is {client.status}, not running")
    return distributed


#: Held while a worker builds a scene, so that its concurrent tasks build it once.
_BUILD_LOCK = threading.Lock()


def _built(scene):
    """``scene.compiled()``, built by one of a worker's tasks while the others wait."""
    with _BUILD_LOCK:
        return scene.compiled()


class _Cancelled(Exception):
    """Raised in a worker's progress callback when the client asked to stop."""


def _watcher(cancel: str) -> Callable[[int, int], None]:
    """A trace progress callback that raises :class:`_Cancelled` once the Dask ``Event``
    ``cancel`` is set (checked at most five times a second)."""
    from distributed import Event

    event = Event(cancel)
    last = [0.0]

    def tick(_done: int, _total: int) -> None:
        now = time.monotonic()
        if now - last[0] >= 0.2:
            last[0] = now
            if event.is_set():
                raise _Cancelled(cancel)

    return tick


def _trace_slab(scene, cells: tuple[int, int], threads: int | None, cancel: str) -> dict:
    """Task: the cells ``cells`` of ``scene``'s retina, flat (the core's ``trace(cells=…)``)."""
    out = _built(scene).trace(threads or 1, _watcher(cancel), cells)
    return {k: out[k] for k in _FIELDS}


#: How often the client looks for finished tasks (and raises a Ctrl-C it held back).
_POLL_SECONDS = 0.05

#: The signals whose Python handlers :class:`_Signals` watches (the CLI's Ctrl-C, SIGTERM and
#: SIGHUP all raise KeyboardInterrupt).
_WATCHED = tuple(getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n))


class _Signals:
    """While in use (``with``), the Python handlers of the signals in ``_WATCHED`` can be held
    back: a handler's exception raised inside ``with held():`` is kept and raised by the next
    ``check()`` instead.

    A signal's handler runs wherever the main thread is, and a KeyboardInterrupt raised inside
    a finalizer — a Dask future's ``__del__``, run as a finished future is let go — is printed
    as "Exception ignored" with a traceback and dropped: Ctrl-C would go unnoticed and the
    render run to its end. So the code that lets futures go runs ``held()``. Outside the main
    thread (no handlers run there) this changes nothing."""

    def __init__(self) -> None:
        self.kept: list[BaseException] = []
        self.holding = False
        self.previous: dict = {}

    def __enter__(self) -> _Signals:
        if threading.current_thread() is threading.main_thread():
            self.previous = {s: h for s in _WATCHED if callable(h := signal.getsignal(s))}
        for s, handler in self.previous.items():
            signal.signal(s, self._keeping(handler))
        return self

    def __exit__(self, *_exc) -> None:
        for s, handler in self.previous.items():
            signal.signal(s, handler)

    def _keeping(self, handler):
        def handle(signum, frame):
            try:
                handler(signum, frame)
            except BaseException as e:
                self.kept.append(e)
                if not self.holding:
                    raise
        return handle

    @contextlib.contextmanager
    def held(self) -> Iterator[None]:
        self.holding = True
        try:
            yield
        finally:
            self.holding = False

    def check(self) -> None:
        """Raises the first exception a handler raised here, if any."""
        if self.kept:
            raise self.kept[0]


def _gather(client, scatter: Callable[[], Any], submit: Callable[[Any, int, str], Any],
            weights: list[int], window: int | None,
            progress: Callable[[int, int], object] | None, what: str,
            on_result: Callable[[int, Any], None]) -> None:
    """Runs task ``i`` = ``submit(shared, i, cancel)`` for every index of ``weights`` (``shared``:
    what ``scatter()`` put on the workers; ``cancel``: the name of the Dask ``Event`` the tasks
    watch), at most ``window`` at once (None: all), in index order, and calls
    ``on_result(i, value)`` in completion order and ``progress(done, total)`` by ``weights``; a
    finished future is let go at once. A task's error is re-raised here with a note naming
    ``what`` and the index. On any error or Ctrl-C (submitting included): sets the event
    (running tasks stop; it stays set, named for this call only), cancels the rest, and
    re-raises."""
    distributed = distributed_module()
    cancel = f"ndtrace-cancel-{uuid.uuid4().hex}"
    event = distributed.Event(cancel, client=client)
    count = len(weights)
    running: dict[str, tuple[int, Any]] = {}
    try:
        with _Signals() as signals:
            shared = scatter()
            queue = distributed.as_completed()
            following = 0

            def more() -> None:
                nonlocal following
                while following < count and (window is None or len(running) < window):
                    # (ruff takes the `del` below for an unbinding of these two: F821)
                    future = submit(shared, following, cancel)  # noqa: F821
                    running[future.key] = (following, future)
                    queue.add(future)  # noqa: F821
                    following += 1

            total, done = sum(weights), 0
            more()
            if progress is not None:
                progress(0, total)
            while not queue.is_empty():
                signals.check()
                if not queue.has_ready():
                    time.sleep(_POLL_SECONDS)
                    continue
                # Finished futures are let go here (their __del__ runs): Ctrl-C waits.
                with signals.held():
                    future = next(queue)
                    i = running.pop(future.key)[0]
                    try:
                        value = future.result()
                    except Exception as e:
                        e.add_note(f"(raised on a Dask worker, {what} {i})")
                        raise
                    finally:
                        del future
                    more()
                signals.check()
                on_result(i, value)
                done += weights[i]
                if progress is not None:
                    progress(done, total)
            with signals.held():
                del queue, shared
            # A Ctrl-C kept during the last progress call (or the last futures' release) still
            # stops the call, as one during any earlier step does.
            signals.check()
    except BaseException:
        with contextlib.suppress(Exception):
            event.set()
        with contextlib.suppress(Exception):
            client.cancel([f for _, f in running.values()])
        raise


def trace_slabs(scene, client, threads: int | None,
                progress: Callable[[int, int], object] | None) -> dict:
    """The retina of ``scene`` traced in slabs on ``client``'s workers: a dict of numpy arrays
    as ``CompiledScene.trace`` gives, bit-identical to it."""
    _check_client(client)
    compiled = scene.compiled()
    shape = tuple(compiled.retina_shape)
    slots = sum(client.nthreads().values()) or 1
    slabs = compiled.slabs(SLABS_PER_THREAD * slots)
    token = uuid.uuid4().hex
    parts: list = [None] * len(slabs)
    _gather(client, lambda: client.scatter([scene], broadcast=True, hash=False)[0],
            lambda shared, i, cancel: client.submit(
                _trace_slab, shared, slabs[i], threads, cancel,
                key=f"ndtrace-slab-{token}-{i}", pure=False),
            [b - a for a, b in slabs], None, progress, "slab",
            lambda i, value: parts.__setitem__(i, value))
    out: dict = {"dim": compiled.dim}
    for name in _FIELDS:
        joined = np.concatenate([p[name] for p in parts])
        extra = joined.shape[1:]
        out[name] = joined.reshape(shape + extra)
    return out


def _render_frame(render: Callable[..., np.ndarray], animated, k: int, threads: int | None,
                  options: dict, cancel: str) -> np.ndarray:
    """Task: frame ``k`` of an animation, traced and composited by ``render`` (the caller's
    ``ndtrace.animation.render_frame``)."""
    _built(animated)
    return render(animated, k, threads or 1, options, _watcher(cancel))


def render_frames(animated, count: int, client, threads: int | None, options: dict,
                  cells: int, progress: Callable[[int, int], object] | None,
                  on_frame: Callable[[int, np.ndarray], None],
                  render: Callable[..., np.ndarray]) -> None:
    """Frames ``0 … count−1`` of ``animated`` rendered on ``client``'s workers, frame k by
    ``render(animated, k, threads, options, progress)`` (a module-level function: the tasks
    pickle it by name); ``on_frame(k, picture)`` is called here in frame order (frames that
    finish early wait their turn)."""
    _check_client(client)
    token = uuid.uuid4().hex
    waiting: dict[int, np.ndarray] = {}
    following = [0]

    def arrived(k: int, picture: np.ndarray) -> None:
        waiting[k] = picture
        while following[0] in waiting:
            on_frame(following[0], waiting.pop(following[0]))
            following[0] += 1

    # Frames go out in order, a few per worker thread at a time: the pictures that wait here
    # for an earlier frame stay few, however long the animation.
    slots = sum(client.nthreads().values()) or 1
    _gather(client, lambda: client.scatter([animated], broadcast=True, hash=False)[0],
            lambda shared, k, cancel: client.submit(
                _render_frame, render, shared, k, threads, options, cancel,
                key=f"ndtrace-frame-{token}-{k}", pure=False),
            [cells] * count, 2 * slots, progress, "frame", arrived)
