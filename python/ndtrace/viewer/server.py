"""The local web server of ``ndtrace view``: aiohttp on 127.0.0.1, one page, one websocket.

* ``GET /?token=T`` — the page (``static/index.html`` with the viewer's JS and CSS inlined:
  one request, no CDN, works offline);
* ``GET /ws?token=T`` — the websocket: JSON messages from the page (see ``session.py``),
  JSON replies and binary frames back (4-byte little-endian header length, the JSON header,
  the JPEG or PNG picture).

Every request must carry the random token of the printed URL (403 without it), and the server
listens on the loopback interface only. Each page gets its own :class:`ViewSession` and
:class:`FrameWorker` (frames render on the worker's thread, off the event loop).
"""

from __future__ import annotations

import asyncio
import collections
import hmac
import json
import os
import secrets
import signal
import sys
import threading
from collections.abc import Callable
from importlib import resources
from typing import Any, TextIO

from ..scene import Scene
from .session import MAX_MESSAGE_BYTES, ViewSession, parse_message
from .worker import FrameWorker

__all__ = ["HOST", "page_html", "frame_message", "dispatch", "make_app", "serve", "Outbox",
           "encode_reply", "session_replies", "MAX_QUEUED_MESSAGES", "MAX_QUEUED_BYTES"]

#: The only interface the viewer listens on.
HOST = "127.0.0.1"


def _static(name: str) -> str:
    return resources.files("ndtrace.viewer").joinpath("static", name).read_text(encoding="utf-8")


def page_html() -> str:
    """The page: index.html with viewer.css and viewer.js inlined."""
    return (_static("index.html").replace("/*VIEWER_CSS*/", _static("viewer.css"))
            .replace("/*VIEWER_JS*/", _static("viewer.js")))


def frame_message(meta: dict, payload: bytes) -> bytes:
    """A binary websocket message: header length (uint32 LE), JSON header, picture bytes."""
    header = encode_reply(meta).encode()
    return len(header).to_bytes(4, "little") + header + payload


def dispatch(worker: FrameWorker, session: ViewSession, frame: str | None) -> None:
    """Passes the frame a message asked for (:meth:`ViewSession.handle`) to the worker."""
    if frame in ("draft", "now"):
        worker.request(session.snapshot())
    if frame in ("now", "release"):
        worker.release()


#: A client's replies and frames waiting to be sent, at most: this many messages …
MAX_QUEUED_MESSAGES = 256
#: … and this many bytes (a full frame is a PNG of the picture; a ``toml`` reply of a large
#: mesh scene can be tens of megabytes). A client that lets more pile up does not read what it
#: is sent: it is disconnected.
MAX_QUEUED_BYTES = 64 << 20
#: Seconds a closing handshake (and the shutdown's) may take before the connection is cut.
CLOSE_TIMEOUT = 2.0


class Outbox:
    """One client's bounded queue of messages to send, each encoded when it is put: a JSON
    reply (``str``) or a binary frame (``bytes``). A frame waiting to be sent is replaced by a
    newer one (a stale frame is never worth sending); beyond :data:`MAX_QUEUED_MESSAGES` or
    :data:`MAX_QUEUED_BYTES` the queue is *overflowing*: :meth:`put` returns False and the
    server disconnects the client."""

    def __init__(self, max_messages: int = MAX_QUEUED_MESSAGES, max_bytes: int = MAX_QUEUED_BYTES) -> None:
        self.max_messages, self.max_bytes = max_messages, max_bytes
        self._items: collections.deque = collections.deque()
        self._bytes = 0
        self._ready = asyncio.Event()
        self.overflowing = False
        self.dropped_frames = 0

    def __len__(self) -> int:
        return len(self._items)

    @property
    def queued_bytes(self) -> int:
        return self._bytes

    def put(self, item: str | bytes) -> bool:
        if self.overflowing:
            return False
        if isinstance(item, bytes):  # a frame: replaces a waiting one
            for i, old in enumerate(self._items):
                if isinstance(old, bytes):
                    del self._items[i]
                    self._bytes -= len(old)
                    self.dropped_frames += 1
                    break
        self._items.append(item)
        self._bytes += len(item)
        if len(self._items) > self.max_messages or self._bytes > self.max_bytes:
            self.overflowing = True
            self._items.clear()
            self._bytes = 0
            self._ready.set()
            return False
        self._ready.set()
        return True

    async def get(self) -> str | bytes | None:
        """The next message, None once the queue overflowed."""
        while not self._items:
            if self.overflowing:
                return None
            self._ready.clear()
            await self._ready.wait()
        item = self._items.popleft()
        self._bytes -= len(item)
        return item


def encode_reply(meta: dict) -> str:
    """A JSON reply: strictly JSON (no NaN or Infinity, which the page's ``JSON.parse``
    refuses); a reply that is not becomes an error reply saying so."""
    try:
        return json.dumps(meta, allow_nan=False)
    except (ValueError, TypeError) as e:
        return json.dumps({"type": "error", "seq": meta.get("seq") if isinstance(meta.get("seq"), int) else None,
                           "message": f"reply: not JSON: {e}"})


def session_replies(session: ViewSession, text: str | bytes) -> tuple[list[dict], str | None]:
    """What the server answers to one message ``text`` of a page: the replies (a ``state``,
    ``hello``, ``toml`` or ``error`` object) and the frame to ask the worker for. Never raises:
    a bad message is an error reply and leaves the session as it was."""
    data: Any = None
    try:
        data = parse_message(text)
        reply, frame = session.handle(data)
    except (ValueError, TypeError, OverflowError, RecursionError, MemoryError) as e:
        seq = data.get("seq") if isinstance(data, dict) else None
        return [{"type": "error", "seq": seq if isinstance(seq, int) and not isinstance(seq, bool) else None,
                 "message": (str(e) or type(e).__name__).splitlines()[0]}], None
    return ([reply] if reply is not None else []), frame


def _allowed_origins(port: int) -> set[str]:
    return {f"http://{HOST}:{port}", f"http://localhost:{port}"}


def make_app(make_session: Callable[[], ViewSession], token: str):
    """The aiohttp application: the token check, the page and the websocket."""
    from aiohttp import WSMsgType, web

    @web.middleware
    async def require_token(request: web.Request, handler):
        given = request.query.get("token", "")
        if not hmac.compare_digest(given.encode(), token.encode()):
            return web.Response(status=403, text="403: ndtrace view needs the token of the URL it printed\n")
        return await handler(request)

    html = page_html()

    async def page(request: web.Request) -> web.Response:
        return web.Response(text=html, content_type="text/html",
                            headers={"Cache-Control": "no-store", "X-Content-Type-Options": "nosniff",
                                     "Referrer-Policy": "no-referrer"})

    sockets: dict = {}  # open websockets → their transports (cut at shutdown if need be)

    async def close(ws, transport, code: int, message: bytes) -> None:
        """Closes a websocket; cuts the connection when the peer does not take the close."""
        try:
            await asyncio.wait_for(ws.close(code=code, message=message), CLOSE_TIMEOUT)
        except (TimeoutError, ConnectionError, RuntimeError):
            pass
        finally:
            if transport is not None and not transport.is_closing():
                transport.abort()

    async def socket(request: web.Request) -> web.StreamResponse:
        # A page's own websocket comes from the page's origin (the browser says so): a page of
        # another site that learnt the token cannot drive the viewer.
        origin = request.headers.get("Origin")
        sockname = request.transport.get_extra_info("sockname") if request.transport else None
        port = sockname[1] if sockname else 0
        if origin is not None and origin not in _allowed_origins(port):
            return web.Response(status=403, text="403: ndtrace view takes websockets from its own page only\n")
        # Messages up to 4× the limit get an error reply (parse_message); longer ones close the socket.
        ws = web.WebSocketResponse(heartbeat=30.0, max_msg_size=4 * MAX_MESSAGE_BYTES, timeout=CLOSE_TIMEOUT)
        await ws.prepare(request)
        transport = request.transport
        sockets[ws] = transport
        loop = asyncio.get_running_loop()
        outbox = Outbox()

        def enqueue(item: str | bytes) -> None:  # on the event loop
            if not outbox.put(item):
                sys.stderr.write("ndtrace view: a page did not read its replies: disconnected it\n")
                overflowed.set()

        def emit(meta: dict, payload: bytes | None) -> None:  # from the worker thread
            if meta.get("type") == "error":  # a frame failed: the terminal hears of it too
                sys.stderr.write(f"ndtrace view: a frame failed: {meta['message']}\n")
            item = encode_reply(meta) if payload is None else frame_message(meta, payload)
            try:
                loop.call_soon_threadsafe(enqueue, item)
            except RuntimeError:  # the loop has closed: the page is gone
                pass

        session = make_session()
        worker = FrameWorker(session.render, emit)
        overflowed = asyncio.Event()

        async def sender() -> None:
            while True:
                item = await outbox.get()
                if item is None:
                    return
                if isinstance(item, str):
                    await ws.send_str(item)
                else:
                    await ws.send_bytes(item)

        async def receiver() -> None:
            async for msg in ws:
                if msg.type not in (WSMsgType.TEXT, WSMsgType.BINARY):
                    continue
                replies, frame = session_replies(session, msg.data)
                for reply in replies:
                    enqueue(encode_reply(reply))
                if outbox.overflowing:
                    return
                dispatch(worker, session, frame)

        sending = asyncio.create_task(sender())
        receiving = asyncio.create_task(receiver())
        cut = asyncio.create_task(overflowed.wait())
        try:
            await asyncio.wait({sending, receiving, cut}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            worker.close(timeout=0)
            session.close()
            for task in (sending, receiving, cut):
                task.cancel()
            await asyncio.gather(sending, receiving, cut, return_exceptions=True)
            code, why = (1008, b"ndtrace view: the page did not read its replies") if outbox.overflowing \
                else (1000, b"")
            await close(ws, transport, code, why)
            sockets.pop(ws, None)
        return ws

    async def close_sockets(app) -> None:
        await asyncio.gather(*(close(ws, t, 1001, b"ndtrace view stopped") for ws, t in list(sockets.items())),
                             return_exceptions=True)

    app = web.Application(middlewares=[require_token])
    app.router.add_get("/", page)
    app.router.add_get("/ws", socket)
    app.on_shutdown.append(close_sockets)
    return app


def _can_open_browser() -> bool:
    """False where webbrowser would take over the terminal with a text browser (Linux without
    a display)."""
    if sys.platform.startswith("linux"):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


def serve(scene: Scene, *, port: int = 0, open_browser: bool = True, name: str | None = None,
          size: tuple[int, int] | None = None, threads: int | None = None,
          draft_cells: int | None = None, out: TextIO | None = None) -> None:
    """Serves the viewer of ``scene`` on http://127.0.0.1:PORT (``port=0``: any free port)
    until Ctrl-C (SIGINT) or SIGTERM. Prints the page's URL, with its token, as the first line
    on ``out`` (stdout), and opens it in the browser when ``open_browser``."""
    out = out or sys.stdout
    kwargs: dict[str, Any] = {"size": size, "threads": threads, "name": name}
    if draft_cells is not None:
        kwargs["draft_cells"] = draft_cells
    ViewSession(scene, **kwargs)  # the options are checked before the server starts
    token = secrets.token_urlsafe(24)
    app = make_app(lambda: ViewSession(scene, **kwargs), token)
    try:
        asyncio.run(_serve(app, port, token, open_browser, out))
    finally:
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)  # stopping: a late Ctrl-C changes nothing


async def _serve(app, port: int, token: str, open_browser: bool, out: TextIO) -> None:
    from aiohttp import web

    runner = web.AppRunner(app, handle_signals=False, access_log=None)
    await runner.setup()
    site = web.TCPSite(runner, HOST, port, shutdown_timeout=1.0)
    await site.start()
    bound = runner.addresses[0][1]
    url = f"http://{HOST}:{bound}/?token={token}"
    out.write(url + "\n")
    out.flush()
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        try:
            loop.add_signal_handler(sig, stop.set)
        except (NotImplementedError, RuntimeError, ValueError):  # not the main thread
            pass
    if open_browser:
        if _can_open_browser():
            import webbrowser

            threading.Thread(target=webbrowser.open, args=(url,), daemon=True).start()
        else:
            sys.stderr.write("ndtrace view: no display to open a browser on: open the URL above\n")
    sys.stderr.write("ndtrace view: serving on 127.0.0.1 only; Ctrl-C stops\n")
    sys.stderr.flush()
    try:
        await stop.wait()
    finally:
        # A second Ctrl-C while the pages are closed ends the process at once.
        for sig in (signal.SIGINT, signal.SIGTERM):
            try:
                loop.add_signal_handler(sig, _forced_exit)
            except (NotImplementedError, RuntimeError, ValueError):
                pass
        # One signal stops it: the pages are closed (each within CLOSE_TIMEOUT, a page that
        # does not read is cut off), and a shutdown that still hangs is given up on.
        try:
            await asyncio.wait_for(runner.cleanup(), 4 * CLOSE_TIMEOUT)
        except (TimeoutError, asyncio.CancelledError, ConnectionError, RuntimeError):
            pass


def _forced_exit() -> None:
    sys.stderr.write("ndtrace view: stopped\n")
    sys.stderr.flush()
    os._exit(130)
