"""Tests of the viewer's controllers, view session and frame worker (``ndtrace.viewer``):
the mouse mappings against the course's formulas written independently here (plane rotations,
quaternion products), the session's messages and frames, and the worker's rule that inputs
supersede frames instead of queueing behind them. The page itself is tested in
test_viewer.py."""

from __future__ import annotations

import io
import itertools
import math
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy.stats import special_ortho_group

import ndtrace
from ndtrace import rotation as rot
from ndtrace.viewer import controls
from ndtrace.viewer.session import DRAFT_CELLS, ViewSession, display_aids, draft_resolution
from ndtrace.viewer.worker import DRAFT, FULL, FrameWorker, Superseded

SCENES = Path(__file__).resolve().parents[1] / "scenes"
DIMS = [3, 4, 5, 6]


def assert_rotation(m, tol=1e-12):
    n = m.shape[0]
    np.testing.assert_allclose(m.T @ m, np.eye(n), atol=tol)
    assert abs(np.linalg.det(m) - 1) < tol


def qmul(a, b):
    """Quaternion product (scalar first), written out."""
    a0, a1, a2, a3 = a
    b0, b1, b2, b3 = b
    return np.array([a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3, a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                     a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1, a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0])


def qconj(q):
    return np.array([q[0], -q[1], -q[2], -q[3]])


def scene_of_dim(n: int) -> ndtrace.Scene:
    up = [list(np.eye(n)[k]) for k in range(1, n - 1)]
    return (ndtrace.Scene(n)
            .set_camera([0] * (n - 1) + [4.0], look_at=[0] * n, up=up if n > 3 else up[0], fov=45,
                        resolution=12 if n <= 4 else 6)
            .add_light("directional", direction=[0.3] * (n - 1) + [1.0])
            .add_object("hypercube", material={"color": [0.9, 0.6, 0.3]}))


# -- the rolling ball -----------------------------------------------------------------------

@pytest.mark.parametrize("n", DIMS)
def test_roll_along_x_and_y_turns_the_last_axis_toward_the_drag(n):
    """A drag along the picture's x is the plane rotation R_{N−1,0}(atan(dx/R)) (the hidden
    axis toward +x); a drag down the picture (+dy) turns it toward −y (picture y points down).
    Only the planes (x, N−1) and (y, N−1) move."""
    radius = 256.0
    for dx in (3.0, -40.0, 300.0):
        m = controls.roll(np.eye(n), [(dx, 0.0)], radius)
        np.testing.assert_allclose(m, rot.plane(n, n - 1, 0, math.atan(dx / radius)), atol=1e-14)
    for dy in (5.0, -120.0):
        m = controls.roll(np.eye(n), [(0.0, dy)], radius)
        np.testing.assert_allclose(m, rot.plane(n, n - 1, 1, -math.atan(dy / radius)), atol=1e-14)
    m = controls.roll(np.eye(n), [(17.0, -9.0)], radius)
    still = [k for k in range(n) if k not in (0, 1, n - 1)]
    for k in still:
        np.testing.assert_array_equal(m[:, k], np.eye(n)[k])


@pytest.mark.parametrize("n", DIMS)
def test_roll_composes_each_step_after_the_rotation_so_far(n):
    rng = np.random.default_rng(n)
    start = special_ortho_group.rvs(n, random_state=n)
    steps = rng.normal(scale=30, size=(7, 2))
    got = controls.roll(start, steps.tolist(), 200.0)
    want = start
    for dx, dy in steps:
        d = np.zeros(n - 1)
        d[0], d[1] = dx, -dy
        want = rot.rolling_ball(d, radius=200.0) @ want
    np.testing.assert_allclose(got, want, atol=1e-12)
    assert_rotation(got)


@pytest.mark.parametrize("n", DIMS)
def test_a_small_counterclockwise_loop_turns_the_object_clockwise(n):
    """The commutator (course, Part I(B)): a loop right, up, left, down on the screen (area h²)
    turns the object by −h²/R² in its (x, y) plane, to second order."""
    radius, h = 100.0, 1.0
    loop = [(h, 0.0), (0.0, -h), (-h, 0.0), (0.0, h)]  # screen y points down: this is counterclockwise
    m = controls.roll(np.eye(n), loop, radius)
    want = rot.plane(n, 0, 1, -(h / radius) ** 2)
    np.testing.assert_allclose(m, want, atol=3 * (h / radius) ** 3)
    assert m[1, 0] < 0  # y turned toward x: clockwise on the screen


# -- the 4D arcball ------------------------------------------------------------------------

def test_arcball_point_is_shoemakes_sphere():
    a = controls.arcball_point(256, 256, 512, 512)
    np.testing.assert_allclose(a, [0, 0, 0, 1])
    a = controls.arcball_point(256 + 128, 256 - 128, 512, 512)  # right and up
    np.testing.assert_allclose(a, [0, 0.5, 0.5, math.sqrt(0.5)])
    a = controls.arcball_point(512 + 300, 256, 512, 512)  # outside: on the rim
    np.testing.assert_allclose(a, [0, 1, 0, 0])
    for x, y in np.random.default_rng(1).uniform(-100, 600, size=(20, 2)):
        assert abs(np.linalg.norm(controls.arcball_point(x, y, 512, 300)) - 1) < 1e-14


def test_arcball_factors_are_quaternion_multiplications():
    """Left factor: v ↦ a1 ā0 v; right factor: v ↦ v a0 ā1, in quaternion coordinates
    (w, x, y, z) of the world; the two together with one drag are the 3D arcball (w fixed)."""
    rng = np.random.default_rng(7)
    p = np.array([[0, 0, 0, 1], [1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], float)
    for _ in range(10):
        a0 = controls.arcball_point(*rng.uniform(0, 512, 2), 512, 512)
        a1 = controls.arcball_point(*rng.uniform(0, 512, 2), 512, 512)
        start = special_ortho_group.rvs(4, random_state=int(rng.integers(1000)))
        left = controls.arcball(start, a0, a1)
        right = controls.arcball(start, a0, a1, right=True)
        assert_rotation(left, 1e-12)
        assert_rotation(right, 1e-12)
        v = rng.normal(size=4)
        q = qmul(a1, qconj(a0))
        np.testing.assert_allclose(left @ v, p.T @ qmul(q, p @ (start @ v)), atol=1e-12)
        np.testing.assert_allclose(right @ v, p.T @ qmul(p @ (start @ v), qmul(a0, qconj(a1))), atol=1e-12)
        both = controls.arcball(controls.arcball(np.eye(4), a0, a1), a0, a1, right=True)
        assert abs(both[3, 3] - 1) < 1e-12  # w fixed
        np.testing.assert_allclose(both[:3, :3], rot.quat_to_matrix(q), atol=1e-12)


# -- snapping, steps, orbit ----------------------------------------------------------------

def signed_permutations(n):
    for perm in itertools.permutations(range(n)):
        for signs in itertools.product((1.0, -1.0), repeat=n):
            m = np.zeros((n, n))
            m[np.arange(n), perm] = signs
            if np.linalg.det(m) > 0:
                yield m


@pytest.mark.parametrize("n", [3, 4])
def test_snap_is_the_nearest_axis_view(n):
    views = list(signed_permutations(n))
    for seed in range(12):
        r = special_ortho_group.rvs(n, random_state=seed)
        s = controls.snap(r)
        best = min(np.linalg.norm(v - r) for v in views)
        assert any(np.array_equal(s, v) for v in views)
        assert np.linalg.norm(s - r) <= best + 1e-12


@pytest.mark.parametrize("n", [5, 6])
def test_snap_recovers_a_perturbed_axis_view(n):
    rng = np.random.default_rng(n)
    perm = rng.permutation(n)
    view = np.zeros((n, n))
    view[np.arange(n), perm] = rng.choice([-1.0, 1.0], size=n)
    if np.linalg.det(view) < 0:
        view[0] *= -1
    r = rot.compose(np.stack([view, rot.plane(n, 0, 2, 0.2), rot.plane(n, 1, n - 1, -0.3)]))
    np.testing.assert_array_equal(controls.snap(r), view)


def test_transform_step_turns_about_the_centre():
    r = rot.plane(4, 0, 3, 0.7)
    c = np.array([1.0, -2.0, 0.5, 3.0])
    step = controls.transform_step(r, c)
    a = np.array(step["matrix"])
    assert a.shape == (5, 5) and np.array_equal(a[4], [0, 0, 0, 0, 1])
    x = np.array([0.3, 0.1, -2.0, 4.0])
    np.testing.assert_allclose(a[:4, :4] @ x + a[:4, 4], r @ (x - c) + c, atol=1e-14)
    assert controls.transform_step(r, np.zeros(4)) == {"matrix": r.tolist()}


def test_orbit_and_rotation_checks():
    assert controls.orbit(30, 20, 10, 5) == pytest.approx((34.0, 22.0))
    assert controls.orbit(170, 80, 50, 100)[1] == 90.0
    assert controls.orbit(170, 0, 50, 0)[0] == pytest.approx(-170.0)
    with pytest.raises(ValueError, match="rotation: expected a 4×4"):
        controls.check_rotation([[1, 0], [0, 1]], 4)
    with pytest.raises(ValueError, match="rotation"):
        controls.check_rotation(np.diag([1.0, 1.0, 1.0, -1.0]), 4)


# -- the session -----------------------------------------------------------------------------

def test_draft_resolution_keeps_the_budget_and_the_aspect():
    assert draft_resolution([64, 64, 64]) == [32, 32, 32]
    assert draft_resolution([16, 16, 16]) == [16, 16, 16]
    assert draft_resolution([120, 60, 30], 32 ** 3) == [64, 32, 16]  # factor (32³/216000)^(1/3)
    assert draft_resolution([100, 3], 50) == [41, 2]  # at least 2 per axis
    assert draft_resolution([24] * 4, 12 ** 4) == [12] * 4


def test_session_messages_move_the_view():
    s = ViewSession(ndtrace.load_file(SCENES / "tesseract.toml"), name="tesseract.toml")
    hello, frame = s.handle({"type": "hello", "seq": 1})
    assert frame == "draft" and hello["type"] == "hello" and hello["dim"] == 4 and hello["picture"] == [512, 512]
    assert hello["radius"] == 256 and hello["arcball"] and hello["orbit"]
    assert set(hello["modes"]) >= {"volume", "mip"} and hello["draft"] == [32, 32, 32]
    state, frame = s.handle({"type": "roll", "seq": 2, "steps": [[10, 0], [0, 5]]})
    assert frame == "draft" and state["seq"] == 2
    want = rot.rolling_ball([0, -5, 0], 256) @ rot.rolling_ball([10, 0, 0], 256)
    np.testing.assert_allclose(np.array(state["rotation"]), want, atol=1e-14)
    state, _ = s.handle({"type": "orbit", "seq": 3, "dx": 10, "dy": -10})
    assert state["options"]["azimuth"] == pytest.approx(34) and state["options"]["elevation"] == pytest.approx(16)
    state, _ = s.handle({"type": "zoom", "factor": 2.0})
    assert state["options"]["zoom"] == 2.0
    state, frame = s.handle({"type": "set", "options": {"mode": "mip", "opacity": 0.25}})
    assert frame == "draft" and state["options"]["mode"] == "mip" and state["options"]["opacity"] == 0.25
    state, frame = s.handle({"type": "snap"})
    assert frame == "now" and np.array_equal(np.abs(np.array(state["rotation"])), np.eye(4))
    state, _ = s.handle({"type": "reset"})
    assert state["rotation"] == np.eye(4).tolist() and "mode" not in state["options"]
    r = rot.plane(4, 1, 3, 0.4)
    typed = np.round(r, 4)  # four digits, as the page shows them
    state, _ = s.handle({"type": "rotation", "matrix": typed.tolist()})
    np.testing.assert_allclose(np.array(state["rotation"]), r, atol=1e-4)
    assert_rotation(np.array(state["rotation"]))


@pytest.mark.parametrize("msg, match", [
    ({"type": "spin"}, "message type 'spin': unknown"),
    ({"seq": 1}, "expected an object with a 'type'"),
    ({"type": "roll", "steps": [[1, "a"]]}, "roll.steps"),
    ({"type": "roll", "steps": [[1, float("nan")]]}, "roll.steps"),
    ({"type": "orbit", "dx": 1}, "orbit.dy: expected a finite number"),
    ({"type": "zoom", "factor": -1}, "zoom.factor: must be > 0"),
    ({"type": "set", "options": {"opacity": -1}}, "opacity"),
    ({"type": "set", "options": {"mode": "cubist"}}, "mode"),
    ({"type": "set", "options": {"size": [3, 3]}}, "set.options.size"),
    ({"type": "set", "options": {"colour": 1}}, "set.options.colour"),
    ({"type": "rotation", "matrix": [[1, 0], [0, 1]]}, "rotation: expected a 4×4"),
    ({"type": "rotation", "matrix": [[1, 0.1, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]}, "rotation"),
    ({"type": "arcball", "phase": "drag", "x": 1, "y": 2}, "must start with phase 'press'"),
    ({"type": "roll", "seq": "7", "steps": []}, "seq: expected an integer"),
])
def test_bad_messages_name_what_is_wrong_and_change_nothing(msg, match):
    s = ViewSession(ndtrace.load_file(SCENES / "tesseract.toml"))
    before = (s.rotation.copy(), dict(s.options), s.seq)
    with pytest.raises(ValueError, match=match):
        s.handle(msg)
    assert np.array_equal(s.rotation, before[0]) and s.options == before[1] and s.seq == before[2]


def test_arcball_is_for_4d_scenes_only():
    s = ViewSession(scene_of_dim(5))
    with pytest.raises(ValueError, match="needs a 4D scene"):
        s.handle({"type": "arcball", "phase": "press", "x": 1, "y": 1})
    s4 = ViewSession(scene_of_dim(4))
    s4.handle({"type": "arcball", "phase": "press", "x": 256, "y": 256})
    state, frame = s4.handle({"type": "arcball", "phase": "drag", "x": 300, "y": 200})
    a0 = controls.arcball_point(256, 256, 512, 512)
    a1 = controls.arcball_point(300, 200, 512, 512)
    np.testing.assert_allclose(np.array(state["rotation"]), controls.arcball(np.eye(4), a0, a1), atol=1e-14)


def decode(meta, payload):
    image = Image.open(io.BytesIO(payload))
    assert image.format == meta["format"].upper()
    assert image.size == (meta["width"], meta["height"])
    return np.asarray(image)


@pytest.mark.parametrize("n", DIMS)
def test_frames_show_the_rotated_scene(n):
    """A full frame is the scene with the rotation appended to each object's transform,
    traced and composited with the page's options (the same pixels as doing that by hand);
    a draft traces the draft resolution."""
    scene = scene_of_dim(n)
    s = ViewSession(scene, size=(96, 80), draft_cells=4 ** (n - 1))
    s.handle({"type": "roll", "steps": [[20, 5], [-3, 12]]})
    meta, payload = s.render(s.snapshot(), FULL, lambda: False)
    got = decode(meta, payload)
    data = scene.to_dict()
    step = {"matrix": s.rotation.tolist()}
    data["objects"] = [dict(o, transform=list(o.get("transform") or []) + [step]) for o in data["objects"]]
    retina = ndtrace.trace(ndtrace.load_dict(data))
    picture = ndtrace.composite(retina, **s.options)
    want = ndtrace.files.to_srgb8(picture, opaque=True)
    assert meta["quality"] == FULL and meta["ms"] > 0 and meta["retina"] == list(retina.shape)
    np.testing.assert_array_equal(got, want)
    meta, payload = s.render(s.snapshot(), DRAFT, lambda: False)
    assert meta["quality"] == DRAFT
    assert decode(meta, payload).shape[:2] == (30, 36)  # drafts composite at 3/8 of the size
    # The full retina of this rotation is kept: the draft composited it without a trace.
    assert "trace" not in meta["timings"] and meta["retina"] == list(retina.shape)
    s.handle({"type": "roll", "steps": [[1, 0]]})
    meta, _ = s.render(s.snapshot(), DRAFT, lambda: False)
    assert meta["retina"] == [4] * (n - 1) and "trace" in meta["timings"]


def test_the_view_as_toml_renders_what_the_page_shows():
    scene = ndtrace.load_file(SCENES / "tesseract.toml")
    s = ViewSession(scene, size=(64, 64), name="tesseract.toml")
    s.handle({"type": "roll", "steps": [[30, -10], [5, 40]]})
    s.handle({"type": "set", "options": {"mode": "mip", "opacity": 0.5}})
    s.handle({"type": "orbit", "dx": 20, "dy": 10})
    s.handle({"type": "zoom", "factor": 2.0})
    text = s.view_toml()
    assert text.startswith("# The view of tesseract.toml")
    table, refused = s.composite_table()
    assert refused == {} and table["zoom"] == 2.0  # [composite] holds every keyword of composite
    assert "does not take" not in text.split("\n[")[0]
    loaded = ndtrace.load_toml(text)
    table = loaded.to_dict()["composite"]
    assert table["mode"] == "mip" and table["opacity"] == 0.5 and table["azimuth"] == pytest.approx(38)
    assert table["zoom"] == 2.0 and table["size"] == (64, 64)
    meta, payload = s.render(s.snapshot(), FULL, lambda: False)
    from ndtrace.composite import scene_options

    want = ndtrace.files.to_srgb8(ndtrace.composite(ndtrace.trace(loaded), **scene_options(loaded.to_dict())), opaque=True)
    np.testing.assert_array_equal(decode(meta, payload), want)


def test_display_aids_follow_the_composite_signature(monkeypatch):
    """Keywords of ndtrace.composite beyond the base ones get controls, typed by default."""
    import inspect

    import ndtrace.viewer.session as session_module

    seen = []

    def fake(retina, *, mode="volume", opacity=1.0, fit=True, sections=0, layout="volume",
             cutaway=None, threads=None, **rest):
        """stand-in"""
        seen.append(cutaway)
        if cutaway is not None and "plane" not in cutaway:
            raise ValueError("cutaway: expected a plane")

    monkeypatch.setattr(session_module, "composite", fake)
    monkeypatch.setattr(session_module._composite_module, "LAYOUTS", ("volume", "sections"), raising=False)
    aids = {a["name"]: a for a in display_aids()}
    assert set(aids) == {"fit", "sections", "layout", "cutaway"}
    assert aids["fit"]["kind"] == "bool" and aids["fit"]["default"] is True
    assert aids["sections"]["kind"] == "number"
    assert aids["layout"]["kind"] == "choice" and aids["layout"]["choices"] == ["volume", "sections"]
    assert aids["cutaway"]["kind"] == "text"
    assert inspect.signature(fake).parameters["fit"].default is True
    # A text aid is a TOML value; empty is the default; the composite's own errors come back.
    s = ViewSession(scene_of_dim(4))
    state, _ = s.handle({"type": "set", "options": {"cutaway": "{ plane = [0, 0, 1, 0], offset = 0.5 }"}})
    assert state["options"]["cutaway"] == {"plane": [0, 0, 1, 0], "offset": 0.5} and seen[-1] == state["options"]["cutaway"]
    with pytest.raises(ValueError, match="cutaway: expected a TOML value"):
        s.handle({"type": "set", "options": {"cutaway": "{ plane = "}})
    with pytest.raises(ValueError, match="cutaway: expected a plane"):
        s.handle({"type": "set", "options": {"cutaway": "{ sphere = 1 }"}})
    state, _ = s.handle({"type": "set", "options": {"cutaway": "", "fit": False}})
    assert "cutaway" not in state["options"] and state["options"]["fit"] is False
    # Today's composite has none of these: no aid controls.
    monkeypatch.undo()
    names = {a["name"] for a in display_aids()}
    assert names == set(inspect.signature(ndtrace.composite).parameters) - session_module.BASE_KEYWORDS


# -- the worker -------------------------------------------------------------------------------

class FakeRender:
    """Stands in for ViewSession.render: records each call; a full frame 'traces' until
    cancelled (polling cancelled() as the core's progress callback does) or released."""

    def __init__(self):
        self.calls = []
        self.full_started = threading.Event()
        self.finish_full = threading.Event()

    def __call__(self, snap, quality, cancelled):
        self.calls.append((snap, quality))
        if quality == FULL:
            self.full_started.set()
            while not self.finish_full.wait(0.005):
                if cancelled():
                    raise Superseded
        else:
            time.sleep(0.01)
        return {"type": "frame", "seq": snap, "quality": quality}, b"x"


def collect():
    got, cond = [], threading.Condition()

    def emit(meta, payload):
        with cond:
            got.append(meta)
            cond.notify_all()

    def wait_for(pred, timeout=10.0):
        with cond:
            assert cond.wait_for(lambda: pred(got), timeout), got

    return got, emit, wait_for


def test_worker_drafts_then_full_at_rest():
    render = FakeRender()
    render.finish_full.set()
    got, emit, wait_for = collect()
    w = FrameWorker(render, emit, rest=0.05)
    try:
        w.request(1)
        wait_for(lambda g: len(g) >= 2)
        assert [(m["seq"], m["quality"]) for m in got] == [(1, DRAFT), (1, FULL)]
        w.request(2, draft=False)  # straight to the full frame
        wait_for(lambda g: len(g) >= 3)
        assert (got[2]["seq"], got[2]["quality"]) == (2, FULL)
    finally:
        w.close()


def test_worker_a_new_input_cancels_the_full_frame_in_flight():
    render = FakeRender()
    got, emit, wait_for = collect()
    w = FrameWorker(render, emit, rest=0.0)
    try:
        w.request(1)
        assert render.full_started.wait(10)
        w.request(2)  # supersedes the full frame of 1
        wait_for(lambda g: any(m["seq"] == 2 and m["quality"] == DRAFT for m in g))
        render.finish_full.set()
        wait_for(lambda g: any(m["seq"] == 2 and m["quality"] == FULL for m in g))
        assert not any(m["seq"] == 1 and m["quality"] == FULL for m in got)
        assert w.stats["cancelled"] == 1
    finally:
        w.close()


def test_worker_keeps_only_the_latest_request():
    """Inputs arriving while a frame renders do not queue: the next frame is the newest."""
    gate = threading.Event()
    calls = []

    def render(snap, quality, cancelled):
        calls.append((snap, quality))
        if snap == 0:
            gate.wait(10)
        return {"type": "frame", "seq": snap, "quality": quality}, b"x"

    got, emit, wait_for = collect()
    w = FrameWorker(render, emit, rest=10.0)
    try:
        w.request(0)
        while not calls:
            time.sleep(0.001)
        for k in range(1, 50):
            w.request(k)
        gate.set()
        wait_for(lambda g: any(m["seq"] == 49 for m in g))
        assert [c[0] for c in calls] == [0, 49]
        w.release()
        wait_for(lambda g: any(m["quality"] == FULL for m in g))
        assert calls[-1] == (49, FULL)
    finally:
        w.close()


def test_worker_reports_errors_and_goes_on():
    def render(snap, quality, cancelled):
        if snap == "bad":
            raise ValueError("opacity: must be ≥ 0")
        return {"type": "frame", "seq": snap, "quality": quality}, b"x"

    got, emit, wait_for = collect()
    w = FrameWorker(render, emit, rest=0.0)
    try:
        w.request("bad")
        wait_for(lambda g: any(m["type"] == "error" for m in g))
        assert got[0]["message"] == "opacity: must be ≥ 0"
        w.request("good")
        wait_for(lambda g: any(m.get("seq") == "good" and m["quality"] == FULL for m in g))
    finally:
        w.close()


def test_a_full_trace_is_cancelled_through_the_progress_callback():
    """The real thing: a slow full frame (a 3-sphere at 128³) stops when an input arrives."""
    scene = ndtrace.load_file(SCENES / "sphere3.toml")
    s = ViewSession(scene, size=(32, 32))
    s._desc["camera"] = dict(s._desc["camera"], resolution=128)
    polled = threading.Event()
    stop = threading.Event()

    def cancelled():
        polled.set()
        return stop.is_set()

    result = {}

    def run():
        try:
            result["frame"] = s.render(s.snapshot(), FULL, cancelled)
        except Superseded:
            result["cancelled"] = True

    t = threading.Thread(target=run)
    t.start()
    assert polled.wait(30)
    stop.set()
    t.join(30)
    assert result == {"cancelled": True}


def test_draft_cells_default_is_32_cubed():
    assert DRAFT_CELLS == 32 ** 3


@pytest.mark.parametrize("kwargs, match", [
    ({"size": (0, 10)}, "size: width and height must be at least 1"),
    ({"size": "big"}, "size: expected"),
    ({"draft_cells": 0}, "draft_cells: expected an integer ≥ 1"),
    ({"threads": 1.5}, "threads: expected an integer"),
    ({"draft_scale": 2}, "draft_scale: expected a number in"),
])
def test_session_arguments_are_checked(kwargs, match):
    with pytest.raises(ValueError, match=match):
        ViewSession(scene_of_dim(4), **kwargs)
    with pytest.raises(TypeError, match="scene: expected an ndtrace.Scene"):
        ViewSession({"dim": 4})


def test_slice_mode_shows_the_slice_of_the_turned_scene():
    """Slice mode: the frame is the 3D slice x_3 = offset of the scene turned by the rolling
    ball (the same pixels as slicing the turned scene by hand); off again shows the projection;
    reset turns it off."""
    scene = ndtrace.load_file(SCENES / "tesseract.toml")
    s = ViewSession(scene, size=(64, 48))
    assert s.hello()["slices"]
    s.handle({"type": "roll", "steps": [[15, 4]]})
    reply, frame = s.handle({"type": "slice", "on": True, "offset": 0.25})
    assert reply["slice"] == 0.25 and frame == "now"
    meta, payload = s.render(s.snapshot(), FULL, lambda: False)
    got = decode(meta, payload)
    data = scene.to_dict()
    step = {"matrix": s.rotation.tolist()}
    data["objects"] = [dict(o, transform=list(o.get("transform") or []) + [step]) for o in data["objects"]]
    cut = ndtrace.slice_scene(ndtrace.load_dict(data), [0, 0, 0, 1], 0.25).to_dict()
    cut["camera"]["resolution"] = [64, 48]
    picture = ndtrace.composite(ndtrace.trace(ndtrace.load_dict(cut)), size=(64, 48),
                                background=s.options["background"])
    np.testing.assert_array_equal(got, ndtrace.files.to_srgb8(picture, opaque=True))
    assert meta["retina"] == [48, 64]
    # A draft of a new view traces the slice at the draft picture's size; turning slice mode
    # off shows the projection again.
    s.handle({"type": "roll", "steps": [[1, 0]]})
    meta, _ = s.render(s.snapshot(), DRAFT, lambda: False)
    assert meta["retina"] == [18, 24]
    s.handle({"type": "slice", "on": False})
    meta, _ = s.render(s.snapshot(), FULL, lambda: False)
    assert meta["retina"] == [64, 64, 64]
    s.handle({"type": "slice", "on": True, "offset": -0.5})
    s.handle({"type": "reset"})
    assert s.slice is None
    with pytest.raises(ValueError, match=r"slice\.offset: expected a finite number"):
        s.handle({"type": "slice", "on": True, "offset": "x"})
    with pytest.raises(ValueError, match=r"slice mode needs dim ≥ 4"):
        ViewSession(scene_of_dim(3), size=(32, 32)).handle({"type": "slice", "offset": 0})
