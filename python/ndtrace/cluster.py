"""Scale-out on Dask distributed (``pip install ndtrace[dask]``): a retina traced in slabs on
the workers (``ndtrace.trace(scene, client=…)``) and an animation's frames rendered on them
(``ndtrace.animate(scene, out, client=…)``); the CLI's ``--dask`` (``local``: a LocalCluster on
this machine, or ``tcp://HOST:PORT``)::

    from dask.distributed import Client, LocalCluster
    client = Client(LocalCluster(n_workers=2, threads_per_worker=1))
    retina = ndtrace.trace(scene, client=client)       # bit-identical to ndtrace.trace(scene)
    ndtrace.animate(scene, "spin.gif", client=client)  # frames on the workers, written here

How it stays exact: a slab is a run of whole chunks of the tracer's order (the core's
``slabs``), and every cell's value depends only on the scene, the seed and the cell's index,
so the slabs traced on the workers and joined in order are the retina traced here, bit for
bit; an animation frame is rendered by the same function as without Dask. (Bit for bit
assumes the workers run the same ndtrace build on the same platform as here.) The scene goes
to every worker once (pickled: its description; each worker builds it once, on first use); a
mesh ``file`` of the scene must be readable at the same path on the workers. Each task traces
with ``threads`` threads, default 1: a worker runs as many tasks at once as it has threads.

Progress counts cells of finished slabs (or frames). Ctrl-C cancels the tasks not yet run and
stops the running traces within a fraction of a second (they watch a Dask ``Event``; a frame
being built or composited finishes that step first); a worker that dies has its tasks re-run
elsewhere by the scheduler (up to its ``allowed-failures``).
"""

from __future__ import annotations

import contextlib
import logging
import signal
import socket
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from ._dask import SLABS_PER_THREAD, distributed_module, render_frames as _render_frames, trace_slabs
from .animation import render_frame

__all__ = ["connect", "check_address", "probe", "distributed_module", "trace_slabs", "render_frames", "SLABS_PER_THREAD"]


#: Seconds a scheduler has to accept a connection and say hello.
CONNECT_TIMEOUT = 10.0


def _host_port(address: str) -> tuple[str, int] | None:
    """(HOST, PORT) of ``tcp://HOST:PORT`` (an IPv6 host in brackets), else None."""
    if not address.startswith("tcp://"):
        return None
    rest = address[len("tcp://"):].rstrip("/")
    host, sep, port = rest.rpartition(":")
    host = host[1:-1] if host.startswith("[") and host.endswith("]") else host
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        return None
    return host, int(port)


def check_address(address: str) -> str:
    """``address`` if it is ``local`` or a scheduler address ``tcp://HOST:PORT``; else a
    ValueError (other protocols, ``tls://`` and ``ucx://``, need a security or UCX setup
    that the command line does not make: give a Client to the Python API instead)."""
    if address == "local" or _host_port(address) is not None:
        return address
    scheme = address.partition("://")[0] if "://" in address else ""
    if scheme and scheme != "tcp":
        raise ValueError(f"expected 'local' or a scheduler address tcp://HOST:PORT, got {address!r} "
                         f"({scheme}:// needs a setup of its own: pass a dask Client to "
                         "ndtrace.trace or ndtrace.animate instead)")
    raise ValueError(f"expected 'local' or a scheduler address tcp://HOST:PORT, got {address!r}")


def probe(address: str, timeout: float | None = None) -> None:
    """Checks that a Dask scheduler answers at ``tcp://HOST:PORT`` before a Client waits on it:
    a scheduler says hello first (its handshake, a message that starts with its length as 8
    bytes little-endian). A ValueError says what is wrong: nothing listens, it does not answer
    within ``timeout`` seconds (default :data:`CONNECT_TIMEOUT`; a silent server, or an HTTP server waiting for a request), or
    it answers something else."""
    host, port = _host_port(address) or ("", 0)
    timeout = CONNECT_TIMEOUT if timeout is None else timeout
    try:
        with socket.create_connection((host, port), timeout=timeout) as conn:
            conn.settimeout(timeout)
            hello = b""
            while len(hello) < 8:
                chunk = conn.recv(8 - len(hello))
                if not chunk:
                    raise ValueError("it closed the connection without a Dask handshake "
                                     "(is it a Dask scheduler?)")
                hello += chunk
    except TimeoutError:
        raise ValueError(f"no Dask handshake within {timeout:g} s (is it a Dask scheduler?)") from None
    except OSError as e:
        raise ValueError(e.strerror or str(e)) from None
    if not 0 < int.from_bytes(hello, "little") < (64 << 20):
        raise ValueError("it does not speak Dask's protocol (is it a Dask scheduler?)")


@contextlib.contextmanager
def connect(address: str) -> Iterator[Any]:
    """A Dask client for the CLI's ``--dask ADDRESS``: ``local`` starts a LocalCluster on this
    machine (worker processes; it and its HTTP server bound to 127.0.0.1; closed on exit), anything
    else is a scheduler address (``tcp://HOST:PORT``)."""
    try:
        check_address(address)
    except ValueError as e:
        raise ValueError(f"--dask {address}: {e}") from None
    distributed = distributed_module()
    if address == "local":
        cluster = distributed.LocalCluster(host="127.0.0.1", dashboard_address="127.0.0.1:0",
                                           processes=True, silence_logs=logging.ERROR)
        try:
            with distributed.Client(cluster) as client:
                # Ctrl-C reaches the workers too (one process group): this process stops them.
                client.register_plugin(_ignore_sigint())
                yield client
        finally:
            cluster.close()
        return
    try:
        probe(address)
        client = distributed.Client(address, timeout=f"{CONNECT_TIMEOUT:g}s")
    except (Exception, SystemExit) as e:  # noqa: BLE001 - distributed raises many kinds; one line
        reason = (str(e).strip() or type(e).__name__).splitlines()[0]
        raise ValueError(f"--dask {address}: cannot reach the Dask scheduler: {reason}") from None
    with client:
        yield client


def _ignore_sigint():
    """A worker plugin that makes the workers of a LocalCluster ignore SIGINT (Ctrl-C in the
    terminal signals the whole process group): the client cancels their tasks instead, and
    closing the cluster ends them, without a traceback from each worker."""
    from distributed import WorkerPlugin

    class IgnoreSigint(WorkerPlugin):
        name = "ndtrace-ignore-sigint"

        def setup(self, worker) -> None:
            signal.signal(signal.SIGINT, signal.SIG_IGN)

    return IgnoreSigint()


def render_frames(animated, count: int, client, threads: int | None, options: dict,
                  cells: int, progress: Callable[[int, int], object] | None,
                  on_frame: Callable[[int, np.ndarray], None]) -> None:
    """Frames ``0 … count−1`` of ``animated`` rendered on ``client``'s workers by
    :func:`ndtrace.animation.render_frame`; ``on_frame(k, picture)`` is called here in frame
    order (frames that finish early wait their turn)."""
    _render_frames(animated, count, client, threads, options, cells, progress, on_frame, render_frame)
