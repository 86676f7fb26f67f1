"""``ndtrace view`` as a server facing a hostile or broken page (issue 52): options checked the
same way for every dimension, messages limited in size and nesting, replies strictly JSON,
per-client bounded queues, websockets only from the page's own origin, and one signal stops
it even while a page does not read. A hypothesis property test feeds random message sequences
to a session and checks that every reply is valid JSON and that the session keeps working.
"""

from __future__ import annotations

import base64
import json
import math
import os
import re
import signal
import socket
import struct
import subprocess
import sys
import threading
import time

import numpy as np
import pytest

import ndtrace
from ndtrace.viewer import ViewSession
from ndtrace.viewer.server import MAX_QUEUED_MESSAGES, Outbox, encode_reply, session_replies
from ndtrace.viewer.session import MAX_MESSAGE_BYTES, MAX_NESTING, parse_message

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
URL = re.compile(r"^http://127\.0\.0\.1:(\d+)/\?token=([A-Za-z0-9_-]{20,})$")


def scene_of_dim(n: int, resolution: int = 6) -> ndtrace.Scene:
    return ndtrace.load_dict({
        "dim": n, "camera": {"position": [0.0] * (n - 1) + [4.0], "look_at": [0.0] * n, "fov": 50,
                             "up": [[1.0 if i == k + 1 else 0.0 for i in range(n)] for k in range(n - 2)],
                             "resolution": resolution},
        "objects": [{"shape": "hypercube" if n > 2 else "simplex"}],
        "lights": [{"type": "directional", "direction": [1.0] * n}]})


def strict(text: str):
    """``text`` parsed as strict JSON (NaN and Infinity refused, as the page's JSON.parse)."""
    def refuse(name):
        raise ValueError(f"{name} is not JSON")
    return json.loads(text, parse_constant=refuse)


# -- 1, 13. set: the same checks in every dimension, turntable refused ----------------------------

@pytest.mark.parametrize("n", [2, 3, 4, 5])
@pytest.mark.parametrize("options, match", [
    ({"opacity": float("nan")}, "opacity"),
    ({"zoom": float("inf")}, "zoom"),
    ({"mode": "bogus"}, "mode"),
    ({"turntable": 3600}, "turntable"),
    ({"size": [4, 4]}, "size"),
])
def test_set_refuses_bad_options_in_every_dimension(n, options, match):
    session = ViewSession(scene_of_dim(n), size=(64, 48))
    before = session.state()
    with pytest.raises(ValueError, match=match):
        session.handle({"type": "set", "options": options})
    assert session.state() == before
    strict(encode_reply(session.state()))


def test_a_2d_view_keeps_working_after_refused_options():
    session = ViewSession(scene_of_dim(2), size=(64, 48))
    for options in ({"opacity": float("nan")}, {"zoom": float("inf")}, {"mode": "bogus"}):
        replies, _ = session_replies(session, json.dumps({"type": "set", "options": options}))
        assert replies[0]["type"] == "error"
    meta, payload = session.render(session.snapshot(), "full", lambda: False)
    assert meta["type"] == "frame" and payload[:4] == b"\x89PNG"


# -- 10. nesting and size limits ----------------------------------------------------------------

def test_deep_or_long_messages_are_error_replies():
    session = ViewSession(scene_of_dim(3), size=(32, 32))
    for text in ("[" * 3000 + "]" * 3000, '{"type": "hello", "x": ' + "[" * 2000 + "]" * 2000 + "}",
                 '{"type": "roll", "steps": ' + json.dumps([[1, 1]] * 20000) + "}",
                 '{"type": "zoom", "factor": NaN}', "not json", "[1, 2]"):
        replies, frame = session_replies(session, text)
        assert len(replies) == 1 and replies[0]["type"] == "error" and frame is None, replies
        strict(encode_reply(replies[0]))
    with pytest.raises(ValueError, match=f"more than the {MAX_MESSAGE_BYTES} allowed"):
        parse_message("x" * (MAX_MESSAGE_BYTES + 1))
    with pytest.raises(ValueError, match=f"nested more than {MAX_NESTING} levels deep"):
        parse_message("[" * (MAX_NESTING + 1) + "]" * (MAX_NESTING + 1))
    # Brackets inside strings are not nesting.
    assert parse_message(json.dumps({"type": "hello", "text": "[" * 5000})) == {"type": "hello", "text": "[" * 5000}


def test_deep_toml_in_set_is_an_error_reply():
    session = ViewSession(scene_of_dim(4), size=(32, 32))
    aids = {a["name"]: a for a in session.aids}
    assert aids["cutaway"]["kind"] == "text"
    for text in ("[" * 3000 + "]" * 3000, "{ a = " * 3000 + "1" + " }" * 3000):
        replies, _ = session_replies(session, json.dumps({"type": "set", "options": {"cutaway": text}}))
        assert replies[0]["type"] == "error" and "nested more than" in replies[0]["message"], replies
    # The widget hands the session parsed messages: the same limit.
    deep: list = []
    for _ in range(100):
        deep = [deep]
    with pytest.raises(ValueError, match="nested more than"):
        session.handle({"type": "hello", "x": deep})


# -- 7. bounded queues per client --------------------------------------------------------------

def test_the_outbox_keeps_one_frame_and_overflows_at_its_limits():
    box = Outbox(max_messages=4, max_bytes=1000)
    assert box.put("a") and box.put(b"frame 1") and box.put(b"frame 2")
    assert len(box) == 2 and box.dropped_frames == 1  # the stale frame replaced
    assert box.put("b") and box.put("c")
    assert not box.put("d") and box.overflowing and len(box) == 0
    big = Outbox(max_messages=100, max_bytes=1000)
    assert big.put("x" * 600) and not big.put("y" * 600) and big.overflowing


# -- the server end to end: a raw websocket client that may stop reading -------------------------

def start_server(*args: str) -> tuple[subprocess.Popen, int, str]:
    proc = subprocess.Popen([sys.executable, "-m", "ndtrace", "view", *args, "--port", "0", "--no-browser"],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, PYTHONUNBUFFERED="1"))
    line = proc.stdout.readline().strip()
    m = URL.match(line)
    if not m:
        proc.kill()
        raise AssertionError(f"no URL: {line!r} {proc.stderr.read()}")
    return proc, int(m.group(1)), m.group(2)


def ws_connect(port: int, token: str, origin: str | None = None) -> tuple[socket.socket, bytes]:
    """A websocket handshake by hand (so that the client can stop reading): the socket and the
    response head."""
    s = socket.create_connection(("127.0.0.1", port), timeout=30)
    key = base64.b64encode(os.urandom(16)).decode()
    head = (f"GET /ws?token={token} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
            f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
            + (f"Origin: {origin}\r\n" if origin else "") + "\r\n")
    s.sendall(head.encode())
    response = b""
    while b"\r\n\r\n" not in response:
        chunk = s.recv(4096)
        if not chunk:
            break
        response += chunk
    return s, response


def ws_text(text: str) -> bytes:
    """A masked client text frame."""
    data = text.encode()
    mask = os.urandom(4)
    n = len(data)
    head = bytes([0x81]) + (bytes([0x80 | n]) if n < 126 else bytes([0x80 | 126]) + struct.pack(">H", n)
                            if n < 65536 else bytes([0x80 | 127]) + struct.pack(">Q", n))
    return head + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(data))


def ws_read(s: socket.socket, first: bytes = b"") -> tuple[int, bytes]:
    """One server frame (unmasked): (opcode, payload)."""
    buf = bytearray(first)

    def need(k):
        while len(buf) < k:
            chunk = s.recv(65536)
            if not chunk:
                raise ConnectionError("closed")
            buf.extend(chunk)

    need(2)
    op, n, at = buf[0] & 0x0F, buf[1] & 0x7F, 2
    if n == 126:
        need(4)
        n, at = struct.unpack(">H", buf[2:4])[0], 4
    elif n == 127:
        need(10)
        n, at = struct.unpack(">Q", buf[2:10])[0], 10
    need(at + n)
    return op, bytes(buf[at:at + n])


def ws_reply(s: socket.socket, first: bytes = b"", kind: str | None = None) -> dict:
    """The next text reply (skipping binary frames), or the next of ``kind``."""
    while True:
        op, payload = ws_read(s, first)
        first = b""
        if op == 1:
            reply = strict(payload.decode())
            if kind is None or reply["type"] == kind:
                return reply


@pytest.fixture
def server():
    proc, port, token = start_server(os.path.join(ROOT, "scenes", "tesseract.toml"), "--size", "96x96")
    yield proc, port, token
    if proc.poll() is None:
        proc.kill()
        proc.communicate(timeout=30)


def test_websockets_from_another_origin_are_refused(server):
    _, port, token = server
    s, head = ws_connect(port, token, origin="http://evil.example")
    assert head.startswith(b"HTTP/1.1 403"), head
    s.close()
    for origin in (None, f"http://127.0.0.1:{port}"):
        s, head = ws_connect(port, token, origin=origin)
        assert head.startswith(b"HTTP/1.1 101"), head
        s.close()


def test_deep_messages_get_an_error_reply_and_the_socket_keeps_working(server):
    _, port, token = server
    s, head = ws_connect(port, token)
    rest = head.split(b"\r\n\r\n", 1)[1]
    s.sendall(ws_text("[" * 2500 + "]" * 2500))
    reply = ws_reply(s, rest)
    assert reply["type"] == "error" and "nested more than" in reply["message"], reply
    s.sendall(ws_text(json.dumps({"type": "hello", "seq": 1})))
    assert ws_reply(s, kind="hello")["dim"] == 4
    s.close()


def test_one_sigint_stops_the_server_while_a_page_does_not_read():
    proc, port, token = start_server(os.path.join(ROOT, "scenes", "tesseract.toml"), "--size", "96x96")
    lines: list[str] = []
    reading = threading.Thread(target=lambda: lines.extend(proc.stderr), daemon=True)
    reading.start()
    try:
        s, head = ws_connect(port, token)
        assert head.startswith(b"HTTP/1.1 101")
        # Far more replies than the queue holds, never read: the server cuts this client off
        # instead of keeping them.
        message = ws_text(json.dumps({"type": "toml", "seq": 1}))
        try:
            for _ in range(4 * MAX_QUEUED_MESSAGES):
                s.sendall(message)
        except OSError:
            pass  # cut off already
        deadline = time.monotonic() + 60  # a hang check, generous
        while time.monotonic() < deadline and not any("did not read its replies" in line for line in lines):
            time.sleep(0.2)
        assert any("did not read its replies" in line for line in lines), lines
        # A second page that stops reading too, and then one SIGINT.
        s2, _ = ws_connect(port, token)
        s2.sendall(ws_text(json.dumps({"type": "hello", "seq": 1})))
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=60)  # a hang check, generous
        reading.join(10)
        err = "".join(lines)
        assert proc.returncode == 0, err
        assert "Traceback" not in err and "CancelledError" not in err, err
        s.close()
        s2.close()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


# -- the property test: random message sequences ----------------------------------------------

hypothesis = pytest.importorskip("hypothesis")
st = hypothesis.strategies

TYPES = ["hello", "roll", "arcball", "orbit", "zoom", "view", "set", "rotation", "snap", "reset",
         "release", "toml", "bogus", ""]
scalars = st.one_of(st.none(), st.booleans(), st.integers(-2**70, 2**70),
                    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=8))
values = st.recursive(scalars, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                       st.dictionaries(st.text(max_size=6), inner, max_size=4)),
                      max_leaves=12)
OPTION_KEYS = ["mode", "opacity", "zoom", "azimuth", "size", "turntable", "cutaway", "layout", "section",
               "stereo_angle", "depth_cue", "background", "threads", "edges", "crease_angle", "nope"]


@st.composite
def messages(draw):
    kind = draw(st.sampled_from(TYPES))
    msg: dict = {"type": kind}
    if draw(st.booleans()):
        msg["seq"] = draw(st.one_of(st.integers(-5, 10**6), scalars))
    if kind == "roll":
        msg["steps"] = draw(st.one_of(st.lists(st.lists(st.floats(-50, 50), min_size=2, max_size=2), max_size=4),
                                      values))
    elif kind in ("orbit", "arcball", "zoom", "view"):
        for key in ("dx", "dy", "x", "y", "factor", "azimuth", "elevation", "phase", "right"):
            if draw(st.booleans()):
                msg[key] = draw(st.one_of(st.floats(-100, 100), st.sampled_from(["press", "drag"]), scalars))
    elif kind == "set":
        msg["options"] = draw(st.one_of(st.dictionaries(st.sampled_from(OPTION_KEYS), values, max_size=3), values))
    elif kind == "rotation":
        msg["matrix"] = draw(st.one_of(values, st.just(np.eye(4).tolist())))
    else:
        msg.update(draw(st.dictionaries(st.text(max_size=5), values, max_size=2)))
    return msg


def raw_text(msg) -> str:
    try:
        return json.dumps(msg)  # NaN and Infinity as JSON's extensions: refused by the server
    except (ValueError, TypeError):
        return "{"


@hypothesis.settings(max_examples=60, deadline=None,
                     suppress_health_check=[hypothesis.HealthCheck.too_slow])
@hypothesis.given(st.lists(st.one_of(messages(), st.text(max_size=30).map(lambda t: ("raw", t))),
                           min_size=1, max_size=12))
def test_random_message_sequences_get_json_replies_and_the_session_keeps_working(sequence):
    session = ViewSession(SESSION_SCENE, size=(24, 24))
    for item in sequence:
        text = item[1] if isinstance(item, tuple) else raw_text(item)
        replies, frame = session_replies(session, text)
        assert frame in (None, "draft", "now", "release")
        for reply in replies:
            parsed = strict(encode_reply(reply))
            assert isinstance(parsed, dict) and isinstance(parsed.get("type"), str)
        strict(encode_reply(session.state()))
    # Still working: a hello is answered and a frame renders.
    replies, _ = session_replies(session, json.dumps({"type": "hello", "seq": 7}))
    assert replies[0]["type"] == "hello"
    meta, payload = session.render(session.snapshot(), "draft", lambda: False)
    assert meta["type"] == "frame" and len(payload) > 0
    assert all(math.isfinite(x) for row in session.rotation.tolist() for x in row)


SESSION_SCENE = scene_of_dim(4, resolution=4)
