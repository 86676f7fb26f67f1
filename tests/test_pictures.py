"""Display aids of the composite (turntable, stereo, sections, cutaways), the smooth first-hit
surface, and the SVG hidden-line drawing (rasterized with resvg and compared with the raster
composite's edges)."""

from __future__ import annotations

import io
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

import ndtrace

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"


@pytest.fixture(scope="module")
def tesseract():
    scene = ndtrace.load_file(str(SCENES / "tesseract.toml"))
    d = scene.to_dict()
    d["camera"]["resolution"] = 32
    scene = ndtrace.load_dict(d, base=str(SCENES))
    return scene, ndtrace.trace(scene)


def cube(n: int = 16, a: float = 0.2) -> np.ndarray:
    """A raw uniform retina (n³ cells of alpha a, grey)."""
    r = np.zeros((n, n, n, 4), np.float32)
    r[...] = [0.5 * a, 0.5 * a, 0.5 * a, a]
    return r


# -- turntable, stereo, sections --------------------------------------------------------------

def test_turntable_frames_are_the_pictures_at_their_azimuths(tesseract):
    _, retina = tesseract
    frames = ndtrace.composite(retina, size=(48, 40), turntable=4, azimuth=10.0)
    assert frames.shape == (4, 40, 48, 4) and frames.dtype == np.float32
    for k in range(4):
        one = ndtrace.composite(retina, size=(48, 40), azimuth=10.0 + 90.0 * k)
        np.testing.assert_array_equal(frames[k], one)
    assert not np.array_equal(frames[0], frames[1])


def test_turntable_range_is_checked(tesseract):
    _, retina = tesseract
    with pytest.raises(ValueError, match="turntable"):
        ndtrace.composite(retina, turntable=100000)


def test_stereo_halves_are_the_two_eyes_views(tesseract):
    _, retina = tesseract
    kw = dict(size=(81, 60), layout="stereo", stereo_angle=8.0, azimuth=20.0, axes=False)
    pair = ndtrace.composite(retina, **kw)
    assert pair.shape == (60, 81, 4)
    # Each half is its eye's view, under its title.
    left, right = ndtrace._ndtrace.picture_layout(list(retina.shape), kw)["panels"]
    assert (left["title"], right["title"]) == ("left", "right")
    for panel, azimuth in ((left, 16.0), (right, 24.0)):
        r = panel["rect"]
        view = ndtrace.composite(retina, size=(r["w"], r["h"]), azimuth=azimuth, axes=False)
        np.testing.assert_array_equal(pair[r["y"]:r["y"] + r["h"], r["x"]:r["x"] + r["w"]], view)
    assert (left["rect"]["x"], right["rect"]["x"], right["rect"]["w"]) == (0, 40, 41)


def test_sections_show_the_view_and_the_cells_through_the_point():
    # Slices of distinct colour: the section across z at the centre is slice 8's colour, the
    # sections across x and y show every slice (z right / z down).
    n = 16
    r = np.zeros((n, n, n, 4), np.float32)
    for z in range(n):
        r[z] = [z / n, 0.2, 1 - z / n, 1.0]
    kw = dict(mode="volume", size=(128, 128), layout="sections", fit=False)
    pic = ndtrace.composite(r, **kw)
    panels = ndtrace._ndtrace.picture_layout([n, n, n], kw)["panels"]
    v, z, x, y = ({k: p["rect"][k] for k in "xywh"} for p in panels)
    tile = lambda q: pic[q["y"]:q["y"] + q["h"], q["x"]:q["x"] + q["w"]]  # noqa: E731
    view = ndtrace.composite(r, mode="volume", size=(v["w"], v["h"]), fit=False)
    np.testing.assert_array_equal(tile(v), view)
    across_z = tile(z)
    np.testing.assert_allclose(across_z[z["h"] // 2, z["w"] // 2, :3], [8 / n, 0.2, 1 - 8 / n], atol=1e-6)
    across_x = tile(x)  # z to the right: colour changes along columns
    mid = x["h"] // 2
    assert across_x[mid, x["w"] // 2 - 20, 0] < across_x[mid, x["w"] // 2 + 20, 0]
    across_y = tile(y)  # z down: colour changes along rows
    assert across_y[y["h"] // 2 - 20, y["w"] // 2, 0] < across_y[y["h"] // 2 + 20, y["w"] // 2, 0]
    with pytest.raises(ValueError, match="section"):
        ndtrace.composite(r, layout="sections", section=(0, float("nan"), 0))


# -- cutaways ---------------------------------------------------------------------------------

def test_half_space_cutaway_removes_half_the_path():
    a = 0.1
    r = cube(16, a)
    o = dict(mode="volume", projection="orthographic", azimuth=0.0, elevation=0.0, size=(32, 32), fit=False)
    full = ndtrace.composite(r, **o)[16, 16, 3]
    cut = ndtrace.composite(r, cutaway={"shape": "half_space", "normal": [0, 0, -1]}, **o)[16, 16, 3]
    np.testing.assert_allclose(full, 1 - (1 - a) ** 16, rtol=1e-3)
    np.testing.assert_allclose(cut, 1 - (1 - a) ** 8, rtol=2e-2)


def test_sphere_and_box_cutaways_and_their_errors():
    r = cube(16, 0.3)
    o = dict(mode="volume", projection="orthographic", azimuth=0.0, elevation=0.0, size=(32, 32), fit=False)
    full = ndtrace.composite(r, **o)[..., 3]
    ball = ndtrace.composite(r, cutaway={"shape": "sphere", "radius": 0.6}, **o)[..., 3]
    box = ndtrace.composite(r, cutaway={"shape": "box", "min": [-2, -2, -2], "max": [0, 2, 2]}, **o)[..., 3]
    assert ball[16, 16] < full[16, 16] - 0.05 and abs(ball[1, 1] - full[1, 1]) < 1e-6
    assert box[16, 4] < 1e-3 and abs(box[16, 28] - full[16, 28]) < 1e-6
    with pytest.raises(ValueError, match="cutaway.radius"):
        ndtrace.composite(r, cutaway={"shape": "sphere", "radius": -1})
    with pytest.raises(ValueError, match="cutaway.max"):
        ndtrace.composite(r, cutaway={"shape": "box", "min": [0, 0, 0], "max": [1, 0, 1]})
    with pytest.raises(ValueError, match="normal"):
        ndtrace.composite(r, cutaway={"shape": "half_space", "normal": [0, 0, 0]})
    with pytest.raises(ValueError, match="cutaway"):
        ndtrace.composite(r, cutaway={"shape": "cone", "radius": 1})


def test_cutaway_cuts_the_edges_too(tesseract):
    # Face-on orthographic, the half x > 0 removed: every drawn piece lies left of the centre.
    _, retina = tesseract
    o = dict(size=(96, 96), azimuth=0.0, elevation=0.0, projection="orthographic", hidden_edges="dashed")
    full = _ends(ndtrace.svg.svg_text(retina, fill=False, **o))
    cut = _ends(ndtrace.svg.svg_text(retina, fill=False, cutaway={"shape": "half_space", "normal": [1, 0, 0]}, **o))
    assert full[:, 0].max() > 60 and len(cut) > 0
    assert cut[:, 0].max() < 48 + 2  # the plane, within a cell of the 24³ retina


def _ends(text: str) -> np.ndarray:
    ns = "{http://www.w3.org/2000/svg}"
    ends = []
    for p in ET.fromstring(text).findall(f".//{ns}path"):
        m, l = p.get("d")[1:].split("L")
        ends += [[float(v) for v in m.split()], [float(v) for v in l.split()]]
    return np.asarray(ends).reshape(-1, 2)


# -- first hit: a smooth surface --------------------------------------------------------------

def test_first_hit_of_a_ball_is_round_not_a_staircase():
    n, rad = 32, 10.0
    z, y, x = np.mgrid[:n, :n, :n] + 0.5 - n / 2
    inside = (np.sqrt(x * x + y * y + z * z) < rad).astype(np.float32)
    r = np.zeros((n, n, n, 4), np.float32)
    r[..., 0] = inside * 0.8
    r[..., 3] = inside
    pic = ndtrace.composite(r, mode="first_hit", projection="orthographic", azimuth=0.0, elevation=0.0,
                            size=(256, 256), fit=False)
    # Orthographic face-on: the picture's shorter side spans the cube's bounding sphere
    # (diameter 2·√3 in units where the cube spans [−1, 1]), so a cell is 256 / (√3 · n) px.
    px_per_cell = 256 / (np.sqrt(3) * n)
    area = (pic[..., 3] > 0.5).sum() / px_per_cell**2
    assert abs(area - np.pi * rad**2) < 0.03 * np.pi * rad**2
    np.testing.assert_allclose(pic[128, 128, :3], [0.8, 0, 0], atol=1e-5)
    # The outline's radius varies little with the angle (a staircase would vary by ~½ cell).
    ys, xs = np.nonzero(pic[..., 3] > 0.5)
    radii = np.hypot(xs + 0.5 - 128, ys + 0.5 - 128) / px_per_cell
    edge = radii[radii > radii.max() - 1.5]
    assert edge.max() - edge.min() < 1.5


# -- SVG --------------------------------------------------------------------------------------

def _svg_pixels(text: str) -> np.ndarray:
    resvg_py = pytest.importorskip("resvg_py")
    from PIL import Image

    png = bytes(resvg_py.svg_to_bytes(svg_string=text))
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(np.float64) / 255.0


def test_svg_opens_and_its_lines_lie_on_the_composite_edges(tesseract, tmp_path):
    scene, retina = tesseract
    size = (160, 160)
    path = tmp_path / "t.svg"
    # The edges' geometry, one width (depth styling apart: the SVG weights a piece at its middle).
    ndtrace.write_svg(path, scene, fill=False, size=size, hidden_edges="none", axes=False, edge_color_by="none")
    text = path.read_text()
    root = ET.fromstring(text)
    ns = "{http://www.w3.org/2000/svg}"
    paths = root.findall(f".//{ns}path")
    assert len(paths) >= 20 and root.get("width") == "160"
    drawn = _svg_pixels(text).max(axis=2) > 0.5
    # The raster composite's edge layer: where drawing the edges changed the picture.
    with_edges = ndtrace.composite(retina, size=size, hidden_edges="none", edge_color_by="none")
    without = ndtrace.composite(retina, size=size, edges=False)
    raster = np.abs(with_edges - without)[..., :3].max(axis=2) > 0.1  # faded behind dense cells: > 0.1
    assert drawn.sum() > 300 and raster.sum() > 300
    from scipy import ndimage

    near_raster = ndimage.binary_dilation(raster, iterations=2)
    near_svg = ndimage.binary_dilation(drawn, iterations=2)
    assert (drawn & near_raster).sum() > 0.95 * drawn.sum()
    assert (raster & near_svg).sum() > 0.95 * raster.sum()


def test_svg_hidden_edges_dashed_and_fill(tesseract):
    scene, _ = tesseract
    text = ndtrace.svg.svg_text(scene, size=(96, 96))
    assert 'id="hidden-edges"' in text and "stroke-dasharray" in text
    assert "data:image/png;base64," in text
    none = ndtrace.svg.svg_text(scene, size=(96, 96), hidden_edges="none", fill=False)
    assert 'id="hidden-edges"' not in none and "<image" not in none
    with pytest.raises(ValueError, match=r"\.svg"):
        ndtrace.write_svg("x.png", scene)


def test_svg_needs_a_scene_of_four_or_more_dimensions():
    flat = ndtrace.load_file(str(SCENES / "cube.toml"))
    with pytest.raises(ValueError, match="N ≥ 4"):
        ndtrace.svg.svg_text(flat)


# -- command line -----------------------------------------------------------------------------

def _cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "ndtrace", *map(str, args)], capture_output=True,
                          text=True, cwd=cwd, timeout=300)


def test_cli_svg_turntable_layout_and_cutaway(tmp_path):
    scene = SCENES / "tesseract.toml"
    common = ["--resolution", "24", "--size", "64x64", "--quiet"]
    svg = tmp_path / "t.svg"
    out = _cli(scene, "-o", svg, *common)
    assert out.returncode == 0, out.stderr
    assert ET.fromstring(svg.read_text()).findall(".//{http://www.w3.org/2000/svg}path")
    gif = tmp_path / "orbit.gif"
    out = _cli(scene, "-o", gif, "--turntable", "3", *common)
    assert out.returncode == 0, out.stderr
    from PIL import Image

    assert Image.open(gif).n_frames == 3
    png = tmp_path / "s.png"
    out = _cli(scene, "-o", png, "--layout", "sections", "--cutaway", "sphere:0,0,0,0.5", *common)
    assert out.returncode == 0, out.stderr and png.exists()
    bad = _cli(scene, "-o", png, "--cutaway", "cone:1", *common)
    assert bad.returncode == 2 and "--cutaway" in bad.stderr
    bad = _cli(scene, "-o", png, "--cutaway", "sphere:0,0,0,-1", *common)
    assert bad.returncode == 2 and "cutaway.radius" in bad.stderr
    frames = _cli(scene, "-o", png, "--turntable", "2", *common)  # numbered PNG frames
    assert frames.returncode == 0 and (tmp_path / "s_0001.png").exists() and (tmp_path / "s_0002.png").exists()
    bad = _cli(scene, "-o", tmp_path / "x.jpg", "--turntable", "3", *common)
    assert bad.returncode == 2 and "--turntable" in bad.stderr
