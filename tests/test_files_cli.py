"""EXR/PNG files (against the official OpenEXR package) and the ``ndtrace`` command line."""

from __future__ import annotations

import os
import signal
import subprocess
import sys

import numpy as np
import pytest

import ndtrace

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OpenEXR = pytest.importorskip("OpenEXR")


def small_scene(dim: int, res: int = 8) -> ndtrace.Scene:
    d = {
        "dim": dim,
        "camera": {"position": [0.3] * (dim - 1) + [4.0], "look_at": [0.0] * dim,
                   "up": [[1.0 if i == k + 1 else 0.0 for i in range(dim)] for k in range(dim - 2)],
                   "fov": 50, "resolution": res},
        "lights": [{"type": "directional", "direction": [0.2] * (dim - 1) + [1.0]}],
        "objects": [{"shape": "hypercube", "transform": [{"scale": 0.8}]}],
    }
    return ndtrace.load_dict(d)


@pytest.mark.parametrize("dim", [2, 3, 4, 5])
def test_retinas_round_trip_through_exr(tmp_path, dim):
    r = ndtrace.trace(small_scene(dim))
    assert r.hit.any()
    path = tmp_path / "r.exr"
    ndtrace.write_exr(path, r)
    back = ndtrace.read_exr(path)
    assert isinstance(back, ndtrace.Retina) and back.shape == r.shape and back.dim == dim
    for k in ("rgba", "depth", "normal", "object_id", "primitive_id"):
        np.testing.assert_array_equal(getattr(back, k), getattr(r, k), err_msg=k)
    assert "[camera]" in back.camera


def test_retina_files_open_in_openexr_with_the_same_values(tmp_path):
    r = ndtrace.trace(small_scene(4, res=6))
    path = tmp_path / "r.exr"
    ndtrace.write_exr(path, r)
    f = OpenEXR.File(str(path), separate_channels=True)
    assert len(f.parts) == r.shape[0]  # one part per 2D slice, nothing else
    for k, part in enumerate(f.parts):
        ch = part.channels
        for c, name in enumerate("RGBA"):
            np.testing.assert_array_equal(ch[name].pixels, r.rgba[k, ..., c])
        np.testing.assert_array_equal(ch["Z"].pixels, r.depth[k])
        for a in range(4):
            np.testing.assert_array_equal(ch[f"N.{a}"].pixels, r.normal[k, ..., a])
        np.testing.assert_array_equal(ch["objectId"].pixels.astype(np.int64) - 1, r.object_id[k])
        pid = (ch["primitiveId.hi"].pixels.astype(np.int64) << 32) | ch["primitiveId.lo"].pixels.astype(np.int64)
        np.testing.assert_array_equal(pid - 1, r.primitive_id[k])
        assert part.header["ndtrace.dim"] == 4
        assert part.header["ndtrace.retinaShape"] == "6,6,6"
        assert part.header["ndtrace.slice"] == k
        assert "ZIP" in str(part.header["compression"]).upper()


def test_pictures_round_trip_and_openexr_files_read_in_ndtrace(tmp_path):
    rng = np.random.default_rng(5)
    img = rng.random((7, 9, 4)).astype(np.float32)
    depth = rng.random((7, 9)).astype(np.float32)
    p = tmp_path / "img.exr"
    ndtrace.write_exr(p, img, depth=depth)
    np.testing.assert_array_equal(ndtrace.read_exr(p), img)
    f = OpenEXR.File(str(p), separate_channels=True)
    np.testing.assert_array_equal(f.parts[0].channels["G"].pixels, img[..., 1])
    np.testing.assert_array_equal(f.parts[0].channels["Z"].pixels, depth)
    # An RGB file written by OpenEXR itself (no alpha: reads as opaque).
    rgb = rng.random((5, 6, 3)).astype(np.float32)
    q = tmp_path / "openexr.exr"
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                 {"RGB": rgb}).write(str(q))
    back = ndtrace.read_exr(q)
    np.testing.assert_array_equal(back[..., :3], rgb)
    np.testing.assert_array_equal(back[..., 3], 1.0)


def read_image(path) -> tuple[str, np.ndarray]:
    from PIL import Image

    with Image.open(path) as im:
        return im.mode, np.asarray(im)


def test_transparent_png_is_8_bit_srgb_with_straight_alpha(tmp_path):
    img = np.zeros((2, 3, 4), np.float32)
    img[0, 0] = [0.5, 0.5, 0.5, 1.0]  # linear 0.5 → sRGB 188
    img[0, 1] = [0.25, 0.0, 0.0, 0.5]  # premultiplied: straight red 0.5 at alpha 0.5
    p = tmp_path / "x.png"
    ndtrace.write_png(p, img, transparent=True)
    mode, a = read_image(p)
    assert mode == "RGBA" and a.shape == (2, 3, 4)
    assert tuple(a[0, 0]) == (188, 188, 188, 255)
    assert tuple(a[0, 1]) == (188, 0, 0, 128)
    assert tuple(a[1, 2]) == (0, 0, 0, 0)
    # By default the colour is written as it is, opaque: linear 0.25 → sRGB 137.
    ndtrace.write_png(p, img)
    mode, a = read_image(p)
    assert mode == "RGB" and tuple(a[0, 0]) == (188, 188, 188) and tuple(a[0, 1]) == (137, 0, 0)


def test_png_of_a_white_background_scene_is_white_around_the_object(tmp_path):
    d = small_scene(3, res=16).to_dict()
    d["background"] = [1.0, 1.0, 1.0]
    scene = ndtrace.load_dict(d)
    from ndtrace.composite import scene_options

    picture = ndtrace.composite(ndtrace.trace(scene), **scene_options(d), size=(32, 32))
    ndtrace.write_png(tmp_path / "w.png", picture)
    _, a = read_image(tmp_path / "w.png")
    assert a.shape == (32, 32, 3)
    assert tuple(a[0, 0]) == (255, 255, 255) and tuple(a[-1, -1]) == (255, 255, 255)
    assert a[16, 16].max() < 250  # the cube
    p = cli("scenes/cube.toml", "-o", str(tmp_path / "c.png"), "--resolution", "16", "--size", "32x32",
            "--set", "background=[1, 1, 1]", "--quiet")
    assert p.returncode == 0, p.stderr
    mode, a = read_image(tmp_path / "c.png")
    assert mode == "RGB" and tuple(a[0, 0]) == (255, 255, 255)
    p = cli("scenes/cube.toml", "-o", str(tmp_path / "t.png"), "--resolution", "16", "--size", "32x32",
            "--set", "background=[1, 1, 1]", "--transparent", "--quiet")
    assert p.returncode == 0, p.stderr
    mode, t = read_image(tmp_path / "t.png")
    assert mode == "RGBA" and tuple(t[0, 0]) == (0, 0, 0, 0) and t[16, 16, 3] == 255
    np.testing.assert_array_equal(t[16, 16, :3], a[16, 16])  # the opaque cube, either way


def test_uint8_images_are_written_unchanged_in_every_shape(tmp_path):
    rng = np.random.default_rng(2)
    for shape, mode in (((4, 5), "L"), ((4, 5, 3), "RGB"), ((4, 5, 4), "RGBA")):
        img = rng.integers(0, 256, size=shape, dtype=np.uint8)
        img.flat[0] = 128
        for ext in (".png", ".tif", ".webp") if mode != "L" else (".png", ".tif"):
            path = tmp_path / f"u{len(shape)}{ext}"
            if ext == ".webp":
                ndtrace.write_image(path, img, quality=100)
                continue  # lossy: only readable
            ndtrace.write_image(path, img)
            got_mode, got = read_image(path)
            assert got_mode == mode, ext
            np.testing.assert_array_equal(got, img, err_msg=ext)
    # Float grey and RGB pictures are linear and opaque.
    ndtrace.write_png(tmp_path / "g.png", np.full((2, 2), 0.5))
    assert read_image(tmp_path / "g.png")[0] == "L" and read_image(tmp_path / "g.png")[1][0, 0] == 188
    ndtrace.write_png(tmp_path / "c.png", np.full((2, 2, 3), [1.0, 0.0, 0.5]))
    assert tuple(read_image(tmp_path / "c.png")[1][1, 1]) == (255, 0, 188)


def test_jpeg_output(tmp_path):
    p = cli("scenes/cube.toml", "-o", str(tmp_path / "c.jpg"), "--resolution", "16", "--size", "40x30",
            "--quiet")
    assert p.returncode == 0, p.stderr
    assert (tmp_path / "c.jpg").read_bytes()[:3] == b"\xff\xd8\xff"
    mode, a = read_image(tmp_path / "c.jpg")
    assert mode == "RGB" and a.shape == (30, 40, 3)
    png = cli("scenes/cube.toml", "-o", str(tmp_path / "c.png"), "--resolution", "16", "--size", "40x30",
              "--quiet")
    assert png.returncode == 0
    assert np.abs(a.astype(int) - read_image(tmp_path / "c.png")[1].astype(int)).mean() < 4
    with pytest.raises(ValueError, match="JPEG has no alpha channel"):
        ndtrace.write_image(tmp_path / "x.jpg", np.zeros((2, 2, 4)), transparent=True)
    p = cli("scenes/cube.toml", "-o", str(tmp_path / "x.jpg"), "--transparent")
    assert p.returncode == 2 and "--transparent" in p.stderr


def test_bad_files_and_paths_are_clear_errors(tmp_path):
    junk = tmp_path / "junk.exr"
    junk.write_bytes(b"not an exr at all")
    with pytest.raises(OSError, match="not a readable OpenEXR file"):
        ndtrace.read_exr(junk)
    with pytest.raises(OSError, match="cannot read"):
        ndtrace.read_exr(tmp_path / "missing.exr")
    with pytest.raises(ValueError, match="unknown extension"):
        ndtrace.write_exr(tmp_path / "x.tiff", np.zeros((2, 2, 4)))
    with pytest.raises(OSError, match="does not exist"):
        ndtrace.write_png(tmp_path / "nope" / "x.png", np.zeros((2, 2, 4)))
    with pytest.raises(ValueError, match=r"image: expected an image of shape \(H, W\), \(H, W, 3\) or \(H, W, 4\)"):
        ndtrace.write_png(tmp_path / "x.png", np.zeros((2, 2, 2)))
    with pytest.raises(ValueError, match="unknown extension"):
        ndtrace.write_image(tmp_path / "x.bmp", np.zeros((2, 2, 4)))


def test_a_failed_write_leaves_the_old_file(tmp_path):
    target = tmp_path / "keep.png"
    target.write_bytes(b"precious")
    with pytest.raises(ValueError):
        ndtrace.write_png(target, np.full((2, 2, 4), np.nan))
    assert target.read_bytes() == b"precious"
    assert [p.name for p in tmp_path.iterdir()] == ["keep.png"]


# -- the command line ------------------------------------------------------------------


def cli(*args, **kw) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ndtrace.cli", *args], capture_output=True,
                          text=True, cwd=kw.pop("cwd", ROOT), timeout=kw.pop("timeout", 120), **kw)


def test_cli_renders_a_scene_to_png_and_exr(tmp_path):
    out, ret = tmp_path / "t.png", tmp_path / "r.exr"
    p = cli("scenes/tesseract.toml", "-o", str(out), "--retina", str(ret), "--resolution", "16",
            "--size", "64x48", "--quiet")
    assert p.returncode == 0, p.stderr
    from PIL import Image

    with Image.open(out) as im:
        assert im.size == (64, 48)
    r = ndtrace.read_exr(ret)
    assert r.shape == (16, 16, 16) and r.hit.any()
    p = cli("scenes/cube.toml", "-o", str(tmp_path / "c.exr"), "--resolution", "24", "--size", "48x48",
            "--quiet")
    assert p.returncode == 0, p.stderr
    img = ndtrace.read_exr(tmp_path / "c.exr")
    assert img.shape == (48, 48, 4)
    assert img[24, 24, 3] == 1.0 and img[0, 0, 3] == 0.0  # the cube in the middle, background around


def test_cli_errors_are_one_line_with_exit_status_2(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text((open(os.path.join(ROOT, "scenes", "cube.toml")).read())
                   .replace('shape = "hypercube"', 'shape = "hypercub"'))
    p = cli(str(bad), "-o", str(tmp_path / "x.png"))
    assert p.returncode == 2
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1, p.stderr
    line_no = next(i for i, l in enumerate(bad.read_text().splitlines(), 1) if "hypercub" in l)
    assert lines[0].startswith(f"ndtrace: error: {bad}:{line_no}:9: objects[0].shape: unknown shape "
                               '"hypercub" (did you mean "hypercube"?)'), lines[0]
    assert not (tmp_path / "x.png").exists()
    p = cli("scenes/cube.toml", "-o", str(tmp_path / "x.bmp"))
    assert p.returncode == 2 and "unknown extension" in p.stderr and "Traceback" not in p.stderr
    p = cli("scenes/cube.toml", "-o", str(tmp_path / "no" / "x.png"))
    assert p.returncode == 2 and "does not exist" in p.stderr
    p = cli("scenes/missing.toml", "-o", str(tmp_path / "x.png"))
    assert p.returncode == 2 and p.stderr == "ndtrace: error: scenes/missing.toml: no such file\n"
    p = cli(str(bad), "-o", str(tmp_path / "x.png"), "--debug")
    assert p.returncode == 2 and "Traceback" in p.stderr


def test_cli_composite_flags_are_checked_by_the_core_under_their_names(tmp_path):
    out = tmp_path / "x.png"
    p = cli("scenes/cube.toml", "-o", str(out), "--size", "0x48")
    assert p.returncode == 2
    assert p.stderr.strip() == ("ndtrace: error: --size: composite.size: width and height must be "
                                "positive, got (0, 48)"), p.stderr
    p = cli("scenes/tesseract.toml", "-o", str(out), "--view", "nan,10")
    assert p.returncode == 2
    assert p.stderr.strip() == "ndtrace: error: --view: composite.azimuth: must be finite, got NaN", p.stderr
    # The choices are the core's names.
    p = cli("scenes/tesseract.toml", "-o", str(out), "--composite", "mpi")
    assert p.returncode == 2 and all(f"'{m}'" in p.stderr for m in ndtrace._ndtrace.COMPOSITE_MODES), p.stderr
    p = cli("scenes/tesseract.toml", "-o", str(out), "--mode", "shade")
    assert p.returncode == 2 and all(f"'{m}'" in p.stderr for m in ndtrace._ndtrace.RENDER_MODES), p.stderr
    assert ndtrace._ndtrace.RENDER_MODES == ("shaded", "depth", "normal", "primitive_id", "barycentric")
    assert not out.exists()


def test_cli_version_and_help():
    p = cli("--version")
    assert p.returncode == 0 and p.stdout.strip() == f"ndtrace {ndtrace.__version__}"
    p = subprocess.run([sys.executable, "-m", "ndtrace", "--version"], capture_output=True, text=True, cwd=ROOT)
    assert p.returncode == 0 and p.stdout.strip() == f"ndtrace {ndtrace.__version__}"
    p = cli("--help")
    assert p.returncode == 0 and "ndtrace scenes/tesseract.toml -o tesseract.png" in p.stdout


def test_cli_ctrl_c_stops_quickly_and_leaves_no_output(tmp_path):
    out = tmp_path / "t.png"
    out.write_bytes(b"previous picture")
    proc = subprocess.Popen(
        [sys.executable, "-m", "ndtrace.cli", "scenes/sphere3.toml", "-o", str(out),
         "--resolution", "200", "--samples", "4", "--threads", "1"],
        cwd=ROOT, stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    # Wait for the progress bar's first line (not for a fixed time, which a loaded machine can
    # outlast): the scene is validated and tracing has begun.
    first = proc.stderr.readline()
    assert "%" in first and proc.poll() is None, (first, proc.communicate())
    proc.send_signal(signal.SIGINT)
    # Stopping takes well under a second; the bound is for a machine loaded by other work.
    proc.wait(timeout=30)
    assert proc.returncode == 130, proc.stderr.read()
    assert out.read_bytes() == b"previous picture"
    assert [p.name for p in tmp_path.iterdir()] == ["t.png"]


def test_cli_set_overrides_nested_keys_and_its_errors_name_the_flag(tmp_path):
    out = tmp_path / "c.exr"
    p = cli("scenes/cube.toml", "-o", str(out), "--resolution", "12", "--size", "24x24", "--quiet",
            "--set", "camera.fov=30", "--set", "objects.0.material.color=[1,0,0]",
            "--set", "composite.mode=first_hit", "--set", "render.shadows=false")
    assert p.returncode == 0, p.stderr
    d = ndtrace.load_file(os.path.join(ROOT, "scenes", "cube.toml")).to_dict()
    d["camera"].update(fov=30, resolution=12)
    d["objects"][0]["material"]["color"] = [1, 0, 0]
    d["render"]["shadows"] = False
    scene = ndtrace.load_dict(d, base=os.path.join(ROOT, "scenes"))
    expected = ndtrace.composite(ndtrace.trace(scene), mode="first_hit", size=(24, 24),
                                 background=d["background"])
    np.testing.assert_array_equal(ndtrace.read_exr(out), expected)
    cases = [
        (["--set", "camera.fov=400"], "ndtrace: error: --set camera.fov=400: camera.fov: must be between 0 and 180 degrees, got 400"),
        (["--set", "camera.fov=40", "--set", "objects.0.material.colr=[1,0,0]"],
         'ndtrace: error: --set objects.0.material.colr=[1,0,0]: objects[0].material.colr: unknown key "colr" (did you mean "color"?)'),
        (["--set", "objects.3.material.color=[1,0,0]"], "ndtrace: error: --set objects.3.material.color=[1,0,0]: objects has 1 entries, no 3"),
        (["--set", "camera"], "ndtrace: error: --set camera: expected KEY.PATH=VALUE, e.g. camera.fov=40"),
    ]
    for extra, want in cases:
        p = cli("scenes/cube.toml", "-o", str(tmp_path / "x.png"), *extra)
        assert p.returncode == 2 and p.stderr.strip() == want, p.stderr


def test_cli_videos_alone_unless_keep_frames(tmp_path):
    args = ["scenes/tesseract_spin.toml", "--frames", "3", "--resolution", "8", "--size", "24x24", "--quiet"]
    p = cli(*args, "-o", str(tmp_path / "spin.gif"))
    assert p.returncode == 0, p.stderr
    assert sorted(x.name for x in tmp_path.iterdir()) == ["spin.gif"]
    p = cli(*args, "-o", str(tmp_path / "keep.gif"), "--keep-frames")
    assert p.returncode == 0, p.stderr
    assert sorted(x.name for x in tmp_path.iterdir()) == ["keep.gif", "keep_0001.png", "keep_0002.png",
                                                         "keep_0003.png", "spin.gif"]
    mode, first = read_image(tmp_path / "keep_0001.png")
    assert mode == "RGB" and first.shape == (24, 24, 3)  # frames are opaque, as the GIF
