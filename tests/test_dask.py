"""Dask distributed: retinas traced in slabs on workers and animation frames rendered on them
are bit-identical to a local render; progress, Ctrl-C and a dying worker (ndtrace.cluster)."""

from __future__ import annotations

import logging
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import ndtrace

distributed = pytest.importorskip("distributed")

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SPIN = os.path.join(ROOT, "scenes", "tesseract_spin.toml")
FIELDS = ("rgba", "depth", "normal", "object_id", "primitive_id")


def _cluster(**kw):
    return distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                    host="127.0.0.1", dashboard_address="127.0.0.1:0",
                                    silence_logs=logging.ERROR, **kw)


@pytest.fixture(scope="module")
def client():
    with _cluster() as cluster, distributed.Client(cluster) as c:
        yield c


def _bits(a: np.ndarray) -> np.ndarray:
    return a.view(np.uint32) if a.dtype == np.float32 else a


def assert_same_retina(a: ndtrace.Retina, b: ndtrace.Retina) -> None:
    assert a.dim == b.dim and a.shape == b.shape
    for name in FIELDS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.shape == y.shape and x.dtype == y.dtype, name
        assert np.array_equal(_bits(x), _bits(y)), name


def _scene(dim: int, res, samples: int = 1, surface: bool = False) -> ndtrace.Scene:
    s = ndtrace.Scene(dim)
    up = [[1.0 if i == k else 0.0 for i in range(dim)] for k in range(1, dim - 1)]
    s.set_camera(position=[1.0 + 0.6 * i for i in range(dim)], look_at=[0.0] * dim, fov=55,
                 resolution=res, **({"up": up} if up else {}))
    s.add_light("point", position=[2.0] * dim)
    s.add_object("hypercube", transform=[{"scale": 0.5}, {"rotate": {"plane": [0, 1], "degrees": 25}}])
    s.add_object("sphere", subdivisions=2, transform=[{"scale": 0.3}, {"translate": [0.4] * dim}])
    if surface:
        s.add_object("surface", vertices=[[-1, -1, 0, 0.4], [1, -1, 0, 0.4], [1, 1, 0, 0.4]],
                     triangles=[[0, 1, 2]], width=2.0, material={"opacity": 0.6})
    s.set_render(samples=samples, shadows=True, cull_backfaces=True)
    return s


@pytest.mark.parametrize("dim, res, samples, surface", [
    (2, 400, 2, False),
    (3, [96, 80], 3, False),
    (4, [40, 36, 30], 2, False),
    (4, [32, 32, 24], 1, True),
    (5, [12, 10, 9, 8], 1, False),
])
def test_a_retina_traced_in_slabs_on_workers_is_the_local_retina(client, dim, res, samples, surface):
    scene = _scene(dim, res, samples, surface)
    local = ndtrace.trace(scene)
    calls: list[tuple[int, int]] = []
    remote = ndtrace.trace(scene, progress=lambda d, t: calls.append((d, t)), client=client)
    assert_same_retina(remote, local)
    assert remote.hit.any() and (~remote.hit).any()
    # Progress: from 0 to every cell, never backwards, over several slabs.
    total = int(np.prod(local.shape))
    assert calls[0] == (0, total) and calls[-1] == (total, total)
    assert all(a[0] <= b[0] for a, b in zip(calls, calls[1:]))
    if total > 4096 * 8:
        assert len(calls) >= 4
    # The retina composites as a local one does (camera and edges from the same scene).
    assert remote.camera == local.camera
    assert np.array_equal(ndtrace.composite(remote, size=(64, 64)),
                          ndtrace.composite(local, size=(64, 64)))


def test_slabs_are_whole_chunks_covering_the_retina_and_others_are_refused():
    compiled = _scene(4, [40, 36, 30]).compiled()
    total = 40 * 36 * 30
    for count in (1, 2, 5, 100, 10**6):
        slabs = compiled.slabs(count)
        assert 1 <= len(slabs) <= count
        assert slabs[0][0] == 0 and slabs[-1][1] == total
        assert all(a[1] == b[0] for a, b in zip(slabs, slabs[1:]))
    whole = compiled.trace(1)
    a, b = compiled.slabs(3)[1]
    part = compiled.trace(1, None, (a, b))
    assert part["depth"].shape == (b - a,)
    assert np.array_equal(part["depth"], whole["depth"].reshape(-1)[a:b])
    with pytest.raises(ValueError, match="cells: expected a slab of whole chunks"):
        compiled.trace(1, None, (a + 1, b))
    with pytest.raises(ValueError, match="cells: expected a slab of whole chunks"):
        compiled.trace(1, None, (0, total + 1))


def test_animation_frames_rendered_on_workers_are_the_local_files(client, tmp_path):
    scene = ndtrace.load_file(SPIN)
    options = {"frames": 5, "composite": {"size": [96, 96]}, "keep_frames": True}
    local = ndtrace.animate(scene, tmp_path / "local.gif", **options)
    calls: list[tuple[int, int]] = []
    remote = ndtrace.animate(scene, tmp_path / "remote.gif", client=client,
                             progress=lambda d, t: calls.append((d, t)), **options)
    assert [os.path.basename(p).replace("remote", "local") for p in remote] == \
        [os.path.basename(p) for p in local]
    for a, b in zip(local, remote):
        assert open(a, "rb").read() == open(b, "rb").read(), b
    cells = 48**3
    assert calls[0] == (0, 5 * cells) and calls[-1] == (5 * cells, 5 * cells)
    assert sorted({d for d, _ in calls}) == [k * cells for k in range(6)]


def test_a_workers_error_reaches_the_caller_saying_where_it_came_from(client, tmp_path):
    # A mesh file the workers cannot read (gone after the scene was built here).
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    path = tmp_path / "tet.npz"
    np.savez(path, vertices=v, simplices=np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
    scene = ndtrace.load_toml(f"dim = 3\n[camera]\nposition = [2, 2, 2]\nlook_at = [0, 0, 0]\nup = [0, 0, 1]\n"
                              f"fov = 40\nresolution = 16\n[[objects]]\nshape = \"mesh\"\n"
                              f"file = \"{path}\"\n")
    os.unlink(path)
    with pytest.raises((OSError, ValueError)) as info:
        ndtrace.trace(scene, client=client)
    assert "tet.npz" in str(info.value)
    assert any("raised on a Dask worker, slab 0" in n for n in getattr(info.value, "__notes__", []))


def test_bad_clients_are_refused_by_name(client):
    scene = _scene(3, [16, 16])
    with pytest.raises(TypeError, match="client: expected a dask.distributed.Client, got str"):
        ndtrace.trace(scene, client="tcp://127.0.0.1:1")
    with distributed.Client(client.scheduler.address) as other:
        pass
    with pytest.raises(ValueError, match="client: the Dask client is closed"):
        ndtrace.trace(scene, client=other)


def _executing(c) -> int:
    """Tasks whose threads are running on the workers (cancelled ones included)."""
    return sum(c.run(lambda dask_worker: len(dask_worker.state.executing)).values())


def test_ctrl_c_stops_the_running_frames_on_the_workers_and_writes_no_video(tmp_path):
    data = ndtrace.load_file(SPIN).to_dict()
    data["camera"]["resolution"] = 112
    data["render"]["samples"] = 8
    scene = ndtrace.load_dict(data)
    options = {"composite": {"size": [64, 64]}, "threads": 1}
    # How long a frame takes here on one thread (the workers have one each).
    from ndtrace.animation import _table, render_frame
    from ndtrace.composite import scene_options

    start = time.monotonic()
    render_frame(_table(scene, None, 8), 0, 1, {**scene_options(data), "size": [64, 64]})
    frame_seconds = time.monotonic() - start
    with _cluster() as cluster, distributed.Client(cluster) as c:
        stopped: list[float] = []

        def interrupt(done, total):
            # Once both workers are tracing a frame, Ctrl-C.
            deadline = time.monotonic() + 60
            while _executing(c) < 2 and time.monotonic() < deadline:
                time.sleep(0.05)
            time.sleep(0.2)
            stopped.append(time.monotonic())
            raise KeyboardInterrupt

        with pytest.raises(KeyboardInterrupt):
            ndtrace.animate(scene, tmp_path / "spin.gif", frames=8, client=c, progress=interrupt,
                            **options)
        # The running frames stop (their trace watches the cancel event), well before they
        # would have finished; the others never start.
        while _executing(c) and time.monotonic() < stopped[0] + 60:
            time.sleep(0.05)
        elapsed = time.monotonic() - stopped[0]
        assert _executing(c) == 0
        assert elapsed < frame_seconds / 2, (elapsed, frame_seconds)
    assert not os.path.exists(tmp_path / "spin.gif")
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".ndtrace-")]


@pytest.fixture
def sigint_handled():
    """Python's own SIGINT handler during the test, whatever the runner left: a job a shell
    starts in the background begins with SIGINT ignored, and Python then keeps it ignored (so a
    raised SIGINT would do nothing)."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_ctrl_c_that_python_swallows_in_a_finalizer_still_stops_the_render(client, sigint_handled):
    # A signal's handler runs wherever the main thread is; in a __del__ (a Dask future's, as a
    # finished one is let go) its KeyboardInterrupt is printed as "Exception ignored" and lost.
    class Finalizer:
        def __del__(self):
            signal.raise_signal(signal.SIGINT)

    calls: list[tuple[int, int]] = []

    def progress(done, total):
        calls.append((done, total))
        if len(calls) == 2:  # after the first slab: Ctrl-C, lost in a finalizer
            Finalizer()

    scene = _scene(4, [24, 24, 24])
    assert len(scene.compiled().slabs(8)) > 2
    with pytest.raises(KeyboardInterrupt):
        ndtrace.trace(scene, client=client, progress=progress)
    assert len(calls) == 2 and calls[-1][0] < calls[-1][1]  # stopped at once, not at the end
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_ctrl_c_swallowed_during_the_last_progress_call_still_raises(client, sigint_handled):
    # As above, but the Ctrl-C comes with the last slab's progress: the render is done, and the
    # call still ends with KeyboardInterrupt (not a retina the user asked to stop).
    class Finalizer:
        def __del__(self):
            signal.raise_signal(signal.SIGINT)

    def progress(done, total):
        if done == total:
            Finalizer()

    with pytest.raises(KeyboardInterrupt):
        ndtrace.trace(_scene(4, [8, 8, 8]), client=client, progress=progress)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_frames_of_a_worker_that_dies_are_rerun_elsewhere(tmp_path):
    data = ndtrace.load_file(SPIN).to_dict()
    data["camera"]["resolution"] = 80  # frames of about a second: the kill finds one running
    scene = ndtrace.load_dict(data)
    options = {"frames": 8, "composite": {"size": [64, 64]}, "video": None}
    local = ndtrace.animate(scene, tmp_path / "local.png", **options)
    with _cluster() as cluster, distributed.Client(cluster) as c:
        pids = c.run(os.getpid)
        killed: list[int] = []

        def kill_one(done, total):
            # Once a frame has arrived, kill a worker while it renders another one.
            if done == 0 or killed:
                return
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline:
                busy = [w for w, n in c.run(lambda dask_worker: len(dask_worker.state.executing)).items() if n]
                if busy:
                    killed.append(pids[busy[0]])
                    os.kill(pids[busy[0]], signal.SIGKILL)
                    return
                time.sleep(0.01)

        remote = ndtrace.animate(scene, tmp_path / "remote.png", client=c, progress=kill_one,
                                 **options)
        assert killed and killed[0] not in c.run(os.getpid).values()
    for a, b in zip(local, remote, strict=True):
        assert open(a, "rb").read() == open(b, "rb").read(), b


def test_cli_dask_local_writes_the_local_picture(tmp_path):
    def run(*extra):
        out = tmp_path / f"t{len(extra)}.png"
        r = subprocess.run([sys.executable, "-m", "ndtrace", os.path.join(ROOT, "scenes", "cube.toml"),
                            "-o", str(out), "--quiet", *extra], capture_output=True, text=True,
                           timeout=300)
        assert r.returncode == 0, r.stderr
        return out.read_bytes()
    assert run("--dask") == run()
    r = subprocess.run([sys.executable, "-m", "ndtrace", "--dask", "scene.toml", "-o", "x.png"],
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 2
    assert "--dask: expected 'local' or a scheduler address tcp://HOST:PORT, got 'scene.toml'" in r.stderr
    r = subprocess.run([sys.executable, "-m", "ndtrace", os.path.join(ROOT, "scenes", "cube.toml"),
                        "-o", str(tmp_path / "x.png"), "--dask", "tcp://127.0.0.1:9"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2
    assert "--dask tcp://127.0.0.1:9: cannot reach the Dask scheduler" in r.stderr
    assert not (tmp_path / "x.png").exists()


def test_ctrl_c_in_the_terminal_stops_a_cli_render_on_a_local_cluster_cleanly(tmp_path):
    import threading

    out = tmp_path / "spin.gif"
    p = subprocess.Popen(
        [sys.executable, "-m", "ndtrace", SPIN, "-o", str(out), "--dask", "--frames", "48",
         "--set", "camera.resolution=96"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
        text=True, start_new_session=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    seen: list[str] = []
    started = threading.Event()

    def read():
        for line in p.stdout:
            seen.append(line)
            if "frames" in line and "ETA" in line:  # a frame has arrived
                started.set()

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        assert started.wait(240), "".join(seen)
        # Ctrl-C in a terminal signals the whole process group: the CLI and its workers.
        os.killpg(p.pid, signal.SIGINT)
        assert p.wait(60) == 130, "".join(seen)[-4000:]
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
    reader.join(10)
    text = "".join(seen)
    assert "ndtrace: interrupted" in text
    assert "Traceback" not in text, text
    assert not out.exists() and not [f for f in os.listdir(tmp_path) if f.startswith(".ndtrace-")]
