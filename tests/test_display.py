"""Notebook display: ``Retina.__repr__`` / ``_repr_png_``, ``Scene._repr_png_``, ``ndtrace.show``
and ``ndtrace.widget`` (driven through its message handler, as the page's JS drives it)."""

from __future__ import annotations

import io
import threading
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import ndtrace
from ndtrace.files import to_srgb8

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def png_pixels(data: bytes) -> np.ndarray:
    image = Image.open(io.BytesIO(data))
    assert image.format == "PNG"
    return np.asarray(image)


@pytest.fixture(scope="module")
def tesseract():
    return ndtrace.load_file(SCENES / "tesseract.toml")


@pytest.fixture(scope="module")
def retina(tesseract):
    return ndtrace.trace(ndtrace.load_dict(dict(tesseract.to_dict(), camera=dict(
        tesseract.to_dict()["camera"], resolution=24))))


def test_retina_repr_is_one_short_line(retina):
    text = repr(retina)
    hit = retina.object_id >= 0
    d = retina.depth[hit]
    assert text == (f"<ndtrace.Retina dim=4 shape=24×24×24 hit={hit.mean():.1%} "
                    f"depth {d.min():.4g}…{d.max():.4g}>")
    assert len(text) < 100 and "\n" not in text
    empty = ndtrace.Retina(dim=3, rgba=np.zeros((2, 3, 4), np.float32), depth=np.full((2, 3), np.inf, np.float32),
                           normal=np.zeros((2, 3, 3), np.float32), object_id=np.full((2, 3), -1, np.int32),
                           primitive_id=np.full((2, 3), -1, np.int64))
    assert repr(empty) == "<ndtrace.Retina dim=3 shape=2×3 hit=0.0% no hits>"


def test_retina_png_is_the_default_composite(retina):
    got = png_pixels(retina._repr_png_())
    np.testing.assert_array_equal(got, to_srgb8(ndtrace.composite(retina), opaque=True))


def test_scene_png_is_a_small_trace(tesseract):
    got = png_pixels(tesseract._repr_png_())
    assert got.shape == (384, 384, 3)
    data = tesseract.to_dict()
    data["camera"]["resolution"] = [48, 48, 48]
    data["render"]["samples"] = 1
    small = ndtrace.load_dict(data)
    from ndtrace.composite import scene_options

    want = to_srgb8(ndtrace.composite(ndtrace.trace(small), **dict(scene_options(data), size=(384, 384))), opaque=True)
    np.testing.assert_array_equal(got, want)
    square = ndtrace.load_file(SCENES / "square.toml")  # a 2D scene: a strip
    assert png_pixels(square._repr_png_()).ndim == 3
    cube = ndtrace.load_file(SCENES / "cube.toml")  # a 3D scene: the retina is the picture
    assert png_pixels(cube._repr_png_()).shape[2] == 3


def test_show_takes_pictures_retinas_and_scenes(retina, tesseract, tmp_path):
    picture = ndtrace.composite(retina, mode="mip", size=(64, 48))
    shown = ndtrace.show(picture)
    assert repr(shown) == "<ndtrace picture 64×48>"
    np.testing.assert_array_equal(png_pixels(shown._repr_png_()), to_srgb8(picture, opaque=True))
    clear = png_pixels(ndtrace.show(picture, transparent=True)._repr_png_())
    np.testing.assert_array_equal(clear, to_srgb8(picture))
    np.testing.assert_array_equal(png_pixels(ndtrace.show(retina, mode="mip", size=(64, 48))._repr_png_()),
                                  to_srgb8(picture, opaque=True))
    grey = np.linspace(0, 1, 12, dtype=np.float32).reshape(3, 4)
    assert png_pixels(ndtrace.show(grey)._repr_png_()).shape == (3, 4)
    rgb8 = np.arange(2 * 3 * 3, dtype=np.uint8).reshape(2, 3, 3)
    np.testing.assert_array_equal(png_pixels(ndtrace.show(rgb8)._repr_png_()), rgb8)
    assert png_pixels(ndtrace.show(tesseract, size=(40, 30))._repr_png_()).shape == (30, 40, 3)
    shown.save(tmp_path / "p.png")
    np.testing.assert_array_equal(np.asarray(Image.open(tmp_path / "p.png")), to_srgb8(picture, opaque=True))


@pytest.mark.parametrize("bad, match", [
    ("picture.png", "image_or_retina: expected a picture array"),
    (None, "image_or_retina: expected a picture array"),
    (np.zeros((4, 4, 5)), r"image_or_retina: expected an image of shape \(H, W\)"),
    (np.full((2, 2, 4), np.nan, np.float32), "NaN"),
])
def test_show_refuses_what_is_not_a_picture(bad, match):
    with pytest.raises(ValueError, match=match):
        ndtrace.show(bad)


def test_show_composite_keywords_need_a_retina():
    with pytest.raises(ValueError, match="mode: composite keywords go with a Retina"):
        ndtrace.show(np.zeros((2, 2, 4), np.float32), mode="mip")


def test_widget_works_on_every_call(tesseract):
    """``ndtrace.viewer.widget`` and ``ndtrace.widget`` make a widget each time they are called
    (the first call used to replace the function by its submodule of the same name: the second
    raised TypeError: 'module' object is not callable)."""
    pytest.importorskip("anywidget")
    import ndtrace.viewer.widget  # noqa: F401 - the submodule, as a script may import it

    widgets = []
    try:
        for _ in range(2):
            widgets.append(ndtrace.viewer.widget(tesseract, size=(8, 8)))
            widgets.append(ndtrace.widget(tesseract, size=(8, 8)))
        assert len(widgets) == 4 and all(w.session.scene is tesseract for w in widgets)
        assert ndtrace.viewer.widget is ndtrace.widget
    finally:
        for w in widgets:
            w.close()


def test_widget_runs_the_viewer_over_custom_messages(tesseract):
    """The widget answers the page's messages as the server does and sends frames as buffers."""
    pytest.importorskip("anywidget")
    w = ndtrace.widget(tesseract, size=(64, 64), draft_cells=8 ** 3)
    sent, cond = [], threading.Condition()

    def send(content, buffers=None):
        with cond:
            sent.append((content, buffers))
            cond.notify_all()

    w.send = send
    try:
        assert "export function mount" in w._esm and "export default" in w._esm and "render({ model, el })" in w._esm
        assert ".ndv" in w._css
        w._on_message(w, {"type": "hello", "seq": 1}, [])
        w._on_message(w, {"type": "roll", "seq": 2, "steps": [[20, 0]]}, [])
        w._on_message(w, {"type": "release", "seq": 3}, [])
        w._on_message(w, {"type": "zoom", "seq": 4, "factor": -2}, [])
        with cond:
            assert cond.wait_for(lambda: any(c.get("quality") == "full" and c["type"] == "frame" for c, _ in sent), 30)
        replies = [c["type"] for c, _ in sent if c["type"] != "frame"]  # frames come from the worker
        assert replies[:4] == ["hello", "state", "state", "error"]
        error = next(c for c, _ in sent if c["type"] == "error")
        assert error["seq"] == 4 and "zoom.factor" in error["message"]
        frame, buffers = next((c, b) for c, b in sent if c["type"] == "frame" and c["quality"] == "full")
        assert Image.open(io.BytesIO(buffers[0])).size == (64, 64)
        np.testing.assert_allclose(w.rotation, ndtrace.rotation.rolling_ball([20, 0, 0], 32), atol=1e-14)
        assert ndtrace.load_toml(w.to_toml()).dim == 4
    finally:
        w.close()
