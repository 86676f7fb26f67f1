"""Pictures at print quality (issue 47): a picture drawn from its scene (``detail="scene"``, the
default for a traced 4D retina) is limited by its own resolution, not the retina's.

* the first-hit silhouette of the tesseract lies on the exact one (the convex hull of its
  projected vertices, from the exact edges of the same view), anti-aliased, from a 32³ and a
  128³ retina; the default picture has no halo beyond it;
* the default pictures of the tesseract, the 3-sphere and the bear-haired Clifford torus from a
  coarse and a fine retina agree;
* isolines of a linear field are straight in a section; the blobs of a thickened point cloud at
  equal depth have equal areas;
* the picture is the same for any number of threads.

Each test can fail: the same measurements on the retina's grid (``detail="retina"``) fail them.
"""

from __future__ import annotations

import importlib
import os
import runpy
from pathlib import Path

import numpy as np
import pytest

import ndtrace

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"
SIZE = (1024, 1024)


def at_resolution(path: Path, res: int, **render) -> ndtrace.Scene:
    """The scene file or script `path` with a `res`³ retina (and `render` keys)."""
    if path.suffix == ".py":
        scene = runpy.run_path(str(path))["scene"]()
    else:
        scene = ndtrace.load_file(str(path))
    d = scene.to_dict()
    d["camera"]["resolution"] = res
    d.setdefault("render", {}).update(render)
    return ndtrace.load_dict(d, base=str(SCENES))


def hull(points: np.ndarray) -> np.ndarray:
    """The convex hull of 2D points, counter-clockwise in (x right, y down) pixels."""
    pts = sorted(set(map(tuple, np.round(points, 9))))

    def half(seq):
        out: list = []
        for p in seq:
            while len(out) >= 2 and np.cross(np.subtract(out[-1], out[-2]), np.subtract(p, out[-2])) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.asarray(lower[:-1] + upper[:-1], float)


def signed_distance(poly: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Signed distance from points to a convex polygon's outline (negative inside)."""
    d = np.full(x.shape, np.inf)
    inside = np.ones(x.shape, bool)
    for a, b in zip(poly, np.roll(poly, -1, axis=0)):
        ab = b - a
        t = np.clip(((x - a[0]) * ab[0] + (y - a[1]) * ab[1]) / (ab @ ab), 0, 1)
        d = np.minimum(d, np.hypot(a[0] + t * ab[0] - x, a[1] + t * ab[1] - y))
        inside &= (ab[0] * (y - a[1]) - ab[1] * (x - a[0])) >= 0
    # The hull's orientation decides which side is inside; take the side with the centre.
    c = poly.mean(axis=0)
    centre_inside = all((b - a)[0] * (c[1] - a[1]) - (b - a)[1] * (c[0] - a[0]) >= 0
                        for a, b in zip(poly, np.roll(poly, -1, axis=0)))
    if not centre_inside:
        inside = ~inside
    return np.where(inside, -d, d)


def exact_silhouette(scene: ndtrace.Scene, retina: ndtrace.Retina, **options) -> np.ndarray:
    """The hull of the tesseract's projected vertices in the picture of `options` (from the
    ends of its exact feature edges, hidden ones included)."""
    from ndtrace import _ndtrace
    from ndtrace._description import plain

    keys = dict(options, mode="illustrative", edges=True, hidden_edges="dashed")
    rows = np.asarray(_ndtrace.picture_edges(
        retina.rgba, retina.depth, plain(keys), None, retina.normal, retina._camera_info(),
        retina._edges(float(keys.get("crease_angle", 20.0))), retina._source,
        np.ascontiguousarray(retina.object_id, np.int32)))
    return hull(rows[:, :4].reshape(-1, 2))


def coverage(poly: np.ndarray, w: int, h: int, band: float = 3.0, k: int = 16):
    """Per pixel: the signed distance of its centre to the outline, and the exact covered
    fraction of the pixel (k × k samples within `band` px of the outline, 0/1 elsewhere)."""
    y, x = np.mgrid[:h, :w] + 0.5
    sd = signed_distance(poly, x, y)
    cov = (sd < 0).astype(float)
    near = np.abs(sd) < band
    ys, xs = np.nonzero(near)
    offs = (np.arange(k) + 0.5) / k - 0.5
    ox, oy = np.meshgrid(offs, offs)
    sx = (xs[:, None] + 0.5 + ox.ravel()[None, :])
    sy = (ys[:, None] + 0.5 + oy.ravel()[None, :])
    cov[ys, xs] = (signed_distance(poly, sx, sy) < 0).mean(axis=1)
    return sd, cov


@pytest.fixture(scope="module")
def tesseracts():
    out = {}
    for res in (32, 128):
        scene = at_resolution(SCENES / "tesseract.toml", res)
        out[res] = (scene, ndtrace.trace(scene))
    return out


@pytest.mark.parametrize("res", [32, 128])
def test_first_hit_silhouette_is_the_exact_one_antialiased(tesseracts, res):
    scene, retina = tesseracts[res]
    opts = dict(mode="first_hit", opacity=1.0, edges=False, size=SIZE, axes=False)
    pic = ndtrace.composite(retina, **opts)
    poly = exact_silhouette(scene, retina, size=SIZE)
    sd, cov = coverage(poly, *SIZE)
    alpha = pic[..., 3]
    beyond = sd > 1.5
    assert alpha[beyond].max() == 0.0, f"alpha {alpha[beyond].max()} beyond 1.5 px of the silhouette"
    near = np.abs(sd) < 2.0
    err = np.abs(alpha[near] - cov[near]).mean()
    assert err < 0.04, f"mean |alpha − coverage| within 2 px of the outline: {err:.3f}"
    # From the retina's grid the same picture fails (the measure can fail).
    if res == 32:
        grid = ndtrace.composite(retina, detail="retina", **opts)[..., 3]
        assert np.abs(grid[near] - cov[near]).mean() > 0.04


def test_default_composite_has_no_halo(tesseracts):
    scene, retina = tesseracts[32]
    pic = ndtrace.composite(retina, size=SIZE, axes=False)
    poly = exact_silhouette(scene, retina, size=SIZE)
    y, x = np.mgrid[:SIZE[1], :SIZE[0]] + 0.5
    sd = signed_distance(poly, x, y)
    area = (sd < 0).sum()
    glow = ((pic[..., 3] > 0) & (sd > 1.5)).sum()
    assert glow <= 0.001 * area, f"alpha beyond 1.5 px over {glow / area:.2%} of the object's area"
    grid = ndtrace.composite(retina, size=SIZE, detail="retina", axes=False)
    assert ((grid[..., 3] > 0) & (sd > 1.5)).sum() > 0.001 * area


@pytest.mark.parametrize("name,coarse", [("tesseract.toml", 32), ("sphere3.toml", 32),
                                         ("clifford_torus_hair.py", 48)])
def test_pictures_do_not_depend_on_the_retina(name, coarse):
    pics = []
    for res in (coarse, 128):
        scene = at_resolution(SCENES / name, res)
        options = importlib.import_module("ndtrace.composite").scene_options(scene.to_dict())
        options.update(size=SIZE, edges=False)
        pics.append(ndtrace.composite(ndtrace.trace(scene), **options))
    a, b = pics
    covered = (a[..., 3] > 0) | (b[..., 3] > 0)
    d_alpha = np.abs(a[..., 3] - b[..., 3])[covered].mean()
    d_rgb = np.abs(a[..., :3] - b[..., :3])[covered].mean()
    assert d_alpha < 0.04 and d_rgb < 0.04, (d_alpha, d_rgb)


def test_isolines_of_a_linear_field_are_straight_in_a_section():
    # f = x + 0.3·y over a cube, isolines at three values; the section across z shows each as
    # a straight band: the middle of its pixels in each row lies on a line to 0.5 px.
    g = np.linspace(-1, 1, 9)
    x, y, z = np.meshgrid(g, g, g, indexing="ij")
    field = x + 0.3 * y
    scene = (ndtrace.Scene(4, background=[1, 1, 1])
             .set_camera([0.0, 0.0, 0.0, 4.0], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=40,
                         resolution=32)
             .add_light("directional", direction=[0.3, 0.5, 0.4, 1.0])
             .add_object("elevation", field=field, height=0.3,
                         material={"color": [0.8, 0.8, 0.8],
                                   "isolines": {"values": [-0.6, 0.0, 0.6], "color": [0, 0, 0]}}))
    retina = ndtrace.trace(scene)

    def middle_line(detail):
        """Rows of the section across z with three dark runs, and the middle run's centres'
        largest distance from their straight-line fit."""
        options = dict(layout="sections", size=(1024, 1024), mode="volume", background=[1, 1, 1],
                       detail=detail, axes=False)
        pic = ndtrace.composite(retina, **options)
        from ndtrace import _ndtrace
        from ndtrace._description import plain

        r = _ndtrace.picture_layout(list(retina.shape), plain(options))["panels"][1]["rect"]
        tile = pic[r["y"]:r["y"] + r["h"], r["x"]:r["x"] + r["w"], :3]  # the section across z
        dark = tile.mean(axis=-1) < 0.25
        centres = []
        for r in np.nonzero(dark.any(axis=1))[0]:
            xs = np.nonzero(dark[r])[0]
            runs = np.split(xs, np.nonzero(np.diff(xs) > 1)[0] + 1)
            if len(runs) == 3:
                centres.append((r, runs[1].mean()))
        if len(centres) < 2:
            return len(centres), np.inf
        r, c = np.asarray(centres).T
        return len(centres), np.abs(np.polyval(np.polyfit(r, c, 1), r) - c).max()

    rows, deviation = middle_line("scene")
    assert rows > 100 and deviation <= 0.5, (rows, deviation)
    # The retina's cells alone draw the lines as scattered blocks (the measure can fail).
    rows, deviation = middle_line("retina")
    assert not (rows > 100 and deviation <= 0.5), (rows, deviation)


def test_point_blobs_at_equal_depth_have_equal_areas():
    # Five tiny 3-spheres at equal distance from the 4D eye and equal angle off its view axis
    # (on a circle about the axis, at angles unrelated to the retina's grid), seen face-on:
    # their pictures are congruent, so their areas (summed alpha) must agree.
    from scipy import ndimage

    a = 0.45
    angles = np.radians([7.0, 81.0, 152.0, 229.0, 301.0])
    points = np.stack([a * np.cos(angles), a * np.sin(angles), np.zeros(5), np.zeros(5)], axis=1)
    v, t = ndtrace.mesh.thicken_points(points, radius=0.09, subdivisions=2)
    scene = (ndtrace.Scene(4)
             .set_camera([0.0, 0.0, 0.0, 3.0], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=40,
                         resolution=32)
             .add_light("directional", direction=[0.2, 0.3, 0.5, 1.0])
             .add_object("mesh", vertices=v, simplices=t, material={"color": [0.9, 0.6, 0.3]}))
    retina = ndtrace.trace(scene)
    opts = dict(mode="first_hit", projection="orthographic", azimuth=0.0, elevation=0.0, size=(512, 512),
                fit=False, axes=False)

    def areas(pic):
        alpha = pic[..., 3]
        labels, count = ndimage.label(alpha > 0)
        assert count == 5, count
        return np.asarray(ndimage.sum(alpha, labels, index=np.arange(1, count + 1)))

    exact = areas(ndtrace.composite(retina, **opts))
    assert exact.min() > 100
    assert exact.max() / exact.min() - 1 < 0.05, exact
    # The retina's cells alone give blobs of different sizes (the measure can fail).
    grid = areas(ndtrace.composite(retina, detail="retina", **opts))
    assert grid.max() / grid.min() - 1 > 0.05, grid


def test_the_picture_is_the_same_for_any_number_of_threads(tesseracts):
    _, retina = tesseracts[32]
    for opts in (dict(), dict(mode="first_hit"), dict(mode="volume", opacity=0.2),
                 dict(layout="sections", section=[0.1, 0.0, 0.0])):
        one = ndtrace.composite(retina, size=(256, 256), threads=1, **opts)
        two = ndtrace.composite(retina, size=(256, 256), threads=2, **opts)
        np.testing.assert_array_equal(one, two)


def test_samples_and_detail_options():
    with pytest.raises(ValueError, match="samples"):
        ndtrace.composite(np.zeros((4, 4, 4, 4), np.float32), samples=1000)
    with pytest.raises(ValueError, match="detail"):
        ndtrace.composite(np.zeros((4, 4, 4, 4), np.float32), detail="cells")
    assert os.path.exists(SCENES)


def test_surface_width_in_retina_cells_still_loads_and_does_not_change_pictures():
    # `width` (retina cells) is what the retina holds: a scene file that sets it keeps working,
    # with a warning naming `line_width`, and a picture drawn from the scene does not change
    # with it (it draws the surface at `line_width` picture pixels), while the grid path does.
    v, t = ndtrace.surfaces.clifford_torus(24)

    def picture(width, detail):
        scene = (ndtrace.Scene(4)
                 .set_camera([0.3, 0.4, 0.5, 2.5], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]],
                             fov=45, resolution=32)
                 .add_light("directional", direction=[0.2, 0.3, 0.5, 1.0])
                 .add_object("surface", vertices=v, triangles=t, width=width))
        with pytest.warns(UserWarning, match="line_width"):
            retina = ndtrace.trace(scene)
        return ndtrace.composite(retina, mode="first_hit", size=(256, 256), detail=detail)

    np.testing.assert_array_equal(picture(1.0, "scene"), picture(4.0, "scene"))
    assert np.abs(picture(1.0, "retina")[..., 3] - picture(4.0, "retina")[..., 3]).mean() > 0.01
