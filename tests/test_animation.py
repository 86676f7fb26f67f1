"""Animations: the [animation] table, ndtrace.animate and the CLI's --frames."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

import ndtrace
from ndtrace.animation import frame_paths, frame_scene

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SPIN = os.path.join(ROOT, "scenes", "tesseract_spin.toml")


def scene4(animation: dict | None = None, res: int = 10, light: bool = True) -> ndtrace.Scene:
    s = ndtrace.Scene(4)
    s.set_camera(position=[0.5, 0.7, 1.0, 4.0], look_at=[0, 0, 0, 0],
                 up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=50, resolution=res)
    if light:
        s.add_light("directional", direction=[0.3, 0.5, 0.7, 1.0])
    s.add_object("hypercube", transform=[{"scale": [1.0, 0.7, 0.5, 0.8]}])
    s.add_object("simplex", transform=[{"translate": [0.3, 0, 0, 0]}])
    data = s.to_dict()
    if animation is not None:
        data["animation"] = animation
    return ndtrace.load_dict(data)


def retina(scene: ndtrace.Scene) -> ndtrace.Retina:
    return ndtrace.trace(scene, threads=1)


def test_each_sweep_frame_equals_the_scene_with_that_rotation_written_out():
    anim = scene4({"frames": 4, "periodic": True, "sweep": {"plane": [0, 3], "degrees": [10, 370]}})
    for k, degrees in enumerate([10, 100, 190, 280]):
        explicit = scene4()
        data = explicit.to_dict()
        for o in data["objects"]:
            o["transform"].append({"rotate": {"plane": [0, 3], "degrees": degrees}})
        a, b = retina(frame_scene(anim, k)), retina(ndtrace.load_dict(data))
        np.testing.assert_array_equal(a.object_id, b.object_id)
        np.testing.assert_array_equal(a.primitive_id, b.primitive_id)
        np.testing.assert_allclose(a.depth[a.hit], b.depth[b.hit], rtol=1e-9)
        np.testing.assert_allclose(a.rgba, b.rgba, atol=1e-6)


def test_turning_the_camera_equals_turning_the_world_the_other_way():
    # Depth and ids don't depend on the (world-fixed) light, so they must agree exactly
    # up to rounding: the camera rotated by M sees the world rotated by M⁻¹.
    cam = scene4({"frames": 3, "target": "camera", "center": [0.1, 0, 0, 0.2],
                  "sweep": {"plane": [1, 3], "degrees": [0, 40]}}, light=False)
    obj = scene4({"frames": 3, "center": [0.1, 0, 0, 0.2],
                  "sweep": {"plane": [1, 3], "degrees": [0, -40]}}, light=False)
    moved = 0
    for k in range(3):
        a, b = retina(frame_scene(cam, k)), retina(frame_scene(obj, k))
        np.testing.assert_array_equal(a.primitive_id, b.primitive_id)
        # (The tree stores each simplex's rows rounded to f32, in world space here and there:
        # the hit points differ by ~1e-7 of a simplex.)
        np.testing.assert_allclose(a.depth[a.hit], b.depth[b.hit], rtol=1e-6)
        moved += int(np.sum(a.primitive_id != retina(frame_scene(cam, 0)).primitive_id))
    assert moved > 50, "the frames must actually differ"


def test_listed_objects_move_and_the_others_stay():
    anim = scene4({"frames": 2, "target": [1], "sweep": {"plane": [0, 1], "degrees": [0, 90]}})
    last = frame_scene(anim, 1).to_dict()
    first = anim.to_dict()
    assert last["objects"][0] == first["objects"][0]
    assert len(last["objects"][1]["transform"]) == len(first["objects"][1]["transform"]) + 1
    m = np.array(last["objects"][1]["transform"][-1]["matrix"])
    np.testing.assert_allclose(m[:2, :2], [[0, -1], [1, 0]], atol=1e-15)  # R_01(90°): e0 ↦ e1
    assert "animation" not in last, "a frame is a still"


def test_animate_writes_numbered_frames_and_a_looping_gif(tmp_path):
    scene = ndtrace.load_file(SPIN)
    calls = []
    paths = ndtrace.animate(scene, tmp_path / "spin.png", frames=5,
                            composite={"size": [64, 48]}, progress=lambda d, t: calls.append((d, t)))
    pngs = [str(tmp_path / f"spin_{k:04d}.png") for k in range(1, 6)]
    assert paths == pngs + [str(tmp_path / "spin.gif")]
    cells = 48 ** 3
    assert calls[-1] == (5 * cells, 5 * cells)
    assert all(t == 5 * cells for _, t in calls)
    assert [d for d, _ in calls] == sorted(d for d, _ in calls), "progress only grows"
    assert {k * cells for k in range(1, 6)} <= {d for d, _ in calls}
    frames = [np.asarray(Image.open(p)) for p in pngs]
    assert all(f.shape == (48, 64, 3) for f in frames), "frames are opaque, as the GIF shows them"
    assert any(not np.array_equal(frames[0], f) for f in frames[1:]), "the tesseract turns"
    gif = Image.open(tmp_path / "spin.gif")
    assert gif.n_frames == 5 and gif.size == (64, 48) and gif.info["loop"] == 0
    assert gif.info["duration"] == 80  # 1/12 s in the GIF's 1/100 s units
    assert [ndtrace.animation.gif_frame_ms(f) for f in (12, 24, 30, 100, 0.5)] == [80, 40, 30, 20, 2000]
    # Frame 0 of a sweep from 0° is the scene as written.
    still = ndtrace.load_dict({k: v for k, v in scene.to_dict().items() if k != "animation"})
    picture = ndtrace.composite(ndtrace.trace(still), **{**scene.to_dict()["composite"], "size": [64, 48],
                                                         "background": scene.to_dict()["background"]})
    np.testing.assert_array_equal(frames[0], ndtrace.files.to_srgb8(picture, opaque=True))
    # The GIF shows the opaque picture (its colour over the background).
    gif.seek(0)
    shown = np.asarray(gif.convert("RGB")).astype(int)
    assert np.abs(shown - ndtrace.files.to_srgb8(picture, opaque=True)).max() <= 24  # palette


def test_video_choices(tmp_path):
    scene = scene4({"frames": 2, "sweep": {"plane": [0, 3], "degrees": [0, 30]}}, res=6)
    small = {"size": [16, 16]}
    assert ndtrace.animate(scene, tmp_path / "a.png", video=None, composite=small) == [
        str(tmp_path / "a_0001.png"), str(tmp_path / "a_0002.png")]
    assert not (tmp_path / "a.gif").exists()
    assert ndtrace.animate(scene, tmp_path / "b.gif", composite=small)[-1] == str(tmp_path / "b.gif")
    many = frame_paths("x/out.mp4", 12345)
    assert (len(many), many[0], many[1], many[-1]) == (12345, "x/out_00001.png", "x/out_00002.png",
                                                       "x/out_12345.png")
    assert frame_paths("out.png", 3) == ["out_0001.png", "out_0002.png", "out_0003.png"]
    try:
        import imageio_ffmpeg  # noqa: F401
    except ImportError:
        with pytest.raises(ValueError, match="MP4 output needs imageio-ffmpeg"):
            ndtrace.animate(scene, tmp_path / "c.mp4", composite=small)
        assert not (tmp_path / "c_0001.png").exists(), "checked before any work"
        return
    path = ndtrace.animate(scene, tmp_path / "c.png", video="mp4", composite={"size": [17, 15]})[-1]
    assert path.endswith("c.mp4") and os.path.getsize(path) > 0
    reader = imageio_ffmpeg.read_frames(path)
    meta = reader.__next__()
    assert meta["size"] == (18, 16)  # padded to even sides for yuv420p
    assert sum(1 for _ in reader) == 2


def test_mp4_without_imageio_ffmpeg_is_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)
    scene = scene4({"frames": 2, "sweep": {"plane": [0, 3], "degrees": [0, 30]}}, res=6)
    with pytest.raises(ValueError, match=r'MP4 output needs imageio-ffmpeg: pip install "ndtrace\[video\]"'):
        ndtrace.animate(scene, tmp_path / "c.mp4")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("table, message", [
    (None, "the scene has no \\[animation\\] table"),
    ({"frames": 0, "sweep": {"plane": [0, 3], "degrees": [0, 1]}}, "animation.frames: must be in 1..="),
    ({"sweep": {"plane": [0, 4], "degrees": [0, 1]}}, "animation.sweep.plane: expected two different axes"),
    ({"sweep": {"plane": [0, 3], "degrees": [0, float("nan")]}}, "animation.sweep.degrees\\[1\\]: must be finite"),
    ({"sweep": {"plane": [0, 3], "degrees": [0, 1]}, "target": [5]}, "animation.target\\[0\\]: object 5 does not exist"),
    ({"slerp": {"from": [[1, 0, 0, 0], [1, 0, 0, 0]], "to": [[2, 0, 0, 0], [1, 0, 0, 0]]}},
     "animation.slerp.to\\[0\\]: not a unit quaternion \\(\\|q\\| = 2"),
    ({"rolling": {"path": [[0, 0, 0], [1, 0]], "radius": 1}}, "animation.rolling.path\\[1\\]: expected 3 numbers"),
    ({"sweep": {"plane": [0, 3], "degrees": [0, 1]}, "spin": 1}, "animation.spin: unknown key \"spin\""),
])
def test_bad_animation_tables_raise_value_errors_naming_the_field(tmp_path, table, message):
    with pytest.raises(ValueError, match=message):
        ndtrace.animate(scene4(), tmp_path / "x.png", animation=table)
    assert os.listdir(tmp_path) == []


def test_bad_arguments(tmp_path):
    scene = scene4({"sweep": {"plane": [0, 3], "degrees": [0, 1]}})
    for kwargs, message in [({"frames": 0}, "frames: expected a positive integer"),
                            ({"video": "avi"}, "video: expected 'gif', 'mp4' or None"),
                            ({"threads": 0}, "threads: expected a positive integer")]:
        with pytest.raises(ValueError, match=message):
            ndtrace.animate(scene, tmp_path / "x.png", **kwargs)
    with pytest.raises(ValueError, match="unknown extension"):
        ndtrace.animate(scene, tmp_path / "x.exr")
    with pytest.raises(ValueError, match="folder .* does not exist"):
        ndtrace.animate(scene, tmp_path / "no" / "x.png")
    three = scene4({"frames": 3, "sweep": {"plane": [0, 3], "degrees": [0, 1]}})
    with pytest.raises(ValueError, match="frame 7 does not exist"):
        frame_scene(three, 7)
    for k in (-1, 2**40, 1.5, True):
        with pytest.raises(ValueError, match="k: expected a frame index"):
            frame_scene(three, k)
    with pytest.raises(ValueError, match="animation.frames: integer out of range"):
        ndtrace.animate(scene, tmp_path / "x.png", animation={"frames": -2, "sweep": {"plane": [0, 3], "degrees": [0, 1]}})
    assert os.listdir(tmp_path) == []


def test_a_gif_too_large_for_memory_is_refused_before_any_work(tmp_path, monkeypatch):
    monkeypatch.setattr(ndtrace.animation, "GIF_MEMORY_LIMIT", 10 * 16 * 16)
    scene = scene4({"frames": 11, "sweep": {"plane": [0, 3], "degrees": [0, 1]}}, res=4)
    with pytest.raises(ValueError, match="a GIF of 11 frames of 16×16 would hold .* write an MP4"):
        ndtrace.animate(scene, tmp_path / "x.gif", composite={"size": [16, 16]})
    assert os.listdir(tmp_path) == []
    assert len(ndtrace.animate(scene, tmp_path / "x.png", frames=10, composite={"size": [16, 16]})) == 11


@pytest.mark.parametrize("output", ["stop.gif", "stop.mp4"])
def test_ctrl_c_keeps_finished_frames_and_leaves_no_video(tmp_path, output):
    if output.endswith(".mp4"):
        pytest.importorskip("imageio_ffmpeg")
    scene = scene4({"frames": 4, "sweep": {"plane": [0, 3], "degrees": [0, 30]}}, res=6)
    cells = 6 ** 3

    def interrupt(done, total):
        if done > 2 * cells:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        ndtrace.animate(scene, tmp_path / output, composite={"size": [16, 16]}, progress=interrupt,
                        keep_frames=True)
    assert sorted(os.listdir(tmp_path)) == ["stop_0001.png", "stop_0002.png"]
    with pytest.raises(KeyboardInterrupt):
        ndtrace.animate(scene, tmp_path / ("again" + output[4:]), composite={"size": [16, 16]},
                        progress=interrupt)
    assert sorted(os.listdir(tmp_path)) == ["stop_0001.png", "stop_0002.png"]  # no video, no frames


def test_the_animation_table_round_trips_through_toml():
    scene = ndtrace.load_file(SPIN)
    again = ndtrace.load_toml(scene.to_toml())
    assert again == scene
    assert again.to_dict()["animation"] == {"frames": 24, "fps": 12.0, "periodic": True,
                                            "target": "objects",
                                            "sweep": {"plane": (0, 3), "degrees": (0.0, 90.0)}}


def run_cli(*args, cwd):
    return subprocess.run([sys.executable, "-m", "ndtrace.cli", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=120)


def test_cli_frames(tmp_path):
    r = run_cli(SPIN, "-o", "spin.png", "--frames", "3", "--size", "32x32", "--resolution", "8",
                cwd=tmp_path)
    assert r.returncode == 0, r.stderr
    assert sorted(os.listdir(tmp_path)) == ["spin.gif", "spin_0001.png", "spin_0002.png", "spin_0003.png"]
    assert "wrote 3 frames spin_0001.png … spin_0003.png and spin.gif" in r.stderr
    assert Image.open(tmp_path / "spin.gif").n_frames == 3
    r = run_cli(SPIN, "-o", "only.gif", "--resolution", "6", "--size", "16x16", "--quiet", cwd=tmp_path)
    assert r.returncode == 0 and r.stderr == ""
    assert Image.open(tmp_path / "only.gif").n_frames == 24  # the table's count
    r = run_cli(SPIN, "-o", "f.png", "--frames", "2", "--video", "none", "--resolution", "6",
                "--size", "16x16", cwd=tmp_path)
    assert r.returncode == 0 and not (tmp_path / "f.gif").exists()


@pytest.mark.parametrize("args, message", [
    (["scenes/tesseract.toml", "-o", "x.gif"], "scenes/tesseract.toml: the scene has no [animation] table"),
    ([SPIN, "-o", "x.png", "--frames", "0"], "--frames: must be at least 1"),
    ([SPIN, "-o", "x.exr", "--frames", "2"], "unknown extension: expected .png or .gif or .mp4"),
    ([SPIN, "-o", "x.gif", "--retina", "r.exr"], "--retina: a retina is written for a still"),
])
def test_cli_frame_errors(tmp_path, args, message):
    r = run_cli(*[a if not a.startswith("scenes/") else os.path.join(ROOT, a) for a in args], cwd=tmp_path)
    assert r.returncode == 2
    assert message.replace("scenes/", os.path.join(ROOT, "scenes") + "/") in r.stderr
    assert [p for p in os.listdir(tmp_path)] == []


def test_slerp_and_rolling_frames_match_ndtrace_rotation():
    from ndtrace import rotation

    h = np.sqrt(0.5)
    qp0 = (np.array([1.0, 0, 0, 0]), np.array([h, 0, h, 0]))
    qp1 = (np.array([h, h, 0, 0]), np.array([0.5, 0.5, 0.5, 0.5]))
    anim = scene4({"frames": 5, "target": [0],
                   "slerp": {"from": [list(qp0[0]), list(qp0[1])], "to": [list(qp1[0]), list(qp1[1])]}})
    for k in range(5):
        m = np.array(frame_scene(anim, k).to_dict()["objects"][0]["transform"][-1]["matrix"])
        want = rotation.so4_from_quaternions(*rotation.slerp_so4(qp0, qp1, k / 4))
        np.testing.assert_allclose(m, want, atol=1e-12)
    path = [[0, 0, 0], [0.5, 0, 0], [0.5, 0.5, 0.2]]
    anim = scene4({"frames": 3, "target": [0], "center": [0, 0, 0, 1],
                   "rolling": {"path": path, "radius": 0.8, "angle": "arc"}})
    m = np.array(frame_scene(anim, 2).to_dict()["objects"][0]["transform"][-1]["matrix"])
    r = rotation.compose([rotation.rolling_ball(np.subtract(b, a), 0.8, angle="arc")
                          for a, b in zip(path, path[1:])])
    np.testing.assert_allclose(m[:4, :4], r, atol=1e-12)
    np.testing.assert_allclose(m[:4, 4], np.array([0, 0, 0, 1]) - r @ [0, 0, 0, 1], atol=1e-12)
    # Frame 1 (t = ½) is half the path length: segment lengths 0.5 and √0.29, so the controller
    # has gone all of the first and a part f of the second.
    second = np.subtract(path[2], path[1])
    total = 0.5 + np.linalg.norm(second)
    f = (total / 2 - 0.5) / np.linalg.norm(second)
    half = rotation.compose([rotation.rolling_ball([0.5, 0, 0], 0.8, angle="arc"),
                             rotation.rolling_ball(f * second, 0.8, angle="arc")])
    m = np.array(frame_scene(anim, 1).to_dict()["objects"][0]["transform"][-1]["matrix"])
    np.testing.assert_allclose(m[:4, :4], half, atol=1e-12)


ANIMATED = [p for p in sorted(os.listdir(os.path.join(ROOT, "scenes"))) if p.endswith(".toml")
            and "[animation]" in open(os.path.join(ROOT, "scenes", p), encoding="utf-8").read()]


@pytest.mark.parametrize("name", ANIMATED)
def test_every_animated_example_scene_animates(tmp_path, name):
    scene = ndtrace.load_file(os.path.join(ROOT, "scenes", name))
    data = scene.to_dict()
    data["camera"]["resolution"] = 8
    small = ndtrace.load_dict(data)
    table = data["animation"]
    last = table["frames"] - 1
    first, final = (retina(frame_scene(small, k)) for k in (0, last))
    assert first.hit.any() and final.hit.any()
    assert not np.array_equal(first.depth, final.depth), "the last frame differs from the first"


def test_the_rolling_example_ends_turned_in_the_controller_plane():
    # Round a closed square, the rolling ball's net rotation stays off the hidden axis: the
    # last frame's rotation fixes e_3 (w) and e_2 and turns the (x, y) plane (the commutator).
    scene = ndtrace.load_file(os.path.join(ROOT, "scenes", "simplex4_rolling.toml"))
    last = frame_scene(scene, scene.to_dict()["animation"]["frames"] - 1).to_dict()
    m = np.array(last["objects"][0]["transform"][-1]["matrix"])
    path = scene.to_dict()["animation"]["rolling"]["path"]
    from ndtrace import rotation
    want = rotation.compose([rotation.rolling_ball(np.subtract(b, a), 1.0, angle="arc")
                             for a, b in zip(path, path[1:])])
    np.testing.assert_allclose(m, want, atol=1e-12)
    assert abs(m[2, 2] - 1) < 0.1 and abs(m[3, 3] - 1) < 0.35
    assert m[1, 0] < -0.3, "counterclockwise loop: the object turns y toward x (against the loop)"


@pytest.mark.parametrize("target", ["camera", "objects", [0]])
def test_frames_that_reuse_the_bvh_equal_frames_built_anew(target):
    # A camera animation shares the scene's BVH; one that moves objects shares its BVHs too.
    anim = scene4({"frames": 3, "target": target, "center": [0.1, 0, 0, 0.2],
                   "sweep": {"plane": [0, 3], "degrees": [0, 60]}}, res=12)
    for k in range(3):
        reused = anim.compiled().reused_frame(k)
        assert reused is not None
        shared = frame_scene(anim, k)
        built = ndtrace.load_dict(anim.compiled().animation_frame(k))
        assert shared == built
        a, b = retina(shared), retina(built)
        for name in ("rgba", "depth", "normal", "object_id", "primitive_id"):
            assert np.array_equal(getattr(a, name).view(np.uint8), getattr(b, name).view(np.uint8)), name
        # The feature edges of the frames are seen as the new build sees its own.
        edges = shared.compiled().retina_edges(20.0)
        assert len(edges) > 0
        assert np.array_equal(edges, built.compiled().retina_edges(20.0))
        assert np.array_equal(ndtrace.composite(a, size=(48, 48)), ndtrace.composite(b, size=(48, 48)))
