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
import hmac
import json
import os
import secrets
import signal
import sys
import threading
import weakref
from collections.abc import Callable
from importlib import resources
from typing import Any, TextIO

from ..scene import Scene
from .session import ViewSession
from .worker import FrameWorker

__all__ = ["HOST", "page_html", "frame_message", "dispatch", "make_app", "serve"]

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
    header = json.dumps(meta).encode()
    return len(header).to_bytes(4, "little") + header + payload


def dispatch(worker: FrameWorker, session: ViewSession, frame: str | None) -> None:
    """Passes the frame a message asked for (:meth:`ViewSession.handle`) to the worker."""
    if frame in ("draft", "now"):
        worker.request(session.snapshot())
    if frame in ("now", "release"):
        worker.release()


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

    sockets: weakref.WeakSet = weakref.WeakSet()

    async def socket(request: web.Request) -> web.WebSocketResponse:
        ws = web.WebSocketResponse(heartbeat=30.0, max_msg_size=1 << 20)
        await ws.prepare(request)
        sockets.add(ws)
        loop = asyncio.get_running_loop()
        outbox: asyncio.Queue = asyncio.Queue()

        def emit(meta: dict, payload: bytes | None) -> None:  # from the worker thread
            if meta.get("type") == "error":  # a frame failed: the terminal hears of it too
                sys.stderr.write(f"ndtrace view: a frame failed: {meta['message']}\n")
            try:
                loop.call_soon_threadsafe(outbox.put_nowait, (meta, payload))
            except RuntimeError:  # the loop has closed: the page is gone
                pass

        session = make_session()
        worker = FrameWorker(session.render, emit)

        async def sender() -> None:
            while True:
                meta, payload = await outbox.get()
                if payload is None:
                    await ws.send_str(json.dumps(meta))
                else:
                    await ws.send_bytes(frame_message(meta, payload))

        sending = asyncio.create_task(sender())
        try:
            async for msg in ws:
                if msg.type != WSMsgType.TEXT:
                    continue
                data = None
                try:
                    data = json.loads(msg.data)
                    reply, frame = session.handle(data)
                except ValueError as e:  # json.JSONDecodeError is a ValueError
                    seq = data.get("seq") if isinstance(data, dict) else None
                    outbox.put_nowait(({"type": "error", "seq": seq, "message": str(e)}, None))
                    continue
                if reply is not None:
                    outbox.put_nowait((reply, None))
                dispatch(worker, session, frame)
        finally:
            worker.close(timeout=0)
            sending.cancel()
            session.close()
        return ws

    async def close_sockets(app) -> None:
        for ws in list(sockets):
            await ws.close(code=1001, message=b"ndtrace view stopped")

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
        await runner.cleanup()


def _forced_exit() -> None:
    sys.stderr.write("ndtrace view: stopped\n")
    sys.stderr.flush()
    os._exit(130)
