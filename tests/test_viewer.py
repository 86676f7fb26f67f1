"""``ndtrace view``: the server as a user starts it, and the page in headless Chromium.

One server process (``ndtrace view scenes/tesseract.toml --port 0 --no-browser``) serves the
module: its URL is the first line on stdout, requests without the token get 403, it listens on
127.0.0.1 only, and Ctrl-C stops it cleanly. The page is driven with real mouse input through
selenium and Debian's chromium + chromium-driver (``.ci/browser-deps`` installs them; without
them the browser tests skip locally and fail under CI).
"""

from __future__ import annotations

import io
import json
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from ndtrace import rotation as rot

ROOT = Path(__file__).resolve().parents[1]
URL = re.compile(r"^http://127\.0\.0\.1:(\d+)/\?token=([A-Za-z0-9_-]{20,})$")


def ndtrace_command() -> list[str]:
    """The ``ndtrace`` command installed beside this Python, else ``python -m ndtrace``."""
    script = Path(sys.executable).with_name("ndtrace")
    return [str(script)] if script.exists() else [sys.executable, "-m", "ndtrace"]


def start_server(*args: str) -> tuple[subprocess.Popen, str]:
    proc = subprocess.Popen(
        [*ndtrace_command(), "view", *args, "--port", "0", "--no-browser"],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env=dict(os.environ, PYTHONUNBUFFERED="1"))
    line = proc.stdout.readline().strip()
    if not URL.match(line):
        proc.kill()
        raise AssertionError(f"first stdout line {line!r} is not the page's URL; stderr: {proc.stderr.read()}")
    return proc, line


def stop_server(proc: subprocess.Popen, interrupt: bool = True) -> tuple[int, str]:
    if interrupt and proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=15)
    except subprocess.TimeoutExpired:
        proc.kill()
        raise AssertionError("ndtrace view did not stop within 15 s of Ctrl-C") from None
    return proc.returncode, err


@pytest.fixture(scope="module")
def server():
    proc, url = start_server("scenes/tesseract.toml")
    yield proc, url
    if proc.poll() is None:
        stop_server(proc)


def status(url: str) -> int:
    try:
        with urllib.request.urlopen(url, timeout=10) as r:
            return r.status
    except urllib.error.HTTPError as e:
        return e.code


def test_every_request_needs_the_token(server):
    _, url = server
    port, token = URL.match(url).groups()
    base = f"http://127.0.0.1:{port}"
    assert status(url) == 200
    with urllib.request.urlopen(url, timeout=10) as r:
        page = r.read().decode()
    assert "window.ndtraceViewer" in page and "export function mount" in page
    assert "http://" not in page.replace("http://127", "")  # no CDN: everything is inline
    for path in ["/", "/?token=", f"/?token={token[:-1]}", f"/?token={token}x", "/ws",
                 f"/ws?token={token[::-1]}", "/favicon.ico", "/static/viewer.js", "/../etc/passwd"]:
        assert status(base + path) == 403, path
    assert status(f"{base}/nothing?token={token}") == 404


def listening_addresses(port: int) -> list[str]:
    """The local addresses of sockets listening on ``port`` (from /proc/net/tcp and tcp6)."""
    out = []
    for name in ("tcp", "tcp6"):
        path = Path("/proc/net") / name
        if not path.exists():
            continue
        for line in path.read_text().splitlines()[1:]:
            fields = line.split()
            local, state = fields[1], fields[3]
            addr, p = local.split(":")
            if state == "0A" and int(p, 16) == port:  # 0A = LISTEN
                out.append(addr)
    return out


def other_addresses() -> list[str]:
    """This machine's IPv4 addresses outside the loopback range."""
    found = set()
    try:
        for info in socket.getaddrinfo(socket.gethostname(), None, socket.AF_INET):
            found.add(info[4][0])
    except OSError:
        pass
    try:
        s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        s.connect(("192.0.2.1", 9))  # no packet is sent: this only picks the outgoing interface
        found.add(s.getsockname()[0])
        s.close()
    except OSError:
        pass
    return sorted(a for a in found if not a.startswith("127."))


@pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="needs Linux's /proc/net/tcp")
def test_the_server_listens_on_loopback_only(server):
    _, url = server
    port = int(URL.match(url).group(1))
    assert listening_addresses(port) == ["0100007F"]  # 127.0.0.1, and nothing on 0.0.0.0 or ::
    for addr in other_addresses():
        with socket.socket() as s:
            s.settimeout(2)
            assert s.connect_ex((addr, port)) != 0, f"port {port} answers on {addr}"


def test_bad_arguments_are_one_line_errors(capsys, monkeypatch):
    r = subprocess.run([sys.executable, "-m", "ndtrace", "view", "scenes/nothing.toml", "--no-browser"],
                       cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert (r.returncode, r.stdout) == (2, "")
    assert r.stderr == "ndtrace view: error: scenes/nothing.toml: no such file\n"
    from ndtrace.viewer.cli import main

    monkeypatch.chdir(ROOT)
    for args, match in [
        (["scenes/tesseract.toml", "--port", "70000"], "--port: expected 0"),
        (["scenes/tesseract.toml", "--size", "3x"], "--size"),
        (["scenes/tesseract.toml", "--threads", "0"], "--threads: must be at least 1"),
        (["scenes/tesseract.toml", "--set", "camera.fov=400"], "camera.fov"),
        (["scenes/cube.py"], "no such file"),
    ]:
        assert main([*args, "--no-browser"]) == 2
        out, err = capsys.readouterr()
        assert out == "" and err.startswith("ndtrace view: error: ") and match in err, err
        assert "Traceback" not in err and err.count("\n") == 1


def test_ctrl_c_stops_the_server_cleanly():
    """With a page connected and frames coming: the socket is closed, the process exits 0."""
    import asyncio

    from aiohttp import ClientSession, WSMsgType

    proc, url = start_server("scenes/cube.toml")
    assert status(url) == 200

    async def connected() -> tuple[str, object]:
        async with ClientSession() as client:
            async with client.ws_connect(url.replace("/?", "/ws?")) as ws:
                await ws.send_str(json.dumps({"type": "hello", "seq": 1}))
                hello = json.loads((await ws.receive()).data)
                while (msg := await ws.receive()).type != WSMsgType.BINARY:  # the first frame
                    pass
                n = int.from_bytes(msg.data[:4], "little")
                meta = json.loads(msg.data[4:4 + n])
                image = Image.open(io.BytesIO(msg.data[4 + n:]))
                assert meta["type"] == "frame" and image.format == meta["format"].upper()
                assert image.size == (meta["width"], meta["height"]) and meta["ms"] > 0
                await ws.send_str(json.dumps({"type": "roll", "seq": 2, "steps": [[5, 5]]}))
                proc.send_signal(signal.SIGINT)
                while True:
                    msg = await asyncio.wait_for(ws.receive(), 15)
                    if msg.type in (WSMsgType.CLOSE, WSMsgType.CLOSED, WSMsgType.CLOSING):
                        return hello["type"], msg.type

    kind, closed = asyncio.run(connected())
    assert kind == "hello"
    code, err = stop_server(proc, interrupt=False)  # the one Ctrl-C above
    assert code == 0, err
    assert "Traceback" not in err and "stopped" in err


def test_a_second_ctrl_c_still_ends_it_quietly():
    proc, url = start_server("scenes/cube.toml")
    proc.send_signal(signal.SIGINT)
    time.sleep(0.05)
    code, err = stop_server(proc)
    assert code in (0, 130), err
    assert "Traceback" not in err and err.rstrip().endswith("stopped")


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_port_and_opening_the_browser(tmp_path):
    """``--port N`` serves on N; without ``--no-browser`` the printed URL (the first stdout line)
    is opened in the user's browser (``$BROWSER``, as Python's webbrowser reads it; a stand-in
    script here), with ``--no-browser`` nothing is opened."""
    opened = tmp_path / "opened.txt"
    fake = tmp_path / "browser"
    fake.write_text(f'#!/bin/sh\necho "$1" >> {opened}\n')
    fake.chmod(0o755)
    env = dict(os.environ, PYTHONUNBUFFERED="1", BROWSER=str(fake), DISPLAY=os.environ.get("DISPLAY") or ":0")

    def run(*extra: str) -> str:
        port = free_port()
        proc = subprocess.Popen([*ndtrace_command(), "view", "scenes/cube.toml", "--port", str(port), *extra],
                                cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        url = proc.stdout.readline().strip()
        try:
            assert URL.match(url) and URL.match(url).group(1) == str(port), url
            assert status(url) == 200
            end = time.monotonic() + (0.5 if extra else 15)  # --no-browser: it would have started by now
            while not (opened.exists() and opened.read_text().endswith("\n")) and time.monotonic() < end:
                time.sleep(0.05)
        finally:
            code, err = stop_server(proc)
        assert code == 0, err
        return url

    url = run()
    assert opened.read_text() == url + "\n"
    run("--no-browser")
    assert opened.read_text() == url + "\n"  # opened once, by the first server only


# -- the page in headless Chromium ---------------------------------------------------------------

def browser():
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver")
    missing = []
    try:
        import selenium  # noqa: F401
    except ImportError:
        missing.append("selenium (pip install selenium)")
    if not chromium or not driver:
        missing.append("Debian's chromium and chromium-driver (.ci/browser-deps installs them)")
    if missing:
        reason = "the page test needs " + " and ".join(missing)
        if os.environ.get("CI"):
            pytest.fail(reason + ": CI must install them")
        pytest.skip(reason)
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 "--window-size=1280,860", "--force-device-scale-factor=1"):
        options.add_argument(flag)
    return webdriver.Chrome(service=Service(executable_path=driver), options=options)


@pytest.fixture(scope="module")
def chrome():
    driver = browser()
    try:
        driver.set_script_timeout(20)
        yield driver
    finally:
        driver.quit()


def open_page(driver, url: str):
    driver.get(url)
    wait(driver, "return window.ndtraceViewer && window.ndtraceViewer.frames >= 1", 30)
    return driver


@pytest.fixture
def page(server, chrome):
    """The tesseract's page (opened again if a test showed another scene)."""
    if chrome.current_url != server[1]:
        open_page(chrome, server[1])
    return chrome


def wait(driver, script: str, timeout: float = 20.0):
    end = time.monotonic() + timeout
    while True:
        value = driver.execute_script(script)
        if value:
            return value
        if time.monotonic() > end:
            logs = driver.execute_script("return document.body.innerText.slice(0, 2000)")
            raise AssertionError(f"timed out waiting for: {script}\npage: {logs}")
        time.sleep(0.05)


def viewer_state(driver) -> dict:
    return driver.execute_script("return JSON.parse(JSON.stringify(window.ndtraceViewer))")


def settled(driver, frames_before: int) -> dict:
    """Waits until every input sent was applied and a new full frame was drawn after it."""
    wait(driver, f"const v = window.ndtraceViewer; return v.acked === v.sent && v.frames > {frames_before}"
                 " && v.quality === 'full'")
    return viewer_state(driver)


def canvas_scale(driver) -> tuple[float, float, float]:
    """(picture pixels per CSS pixel, picture width, picture height) of the canvas."""
    w, h, css = driver.execute_script(
        "const c = document.querySelector('canvas'); return [c.width, c.height, c.getBoundingClientRect().width]")
    return w / css, w, h


def test_the_page_draws_frames(page):
    v = viewer_state(page)
    assert v["frames"] >= 1 and v["lastFrameMs"] > 0
    assert v["rotation"] == np.eye(4).tolist()
    title = page.execute_script("return document.querySelector('.ndv-scene').textContent")
    assert "tesseract.toml" in title and "4D" in title


def test_a_drag_is_the_rolling_ball(page):
    """Real mouse moves (one pointer event per step) across the canvas: the rotation the page
    holds is M_k ⋯ M_1 with M_i = rolling_ball((dx_i, −dy_i, 0), R) of each step in picture
    pixels, R half the picture's side; orthonormal with det +1."""
    from selenium.webdriver.common.action_chains import ActionChains

    canvas = page.find_element("css selector", "canvas")
    scale, w, h = canvas_scale(page)
    before = viewer_state(page)
    steps = [(40, 0), (0, 30), (-25, -10), (15, 22), (-60, 5)]
    chain = ActionChains(page, duration=0).move_to_element(canvas).click_and_hold()
    for dx, dy in steps:
        chain = chain.pause(0.06).move_by_offset(dx, dy)
    chain.pause(0.06).release().perform()
    after = settled(page, before["frames"])
    got = np.array(after["rotation"])
    want = np.eye(4)
    for dx, dy in steps:
        want = rot.rolling_ball([dx * scale, -dy * scale, 0.0], radius=min(w, h) / 2) @ want
    assert got.shape == (4, 4)
    np.testing.assert_allclose(got.T @ got, np.eye(4), atol=1e-12)
    assert abs(np.linalg.det(got) - 1) < 1e-12
    np.testing.assert_allclose(got, want, atol=1e-9)
    assert not np.allclose(got, np.eye(4), atol=0.1)
    assert after["frames"] > before["frames"] and after["lastFrameMs"] > 0
    matrix = page.execute_script("return document.querySelector('.ndv-matrix').value")
    assert np.allclose(np.array([[float(v) for v in row.split()] for row in matrix.splitlines()]), got, atol=1e-4)


def test_shift_drag_orbits_and_the_wheel_zooms_without_turning_the_object(page):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.actions.wheel_input import ScrollOrigin
    from selenium.webdriver.common.keys import Keys

    canvas = page.find_element("css selector", "canvas")
    scale, _, _ = canvas_scale(page)
    before = viewer_state(page)
    (ActionChains(page, duration=0).move_to_element(canvas).key_down(Keys.SHIFT).click_and_hold()
     .pause(0.06).move_by_offset(50, 0).pause(0.06).move_by_offset(0, -20).pause(0.06).release()
     .key_up(Keys.SHIFT).perform())
    after = settled(page, before["frames"])
    assert after["rotation"] == before["rotation"]
    az0 = before["options"].get("azimuth", 30)
    el0 = before["options"].get("elevation", 20)
    assert after["options"]["azimuth"] == pytest.approx(az0 + 50 * scale * 0.4)
    assert after["options"]["elevation"] == pytest.approx(el0 - 20 * scale * 0.4)
    ActionChains(page).scroll_from_origin(ScrollOrigin.from_element(canvas), 0, -200).perform()
    zoomed = settled(page, after["frames"])
    assert zoomed["options"]["zoom"] > 1.0
    assert zoomed["rotation"] == before["rotation"]


def test_keys_and_buttons(page):
    before = viewer_state(page)
    page.find_element("css selector", "canvas").send_keys("s")  # snap to the nearest axis view
    snapped = settled(page, before["frames"])
    r = np.array(snapped["rotation"])
    assert np.array_equal(np.abs(r).sum(axis=0), np.ones(4)) and np.linalg.det(r) == pytest.approx(1)
    modes = page.execute_script("return [...document.querySelectorAll('.ndv-mode option')].map(o => o.value)")
    assert "mip" in modes and "volume" in modes
    page.execute_script("const s = document.querySelector('.ndv-mode'); s.value = 'mip'; s.dispatchEvent(new Event('change'))")
    chosen = settled(page, snapped["frames"])
    assert chosen["options"]["mode"] == "mip"
    canvas = page.find_element("css selector", "canvas")
    canvas.send_keys("m")  # the next mode of the list (after the last: the default again)
    stepped = settled(page, chosen["frames"])
    following = modes[(modes.index("mip") + 1) % len(modes)]
    assert stepped["options"].get("mode") == (following or None)
    opacity = stepped["options"].get("opacity", 1.0)
    canvas.send_keys("]")  # opacity × 1.25, 3 digits
    brighter = settled(page, stepped["frames"])
    assert brighter["options"]["opacity"] == pytest.approx(min(2.0, opacity * 1.25), rel=1e-3)
    canvas.send_keys("[")
    dimmer = settled(page, brighter["frames"])
    assert dimmer["options"]["opacity"] == pytest.approx(brighter["options"]["opacity"] / 1.25, rel=1e-3)
    page.execute_script("const o = document.querySelector('.ndv-opacity'); o.value = 500; o.dispatchEvent(new Event('input'))")
    slid = settled(page, dimmer["frames"])  # the slider is logarithmic: 0.01 … 2, half way √(0.01·2)
    assert slid["options"]["opacity"] == pytest.approx(0.141)
    page.execute_script("const s = document.querySelector('.ndv-mode'); s.value = 'mip'; s.dispatchEvent(new Event('change'))")
    chosen = settled(page, slid["frames"])
    page.execute_script("[...document.querySelectorAll('.ndv-btn')].find(b => b.textContent.startsWith('Reset')).click()")
    reset = settled(page, chosen["frames"])
    assert reset["rotation"] == np.eye(4).tolist() and "mode" not in reset["options"]
    page.execute_script("window.__toml = null; navigator.clipboard.writeText = async (t) => { window.__toml = t; };")
    page.find_element("css selector", "canvas").send_keys("c")
    text = wait(page, "return window.__toml || document.querySelector('.ndv-toml').value")
    import ndtrace

    scene = ndtrace.load_toml(text)
    assert scene.dim == 4 and scene.to_dict()["objects"][0]["transform"][-1]["matrix"] is not None


def test_a_bad_matrix_is_refused_with_a_message(page):
    before = viewer_state(page)
    page.execute_script("const m = document.querySelector('.ndv-matrix'); m.value = '1 0 0\\n0 1 0\\n0 0 1';"
                        "[...document.querySelectorAll('.ndv-btn')].find(b => b.textContent === 'Apply').click()")
    wait(page, "const v = window.ndtraceViewer; return v.acked === v.sent")
    text = wait(page, "const m = document.querySelector('.ndv-message'); return !m.hidden && m.textContent")
    assert "rotation: expected a 4×4 matrix" in text
    assert viewer_state(page)["rotation"] == before["rotation"]
    shown = page.execute_script("return document.querySelector('.ndv-matrix').value")
    assert len(shown.splitlines()) == 4  # the field shows the current rotation again


SPY = """
window.__points = [];
const c = document.querySelector('canvas');
const record = (e) => { const r = c.getBoundingClientRect();
  window.__points.push([(e.clientX - r.left) * c.width / r.width, (e.clientY - r.top) * c.height / r.height]); };
c.addEventListener('pointerdown', record);
c.addEventListener('pointermove', (e) => (e.getCoalescedEvents().length ? e.getCoalescedEvents() : [e]).forEach(record));
"""


def test_the_4d_arcball_mode(page):
    """In arcball mode a drag is arcball_4d from the press point to the last point (Shoemake's
    sphere on the picture's disk, quaternion scalar = w), applied to the rotation at the press;
    ctrl-drag is the right factor."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.keys import Keys

    from ndtrace.viewer import controls

    canvas = page.find_element("css selector", "canvas")
    page.execute_script(SPY)
    page.execute_script("[...document.querySelectorAll('.ndv-seg')].find(b => b.textContent === '4D arcball').click()")
    _, w, h = canvas_scale(page)
    for right in (False, True):
        before = viewer_state(page)
        page.execute_script("window.__points = []")
        chain = ActionChains(page, duration=0).move_to_element_with_offset(canvas, -30, 20)
        if right:
            chain = chain.key_down(Keys.CONTROL)
        chain = chain.click_and_hold()
        for dx, dy in [(25, -10), (30, -15), (10, 40)]:
            chain = chain.pause(0.06).move_by_offset(dx, dy)
        chain = chain.pause(0.06).release()
        if right:
            chain = chain.key_up(Keys.CONTROL)
        chain.perform()
        after = settled(page, before["frames"])
        points = page.execute_script("return window.__points")
        a0 = controls.arcball_point(*points[0], w, h)
        a1 = controls.arcball_point(*points[-1], w, h)
        np.testing.assert_allclose(np.array(after["rotation"]),
                                   controls.arcball(np.array(before["rotation"]), a0, a1, right=right), atol=1e-9)
        assert not np.allclose(after["rotation"], before["rotation"], atol=0.05)
    page.execute_script("[...document.querySelectorAll('.ndv-seg')].find(b => b.textContent === 'Rolling ball').click()")


def cube_scene(n: int, path: Path) -> Path:
    up = [[1.0 if j == k else 0.0 for j in range(n)] for k in range(1, n - 1)]
    lines = [f"dim = {n}", "[camera]", f"position = {[0.3] * (n - 1) + [4.5]}", f"look_at = {[0] * n}",
             f"up = {up if n > 3 else up[0]}", "fov = 50", f"resolution = {64 if n == 3 else 8}",
             "[[lights]]", 'type = "directional"', f"direction = {[0.4] * (n - 1) + [1.0]}",
             "[[objects]]", 'shape = "hypercube"', "[composite]", "size = [256, 256]"]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(scope="module")
def cube_servers(tmp_path_factory):
    """Servers of hypercubes in 3, 5 and 6 dimensions, started together."""
    folder = tmp_path_factory.mktemp("cubes")
    procs = {n: subprocess.Popen(
        [sys.executable, "-m", "ndtrace", "view", str(cube_scene(n, folder / f"cube{n}.toml")), "--port", "0",
         "--no-browser"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for n in (3, 5, 6)}
    urls = {n: p.stdout.readline().strip() for n, p in procs.items()}
    yield urls
    for p in procs.values():
        stop_server(p)


@pytest.mark.parametrize("n", [3, 5, 6])
def test_a_drag_along_x_turns_the_x_and_last_axes_in_every_dimension(n, chrome, cube_servers):
    """N = 3, 5, 6: a drag along the picture's x turns the plane (x, N−1) only, by atan(dx/R)."""
    from selenium.webdriver.common.action_chains import ActionChains

    url = cube_servers[n]
    assert URL.match(url), url
    open_page(chrome, url)
    canvas = chrome.find_element("css selector", "canvas")
    scale, w, h = canvas_scale(chrome)
    before = viewer_state(chrome)
    (ActionChains(chrome, duration=0).move_to_element(canvas).click_and_hold().pause(0.06)
     .move_by_offset(35, 0).pause(0.06).release().perform())
    after = settled(chrome, before["frames"])
    want = rot.plane(n, n - 1, 0, np.arctan(35 * scale / (min(w, h) / 2)))
    np.testing.assert_allclose(np.array(after["rotation"]), want, atol=1e-9)
    hint = chrome.execute_script("return document.querySelector('.ndv-hint').textContent")
    assert hint.startswith("drag: turn x–z / y–z" if n == 3 else f"drag: turn x0–x{n - 1} / x1–x{n - 1}")
    assert chrome.execute_script("return document.querySelector('.ndv-mode').closest('section').hidden") == (n == 3)


def test_the_widget_runs_the_same_viewer_js(chrome):
    """ndtrace.widget's ES module under a stand-in for anywidget's model: render() mounts the
    viewer, which asks for hello, and draws a frame that arrives as a DataView buffer."""
    pytest.importorskip("anywidget")
    import base64

    import ndtrace
    from ndtrace.viewer.session import ViewSession
    from ndtrace.viewer.widget import widget_esm
    from ndtrace.viewer.worker import FULL

    session = ViewSession(ndtrace.load_file(ROOT / "scenes" / "tesseract.toml"), size=(64, 64))
    session.resolution = [8, 8, 8]
    session._desc["camera"] = dict(session._desc["camera"], resolution=8)
    hello = session.hello()
    # Display aids as a composite with these keywords would offer them (session.display_aids).
    hello["aids"] = [{"name": "fit", "kind": "bool", "default": True, "hint": "bool"},
                     {"name": "sections", "kind": "number", "default": 0, "hint": "int"},
                     {"name": "layout", "kind": "choice", "default": "volume", "choices": ["volume", "sections"], "hint": ""},
                     {"name": "cutaway", "kind": "text", "default": None, "hint": "dict | None"}]
    meta, png = session.render(session.snapshot(), FULL, lambda: False)
    chrome.get("about:blank")
    result = chrome.execute_async_script("""
        const [esm, hello, meta, png, done] = arguments;
        const handlers = [], sent = [];
        const model = { send: (m) => sent.push(m), on: (name, f) => handlers.push([name, f]) };
        const url = URL.createObjectURL(new Blob([esm], { type: "text/javascript" }));
        import(url).then(async (mod) => {
          mod.default.render({ model, el: document.body });
          const bytes = Uint8Array.from(atob(png), (c) => c.charCodeAt(0));
          for (const [name, f] of handlers) {
            f(hello, []);
            f(meta, [new DataView(bytes.buffer)]);
          }
          const end = Date.now() + 10000;
          while (window.ndtraceViewer.frames < 1 && Date.now() < end) await new Promise((r) => setTimeout(r, 20));
          const aid = (name) => document.querySelector(`[data-aid="${name}"]`);
          const aids = ["fit", "sections", "layout", "cutaway"].map((n) => [n, aid(n).tagName, aid(n).type, aid(n).checked ?? null, aid(n).value]);
          aid("fit").click();
          aid("sections").value = "3"; aid("sections").dispatchEvent(new Event("change"));
          aid("layout").value = "sections"; aid("layout").dispatchEvent(new Event("change"));
          aid("cutaway").value = "{ plane = [0, 0, 1] }"; aid("cutaway").dispatchEvent(new Event("change"));
          done({ names: handlers.map((h) => h[0]), sent, aids, viewer: window.ndtraceViewer,
                 title: document.querySelector(".ndv-scene").textContent });
        }).catch((e) => done({ error: String(e) }));
    """, widget_esm(), hello, meta, base64.b64encode(png).decode())
    assert "error" not in result, result
    assert result["names"] == ["msg:custom"]
    assert result["sent"][0] == {"type": "hello", "seq": 1}
    assert result["viewer"]["frames"] == 1 and result["viewer"]["lastFrameMs"] == meta["ms"]
    assert result["viewer"]["rotation"] == np.eye(4).tolist() and "4D" in result["title"]
    assert result["aids"] == [["fit", "INPUT", "checkbox", True, "on"], ["sections", "INPUT", "number", False, "0"],
                              ["layout", "SELECT", "select-one", None, "volume"], ["cutaway", "INPUT", "text", False, ""]]
    assert [m["options"] for m in result["sent"] if m["type"] == "set"] == [
        {"fit": False}, {"sections": 3}, {"layout": "sections"}, {"cutaway": "{ plane = [0, 0, 1] }"}]


def test_screenshot_shows_the_viewer(page, tmp_path):
    path = tmp_path / "viewer.png"
    page.save_screenshot(str(path))
    image = np.asarray(Image.open(path).convert("RGB"))
    x0, y0, w, h = page.execute_script(
        "const r = document.querySelector('canvas').getBoundingClientRect(); return [r.left, r.top, r.width, r.height]")
    inside = image[int(y0):int(y0 + h), int(x0):int(x0 + w)]
    # The tesseract is drawn: the canvas is not just its background.
    assert (inside.astype(int).sum(axis=-1) > 120).mean() > 0.02
    print(json.dumps({"screenshot": str(path)}))
