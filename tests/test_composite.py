"""Tests of ``ndtrace.composite``: retinas into 2D pictures.

Expectations are computed here from the documented conventions (``ndtrace.composite``'s
docstring, ``crates/ndtrace/src/composite.rs``):

* a 3D retina (slices, rows, columns) is a cube with its longest side spanning [−1, 1], world
  x along the columns, y up the rows (row 0 on top), z along the slices;
* at azimuth = elevation = 0 the camera looks along +z (slice 0 nearest) with x right, y up;
* an orthographic view's shorter side spans the cube's bounding sphere, radius = half-diagonal;
* RGB is composited over the opaque background, alpha is the content's opacity.
"""

from __future__ import annotations

import importlib
import math

import numpy as np
import pytest

import ndtrace

composite_module = importlib.import_module("ndtrace.composite")


@pytest.fixture(scope="module")
def tesseract() -> ndtrace.Retina:
    scene = ndtrace.load_file("scenes/tesseract.toml")
    desc = scene.to_dict()
    desc["camera"]["resolution"] = 24
    return ndtrace.trace(ndtrace.load_dict(desc))


def face_on_cell(shape, size, px, py):
    """(row, column, distance to the nearest cell edge in cells) seen by the centre of pixel
    (px, py) in a face-on orthographic view, or None outside the cube's footprint."""
    c = 2.0 / max(shape)
    hx, hy, hz = shape[2] * c / 2, shape[1] * c / 2, shape[0] * c / 2
    r = math.sqrt(hx * hx + hy * hy + hz * hz)
    pw = 2 * r / min(size)
    x = (px + 0.5 - size[0] / 2) * pw
    y = (size[1] / 2 - py - 0.5) * pw
    u, v = (x + hx) / c, (hy - y) / c
    if not (0 < u < shape[2] and 0 < v < shape[1]):
        return None
    edge = min(u - math.floor(u), math.ceil(u) - u, v - math.floor(v), math.ceil(v) - v)
    return int(v), int(u), edge


def test_first_hit_of_a_traced_tesseract_shows_the_nearest_cells(tesseract):
    # First-hit is the smooth surface where the interpolated coverage reaches ½: face on, a
    # pixel whose column of cells (and its neighbours') is empty shows the background, and a
    # pixel over the inside of the covered region is opaque, in a colour between the straight
    # colours of the cells around its column.
    rgba = tesseract.rgba
    shape = rgba.shape[:3]
    assert shape == (24, 24, 24)
    bg = (0.2, 0.3, 0.4)
    size = (96, 80)
    img = ndtrace.composite(tesseract, mode="first_hit", projection="orthographic", azimuth=0,
                            elevation=0, size=size, background=bg, fit=False, axes=False)
    assert img.shape == (80, 96, 4) and img.dtype == np.float32 and img.flags.c_contiguous
    occupied = rgba[..., 3] > 0
    straight = np.where(occupied[..., None], rgba[..., :3] / np.maximum(rgba[..., 3:], 1e-30), np.nan)
    background = np.array([*bg, 0.0], np.float32)
    inside = empty = 0
    for py in range(size[1]):
        for px in range(size[0]):
            cell = face_on_cell(shape, size, px, py)
            p = img[py, px]
            if cell is None:
                np.testing.assert_array_equal(p, background)
                continue
            row, col, _ = cell
            rows, cols = slice(max(row - 1, 0), row + 2), slice(max(col - 1, 0), col + 2)
            near = occupied[:, rows, cols]
            if not near.any():
                empty += 1
                np.testing.assert_array_equal(p, background)
            elif near.any(axis=0).all() and (rgba[:, rows, cols, 3].max(axis=0) >= 1).all():
                inside += 1
                assert p[3] == 1.0
                colours = straight[:, rows, cols].reshape(-1, 3)
                assert (p[:3] >= np.nanmin(colours, 0) - 1e-5).all() and (p[:3] <= np.nanmax(colours, 0) + 1e-5).all()
    assert inside > 300 and empty > 300
    assert img[0, 0, 3] == 0 and img[-1, -1, 3] == 0


def test_volume_picture_has_the_object_in_the_middle(tesseract):
    bg = np.array([0.05, 0.1, 0.15])
    img = ndtrace.composite(tesseract, size=(64, 48), background=bg, axes=False)
    alpha = img[..., 3]
    # Drawn from the scene (the default), the illustrative interior is nearly clear, the
    # creases and contours behind the centre inked: well covered, not opaque.
    assert alpha[24, 32] > 0.5
    assert ndtrace.composite(tesseract, size=(64, 48), background=bg, detail="retina")[24, 32, 3] > 0.9
    # Corners: background, nothing in front of it.
    for y, x in [(0, 0), (0, 63), (47, 0), (47, 63)]:
        np.testing.assert_allclose(img[y, x], [*bg, 0.0], atol=1e-7)
    # The object's bounding box of covered pixels sits around the centre.
    ys, xs = np.nonzero(alpha > 0.01)
    assert abs((ys.min() + ys.max()) / 2 - 23.5) < 8 and abs((xs.min() + xs.max()) / 2 - 31.5) < 8
    # RGB = C + (1 − A)·bg: with a black background the colour is C itself.
    black = ndtrace.composite(tesseract, size=(64, 48), axes=False)
    np.testing.assert_allclose(img[..., :3], black[..., :3] + (1 - black[..., 3:]) * bg, atol=1e-6)
    np.testing.assert_array_equal(img[..., 3], black[..., 3])


def test_raw_arrays_and_retinas_give_the_same_picture(tesseract):
    a = ndtrace.composite(tesseract, mode="mip", size=(40, 30), axes=False)  # a raw array has no camera for the glyph
    b = ndtrace.composite(tesseract.rgba, mode="mip", size=(40, 30))
    c = ndtrace.composite(tesseract.rgba.astype(np.float64).tolist(), mode="mip", size=(40, 30))
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, c)


def test_depth_cue_tints_near_and_far_apart(tesseract):
    plain = ndtrace.composite(tesseract, mode="first_hit", size=(48, 48))
    cued = ndtrace.composite(tesseract, mode="first_hit", size=(48, 48), depth_cue=1.0)
    hit = plain[..., 3] > 0
    assert not np.allclose(plain[hit], cued[hit])
    # Warm near, cool far: the red/blue ratio of cued over plain follows the cell's depth.
    c, p = cued[hit], plain[hit]
    ratio = (c[:, 0] / c[:, 2]) / (p[:, 0] / p[:, 2])
    assert ratio.max() > 1.2 and ratio.min() < 1.0
    with pytest.raises(ValueError, match="depth_cue"):
        ndtrace.composite(tesseract.rgba, depth_cue=0.5)


def test_opacity_lets_the_inside_show(tesseract):
    solid = ndtrace.composite(tesseract, mode="volume", size=(48, 48))
    faint = ndtrace.composite(tesseract, mode="volume", size=(48, 48), opacity=0.02)
    assert faint[..., 3].max() < solid[..., 3].max()
    assert 0 < faint[24, 24, 3] < 0.9


def test_threads_do_not_change_the_picture(tesseract):
    for mode in ["volume", "mip", "first_hit", "slices"]:
        one = ndtrace.composite(tesseract, mode=mode, size=(70, 50), threads=1, opacity=0.3)
        two = ndtrace.composite(tesseract, mode=mode, size=(70, 50), threads=2, opacity=0.3)
        np.testing.assert_array_equal(one, two)


def test_slices_montage_places_slice_k_at_its_tile():
    rng = np.random.default_rng(5)
    shape = (7, 5, 6)
    a = (rng.random(shape) > 0.5).astype(np.float32)
    rgba = np.stack([rng.random(shape) * a, rng.random(shape) * a, rng.random(shape) * a, a], -1)
    rgba = rgba.astype(np.float32)
    size = (100, 90)
    img = ndtrace.composite(rgba, mode="slices", size=size, labels=False)
    # The documented layout: cols = ceil(sqrt(7)) = 3, rows = 3, 1-pixel separators.
    cols, rows, gap = 3, 3, 1
    s = min((size[0] - (cols + 1) * gap) / (cols * 6), (size[1] - (rows + 1) * gap) / (rows * 5))
    s = math.floor(s) if s >= 1 else s
    tw, th = int(6 * s), int(5 * s)
    mw, mh = cols * tw + (cols + 1) * gap, rows * th + (rows + 1) * gap
    ox, oy = (size[0] - mw) // 2, (size[1] - mh) // 2
    for k in range(7):
        tx = ox + gap + (k % cols) * (tw + gap)
        ty = oy + gap + (k // cols) * (th + gap)
        tile = img[ty:ty + th, tx:tx + tw]
        expect = np.repeat(np.repeat(rgba[k], s, axis=0), s, axis=1)
        np.testing.assert_array_equal(tile, expect)
    # The separators are opaque grey; the two empty tiles and the border are background.
    assert img[oy, ox, 3] == 1.0 and np.allclose(img[oy, ox, :3], 0.35)
    k = 8
    tx, ty = ox + gap + (k % cols) * (tw + gap), oy + gap + (k // cols) * (th + gap)
    assert np.all(img[ty:ty + th, tx:tx + tw] == 0)
    # Labels draw into the tile's top-left corner.
    labelled = ndtrace.composite(rgba, mode="slices", size=size)
    assert not np.array_equal(labelled, img)


def test_two_and_one_dimensional_retinas():
    rgba = np.zeros((3, 5, 4), np.float32)
    rgba[..., 0] = np.arange(15).reshape(3, 5) / 15
    rgba[..., 3] = 1
    native = ndtrace.composite(rgba, size=None)
    np.testing.assert_array_equal(native, rgba)
    big = ndtrace.composite(rgba, size=(20, 20))  # scale 4: a 20 × 12 picture at row 4
    np.testing.assert_array_equal(big[4:16], np.repeat(np.repeat(rgba, 4, 0), 4, 1))
    assert np.all(big[:4] == 0) and np.all(big[16:] == 0)
    strip = ndtrace.composite(rgba[0], size=None, strip_height=7)
    assert strip.shape == (7, 5, 4)
    np.testing.assert_array_equal(strip, np.broadcast_to(rgba[0], (7, 5, 4)))


def test_five_d_retina_constant_along_the_hidden_axis_reduces_to_one_slice():
    rng = np.random.default_rng(9)
    a = (rng.random((5, 6, 7)) > 0.6).astype(np.float32)
    slice4 = np.stack([rng.random(a.shape) * a, rng.random(a.shape) * a, 0.5 * a, a], -1).astype(np.float32)
    rgba5 = np.ascontiguousarray(np.broadcast_to(slice4, (4, *slice4.shape)))
    for mode in ["volume", "first_hit", "slices"]:
        kw = dict(mode=mode, projection="orthographic", size=(50, 40), azimuth=20, elevation=30)
        five = ndtrace.composite(rgba5, **kw)
        if mode == "slices":
            np.testing.assert_array_equal(five, ndtrace.composite(slice4, **kw))
            continue
        # The 5D view is the 4D view, its title (the axis the stage collapses) written over its
        # top margin: below that band the pictures are equal.
        layout = ndtrace._ndtrace.picture_layout(list(rgba5.shape[:-1]), kw)
        (panel,) = layout["panels"]
        assert panel["title"] == "retina axis u₄ projected orthographically"
        assert panel["rect"] == {"x": 0, "y": 0, "w": 50, "h": 40}
        band = panel["title_band"]["h"]
        four = ndtrace.composite(slice4, **kw)
        np.testing.assert_array_equal(five[band:], four[band:])
    # Perspective stages shrink far slices instead; stages must match N − 4.
    persp = ndtrace.composite(rgba5, size=(50, 40), stages=[(2.5, 3.0)])
    assert persp.shape == (40, 50, 4)
    with pytest.raises(ValueError, match="stages"):
        ndtrace.composite(rgba5, stages=[(2.5, 3.0), (2.5, 3.0)])


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(mode="volumes"), "mode"),
        (dict(projection="fisheye"), "projection"),
        (dict(size=(0, 10)), "size"),
        (dict(size=(10,)), "size"),
        (dict(size=(10.5, 10)), "size"),
        (dict(background=(1, 2)), "background"),
        (dict(background=(0, float("nan"), 0)), "background"),
        (dict(azimuth=float("nan")), "azimuth"),
        (dict(elevation=float("inf")), "elevation"),
        (dict(distance=0.9), "distance"),
        (dict(opacity=-0.1), "opacity"),
        (dict(depth_cue=1.5), "depth_cue"),
        (dict(mode="slices", axis=3), "axis"),
        (dict(axis=-1), "axis"),
        (dict(step=0), "step"),
        (dict(rays_per_cell=65), "rays_per_cell"),
        (dict(rays_per_cell=-1), "rays_per_cell"),
        (dict(zoom=0), "zoom"),
        (dict(threads=0), "threads"),
        (dict(strip_height=0), "strip_height"),
        (dict(stages=[(1.0,)]), "stages"),
        (dict(azimuth="30"), "azimuth"),
    ],
)
def test_bad_options_raise_value_errors_naming_the_argument(kwargs, name):
    rgba = np.zeros((4, 4, 4, 4), np.float32)
    with pytest.raises(ValueError, match=name):
        ndtrace.composite(rgba, **kwargs)


def test_wrongly_typed_keywords_say_what_was_expected():
    rgba = np.zeros((4, 4, 4, 4), np.float32)
    for kwargs, message in [(dict(azimuth="30"), "azimuth: expected a number, got str"),
                            (dict(size=(10.5, 10)), "size[0]: expected an integer, got float"),
                            (dict(axis=-1), "axis: integer out of range: expected a non-negative integer"),
                            (dict(size=(10,)), "size: expected sequence of length 2, got 1"),
                            (dict(mode="volumes"), 'mode: unknown mode "volumes" (did you mean "volume"?)')]:
        with pytest.raises(ValueError) as e:
            ndtrace.composite(rgba, **kwargs)
        assert str(e.value).startswith(message), e.value


@pytest.mark.parametrize(
    "retina",
    [np.zeros((4, 4, 3), np.float32), np.zeros((4,), np.float32), np.zeros((1,) * 8 + (4,), np.float32),
     "retina.npz", None, np.array([["a", "b", "c", "d"]])],
)
def test_bad_retinas_raise_value_errors(retina):
    with pytest.raises(ValueError, match="retina"):
        ndtrace.composite(retina)


def test_the_binding_checks_shapes_too():
    # The compiled kernel re-checks what the wrapper checks, naming the argument.
    with pytest.raises(ValueError, match="depth"):
        ndtrace._ndtrace.composite(np.zeros((2, 2, 2, 4), np.float32), np.zeros((2, 2), np.float32))
    with pytest.raises(ValueError, match="retina"):
        ndtrace._ndtrace.composite(np.zeros((2, 2, 2, 3), np.float32))
    with pytest.raises(ValueError, match="^mode: unknown mode \"x\""):
        ndtrace._ndtrace.composite(np.zeros((2, 2, 2, 4), np.float32), None, {"mode": "x"})
    with pytest.raises(ValueError, match="^options: "):
        ndtrace._ndtrace.composite(np.zeros((2, 2, 2, 4), np.float32), None, ["volume"])
    with pytest.raises(ValueError, match='unknown key "zooom" \\(did you mean "zoom"\\?\\)'):
        ndtrace._ndtrace.composite(np.zeros((2, 2, 2, 4), np.float32), None, {"zooom": 2})


def test_keyword_defaults_are_the_cores():
    """``ndtrace.composite``'s keywords are the core's options with the core's defaults (None
    stands for the core's black background and default stages, as documented)."""
    import inspect

    core = ndtrace._ndtrace.composite_defaults()
    params = inspect.signature(ndtrace.composite).parameters
    keywords = {k: p.default for k, p in params.items() if p.kind is p.KEYWORD_ONLY and k != "threads"}
    assert sorted(keywords) == sorted(core)
    assert list(core)[:3] == ["mode", "azimuth", "elevation"]  # the fields' order
    documented_none = {"background": [0.0, 0.0, 0.0], "stages": []}
    for key, default in keywords.items():
        if default is None and core[key] is None:  # edge_color, cutaway: none by default
            continue
        if default is None:
            assert list(core[key]) == documented_none[key], key
        else:
            assert (list(default) if isinstance(default, tuple) else default) == (
                list(core[key]) if isinstance(core[key], tuple) else core[key]), key
    # The constants are the core's names.
    assert composite_module.MODES == ("volume", "mip", "first_hit", "slices", "illustrative") == ndtrace._ndtrace.COMPOSITE_MODES
    assert composite_module.PROJECTIONS == ("perspective", "orthographic")
    assert core["mode"] in composite_module.MODES


def test_a_bad_option_reads_the_same_as_a_keyword_a_dict_key_and_in_a_scene_file():
    rgba = np.zeros((4, 4, 4, 4), np.float32)
    scene = ndtrace.load_file("scenes/tesseract.toml").to_dict()
    text = open("scenes/tesseract.toml").read()
    for key, value, toml_value in [("opacity", -1, "-1"), ("step", 5.0, "5.0"), ("size", [0, 4], "[0, 4]"),
                                   ("distance", 0.5, "0.5"), ("background", [0, float("inf"), 0], "[0, inf, 0]"),
                                   ("zoom", 0, "0")]:
        with pytest.raises(ValueError) as keyword:
            ndtrace.composite(rgba, **{key: value})
        message = str(keyword.value)
        assert message.startswith(key), message
        with pytest.raises(ValueError) as from_dict:
            ndtrace.load_dict({**scene, "composite": {key: value}})
        assert str(from_dict.value) == f"<dict>: composite.{message}"
        bad = text + f"\n[composite]\n{key} = {toml_value}\n"
        with pytest.raises(ValueError) as from_file:
            ndtrace.load_toml(bad, name="t.toml")
        line = bad.count("\n")
        assert str(from_file.value).startswith(f"t.toml:{line}:"), from_file.value
        assert str(from_file.value).endswith(f": composite.{message}")


def test_the_composite_table_takes_every_keyword_and_is_written_back_as_given():
    text = open("scenes/simplex4.toml").read()
    extra = ("zoom = 1.5\nstep = 0.25\nbackground = [0.1, 0.2, 0.3]\nstrip_height = 9\n"
             "labels = false\n")
    scene = ndtrace.load_toml(text + '\n[composite]\nmode = "volume"\nopacity = 0.6\n' + extra)
    table = scene.to_dict()["composite"]
    assert table == {"mode": "volume", "zoom": 1.5, "opacity": 0.6, "step": 0.25,
                     "background": (0.1, 0.2, 0.3), "strip_height": 9, "labels": False}
    options = composite_module.scene_options(scene.to_dict())
    assert options["background"] == (0.1, 0.2, 0.3)  # the table's, not the scene's
    # The given default mode = "volume" stays; nothing else is added.
    assert scene.to_toml().split("[composite]\n")[1].split("\n\n")[0].splitlines() == [
        'mode = "volume"', "zoom = 1.5", "opacity = 0.6", "step = 0.25", "background = [0.1, 0.2, 0.3]",
        "strip_height = 9", "labels = false"]
    assert ndtrace.load_toml(scene.to_toml()) == scene
    retina = ndtrace.trace(ndtrace.load_dict({**scene.to_dict(), "camera": {**scene.to_dict()["camera"], "resolution": 8}}))
    a = ndtrace.composite(retina, **{**options, "size": (32, 24)})
    b = ndtrace.composite(retina, mode="volume", zoom=1.5, opacity=0.6, step=0.25, background=(0.1, 0.2, 0.3), size=(32, 24))
    np.testing.assert_array_equal(a, b)
