"""Pictures that say what they show (issue 48): colour by cell, the colour bar, the N-D axes
glyph, panel titles and captions, edges by depth or direction — each checked where it can fail:
the hues of the retina's cells, the pixels the legend and the glyph change, the glyph's arrows
against the tracer's own camera, the sections' title positions, and the options through TOML,
dicts, the command line and the viewer."""

from __future__ import annotations

import colorsys
import os
import runpy

import numpy as np
import pytest

import ndtrace
from ndtrace import _ndtrace, annotate
from ndtrace.composite import picture_size, scene_options

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def tesseract(**material) -> ndtrace.Scene:
    data = ndtrace.load_file(os.path.join(ROOT, "scenes", "tesseract.toml")).to_dict()
    data["camera"]["resolution"] = 32
    data["render"]["samples"] = 1
    data["objects"][0]["material"] = {**data["objects"][0]["material"], **material}
    return ndtrace.load_dict(data)


def hue(rgb) -> float:
    """The hue (degrees) of a linear colour, as sRGB."""
    r, g, b = (annotate._srgb(c) for c in rgb)
    return colorsys.rgb_to_hsv(r, g, b)[0] * 360.0


def hue_gap(a: float, b: float) -> float:
    d = abs(a - b) % 360.0
    return min(d, 360.0 - d)


# -- colour by structure ------------------------------------------------------------------------

def test_color_by_cell_gives_each_visible_cell_of_the_tesseract_its_own_hue():
    retina = ndtrace.trace(tesseract(color_by="cell"))
    hit = (retina.rgba[..., 3] > 0.999) & retina.hit  # fully covered cells
    normals = retina.normal[hit]
    colors = retina.rgba[hit][:, :3] / retina.rgba[hit][:, 3:4]
    # Group the cells by their 4D normal (the tesseract's cells are flat: one normal each).
    keys = np.round(normals, 3)
    groups = {}
    for key, c in zip(map(tuple, keys), colors):
        groups.setdefault(key, []).append(hue(c))
    groups = {k: v for k, v in groups.items() if len(v) >= 20}
    assert len(groups) >= 3, f"only {len(groups)} cells in view"
    centres = {}
    for key, hues in groups.items():
        centre = hues[0]
        spread = max(hue_gap(h, centre) for h in hues)
        assert spread <= 3.0, f"normal {key}: hues spread over {spread:.1f}°"
        centres[key] = centre
    keys = list(centres)
    for i in range(len(keys)):
        for j in range(i + 1, len(keys)):
            gap = hue_gap(centres[keys[i]], centres[keys[j]])
            assert gap >= 15.0, f"normals {keys[i]} and {keys[j]}: hues {gap:.1f}° apart"
    # Without color_by, one hue everywhere: the test can tell.
    plain = ndtrace.trace(tesseract())
    lit = plain.rgba[(plain.rgba[..., 3] > 0.999) & plain.hit]
    hues = [hue(c[:3] / c[3]) for c in lit[::50]]
    assert max(hue_gap(h, hues[0]) for h in hues) < 15.0


def test_color_by_object_and_depth_and_the_palette():
    two = tesseract().to_dict()
    two["objects"].append({**two["objects"][0], "transform": [{"translate": [0, 0, 0, -3]}]})
    for o in two["objects"]:
        o["material"] = {"color_by": "object", "palette": "Set1"}
    scene = ndtrace.load_dict(two)
    info = scene.compiled().legend_info()
    set1 = _ndtrace.palette_colors("Set1")
    assert [o["color"] for o in info] == [list(set1[0]), list(set1[1])]
    # By depth: the nearest cells warm, the farthest cool, the range the vertices' depths.
    retina = ndtrace.trace(tesseract(color_by="depth"))
    info = retina._source.legend_info()[0]["colormap"]
    assert info["of"] == "depth" and info["name"] == "coolwarm_r"
    lo, hi = info["range"]
    assert lo < float(retina.depth[retina.hit].min()) + 0.5 and hi > float(retina.depth[retina.hit].max())
    hit = retina.hit & (retina.rgba[..., 3] > 0.999)
    near = retina.depth[hit] < np.percentile(retina.depth[hit], 10)
    far = retina.depth[hit] > np.percentile(retina.depth[hit], 90)
    c = retina.rgba[hit][:, :3]
    assert (c[near][:, 0] / c[near][:, 2]).mean() > 1.5 * (c[far][:, 0] / c[far][:, 2]).mean()


def test_bad_palette_and_color_by_are_located_errors():
    text = open(os.path.join(ROOT, "scenes", "tesseract.toml")).read()
    bad = text.replace('specular = 0.3, shininess = 40 }', 'specular = 0.3, shininess = 40, palette = "tab11" }')
    line = next(i for i, l in enumerate(bad.splitlines(), 1) if "tab11" in l)
    with pytest.raises(ValueError) as e:
        ndtrace.load_toml(bad, name="t.toml")
    assert str(e.value).startswith(f"t.toml:{line}:"), e.value
    assert 'objects[0].material.palette: unknown palette "tab11" (known: tab10, tab20' in str(e.value)
    sphere = text.replace('shape = "hypercube"', 'shape = "sphere"').replace(
        'shininess = 40 }', 'shininess = 40, color_by = "cell" }')
    with pytest.raises(ValueError, match=r'objects\[0\]\.material\.color_by: "cell" needs a mesh of flat cells'):
        ndtrace.load_toml(sphere, name="s.toml")
    smooth = text.replace('shininess = 40 }', 'shininess = 40, smooth = true, color_by = "cell" }')
    with pytest.raises(ValueError, match="a smooth material shades it as a curved boundary"):
        ndtrace.load_toml(smooth, name="s.toml")
    with pytest.raises(ValueError, match=r'<dict>: objects\[0\]\.material\.color_by: unknown color_by "cells" \(did you mean "cell"\?\)'):
        tesseract(color_by="cells")
    with pytest.raises(ValueError, match="colormap and color_by both set the colour"):
        tesseract(color_by="cell", colormap="viridis")


# -- the legend -----------------------------------------------------------------------------------

def elevation_retina():
    scene = runpy.run_path(os.path.join(ROOT, "scenes", "elevation.py"))["scene"]()
    data = scene.to_dict()
    data["camera"]["resolution"] = 24
    data["render"]["samples"] = 1
    return ndtrace.trace(ndtrace.load_dict(data)), data


def test_the_colour_bar_lies_in_a_strip_along_the_bottom_with_both_ends_of_the_colormap():
    retina, data = elevation_retina()
    options = dict(scene_options(data), size=(400, 360), axes=False)
    picture = ndtrace.composite(retina, **options)
    # The same composite without its drawing: the core's picture for the same layout.
    rows = annotate.legend_rows(retina, options)
    assert [r.kind for r in rows] == ["ramp"]
    from ndtrace._description import plain

    given = plain(options)
    layout = _ndtrace.picture_layout(list(retina.shape), given, len(rows), retina._camera_info())
    # The same picture without the legend: the core's composite for the same layout, with the
    # panel titles drawn.
    bare = _ndtrace.composite(retina.rgba, retina.depth, given, None, None, None, None, retina._source,
                              np.ascontiguousarray(retina.object_id, np.int32), legend_rows=len(rows))
    annotate.draw(bare, annotate.items(layout, [], None, options, options["background"]))
    changed = np.abs(picture - bare).max(axis=-1) > 1e-6
    ys, xs = np.nonzero(changed)
    assert len(ys) > 500
    strip = layout["legend"]
    assert (strip["x"], strip["w"], strip["y"] + strip["h"]) == (0, 400, 360)  # along the bottom
    assert strip["h"] <= 0.2 * 360
    assert ys.min() >= strip["y"] and ys.max() < 360, "the legend draws outside its strip"
    # Both end colours of the colormap (coolwarm: blue, red) are in the strip.
    table = np.asarray(_ndtrace.colormap_table("coolwarm"), dtype=np.float32)
    pixels = picture[changed][:, :3]
    for end in (table[0], table[-1]):
        assert np.abs(pixels - end).max(axis=1).min() < 0.02, f"no pixel of {end}"
    # No legend: nothing drawn, and the view takes the whole picture.
    off = ndtrace.composite(retina, **dict(options, legend=False))
    assert annotate.legend_rows(retina, dict(options, legend=False)) == []
    assert _ndtrace.picture_layout(list(retina.shape), plain(dict(options, legend=False)))["legend"] is None
    assert off.shape == picture.shape


def test_legend_rows_say_what_the_colours_mean():
    retina, data = elevation_retina()
    (ramp,) = annotate.legend_rows(retina, {"legend": "auto"})
    assert (ramp.colormap, ramp.range, ramp.isolines) == ("coolwarm", (-1.0, 1.0), (0.25, 0.5, 0.75))
    # A cell key for color_by = "cell": the tesseract's 4 directions of cells, ±x … ±w.
    cells = ndtrace.trace(tesseract(color_by="cell"))
    (row,) = annotate.legend_rows(cells, {})
    assert row.kind == "key" and [label for _, label in row.entries] == ["±x", "±y", "±z", "±w"]
    assert row.title == "8 cells, opposite ones alike:"
    # Edges by direction: their four directions in the object's own axes.
    plain = ndtrace.trace(tesseract())
    assert annotate.legend_rows(plain, {}) == []  # nothing to key: no legend by default
    (row,) = annotate.legend_rows(plain, {"edge_color_by": "direction"})
    assert [label for _, label in row.entries] == ["x", "y", "z", "w"] and row.lines
    # Labels key the objects; legend=False drops everything.
    data = tesseract().to_dict()
    data["objects"][0]["label"] = "the tesseract"
    labelled = ndtrace.trace(ndtrace.load_dict(data))
    (row,) = annotate.legend_rows(labelled, {})
    assert row.entries == [(tuple(data["objects"][0]["material"]["color"]), "the tesseract")]
    assert annotate.legend_rows(labelled, {"legend": False}) == []


def test_direction_labels_and_ticks():
    assert annotate.direction_label([0, 0, 0, 1]) == "w"
    assert annotate.direction_label([0, 0, 0, 1], both=True) == "±w"
    assert annotate.direction_label([0.5, -0.5, 0.5, 0.5]) == "x−y+z+w"
    assert annotate.direction_label([0.8, 0.6, 0, 0]) is None
    assert annotate._ticks(-1, 1) == [-1.0, -0.5, 0.0, 0.5, 1.0]
    assert annotate._number(-0.5, 0.5) == "−0.5" and annotate._number(0.25, 0.25) == "0.25"


# -- the axes glyph -------------------------------------------------------------------------------

def test_the_glyph_changes_pixels_only_in_a_corner_box_of_at_most_a_fifth_of_the_picture():
    retina = ndtrace.trace(tesseract())
    with_axes = ndtrace.composite(retina, size=(300, 240))
    without = ndtrace.composite(retina, size=(300, 240), axes=False)
    changed = np.abs(with_axes - without).max(axis=-1) > 1e-6
    ys, xs = np.nonzero(changed)
    assert len(ys) > 100
    box = _ndtrace.picture_layout(list(retina.shape), {"size": [300, 240]})["axes"]
    assert (box["x"], box["y"] + box["h"]) == (0, 240)  # the lower-left corner
    assert box["w"] * box["h"] <= 0.2 * 300 * 240
    assert xs.min() >= box["x"] and xs.max() < box["x"] + box["w"]
    assert ys.min() >= box["y"] and ys.max() < box["y"] + box["h"]
    # Off by default below N = 4.
    cube = ndtrace.load_file(os.path.join(ROOT, "scenes", "cube.toml"))
    assert _ndtrace.picture_layout([64, 64], {})["axes"] is None
    assert cube.dim == 3


def marker_scene(orientation, offset, projection="orthographic") -> ndtrace.Scene:
    """A small cube at ``offset`` seen by an orthographic camera of ``orientation``."""
    view = np.asarray(orientation)[:, 3]
    return (ndtrace.Scene(4)
            .set_camera(list(-5.0 * view), orientation=np.asarray(orientation).tolist(),
                        projection=projection, extent=1.6, fov=None, resolution=32)
            .add_object("hypercube", transform=[{"scale": 0.1}, {"translate": list(offset)}])
            .set_render(samples=1))


def test_the_glyph_points_where_the_tracer_and_compositor_put_the_unit_axes():
    """Markers traced at ±0.8·e_i around the origin, composited orthographically, lie in the
    picture along the glyph's arrows, for random camera rotations (the core's test checks the
    projection itself against the tracer's camera map, to 1e-4)."""
    rng = np.random.default_rng(48)
    checked = 0
    for trial in range(4):
        q, r = np.linalg.qr(rng.normal(size=(4, 4)))
        orientation = q * np.sign(np.diag(r))
        opts = dict(mode="volume", projection="orthographic", fit=False, size=(240, 240),
                    azimuth=float(rng.uniform(-60, 60)), elevation=float(rng.uniform(-40, 40)),
                    axes=False, legend=False)

        def centroid(offset, orientation=orientation, opts=opts):
            picture = ndtrace.composite(ndtrace.trace(marker_scene(orientation, offset)), **opts)
            a = picture[..., 3]
            ys, xs = np.nonzero(a > 0.2)
            return np.array([xs.mean(), ys.mean()]) if len(xs) else None

        retina = ndtrace.trace(marker_scene(orientation, [0, 0, 0, 0]))
        camera = retina._camera_info()
        arrows = _ndtrace.axis_arrows(list(retina.shape), camera, opts)
        for i in range(4):
            tip = np.array(arrows[i]["tip"])
            if np.hypot(*tip) < 0.35:
                continue  # nearly along a line of sight: its direction is ill-defined
            e = np.zeros(4)
            e[i] = 0.8
            a, b = centroid(-e), centroid(e)
            if a is None or b is None:
                continue
            d = b - a
            cos = float(d @ tip / np.linalg.norm(d) / np.linalg.norm(tip))
            assert cos > np.cos(np.radians(5)), f"trial {trial}, axis {i}: {d} vs {tip}"
            checked += 1
    assert checked >= 6


def test_the_viewer_glyph_follows_the_rotation():
    from ndtrace.viewer.session import ViewSession

    s = ViewSession(tesseract(), size=(160, 160), draft_cells=8 ** 3)
    s.handle({"type": "roll", "steps": [[40, 0]]})
    snap = s.snapshot()
    assert not np.allclose(snap.rotation, np.eye(4))
    meta, _ = s.render(snap, "draft", lambda: False)
    # The frame's glyph is the rotated frame's; the TOML copy keeps it.
    retina = s._retina[2]
    moved = _ndtrace.axis_arrows(list(retina.shape), retina._camera_info(), {"axes_frame": snap.rotation.tolist()})
    still = _ndtrace.axis_arrows(list(retina.shape), retina._camera_info(), {})
    assert any(abs(m["tip"][0] - w["tip"][0]) > 0.05 for m, w in zip(moved, still))
    assert "axes_frame" in s.view_toml()


# -- titles ----------------------------------------------------------------------------------------

def test_the_sections_layout_shows_its_four_titles_over_their_panels():
    retina, data = elevation_retina()
    options = dict(scene_options(data), section=[0.4, -0.2, 0.6])
    from ndtrace._description import plain

    rows = annotate.legend_rows(retina, options)
    layout = _ndtrace.picture_layout(list(retina.shape), plain(options), len(rows), retina._camera_info())
    assert tuple(layout["size"]) == (720, 720) == picture_size(retina.shape, options)
    drawing = annotate.items(layout, rows, None, options, options["background"])
    titles = [t for t in drawing if isinstance(t, annotate.Text) and t.role == "panel-title"]
    # The course's camera (orthographic, down −w): the sections lie in the planes z = …, x = …,
    # y = … of the scene; the volume's x = 0.4 is 0.4 · 32 cells of 2.1/64 = 0.42 units.
    assert [t.text for t in titles] == ["volume", "z = 0.63", "x = 0.42", "y = −0.21"]
    for t, panel in zip(titles, layout["panels"]):
        band, rect = panel["title_band"], panel["rect"]
        assert abs(t.x - (band["x"] + band["w"] / 2)) < 1 and t.anchor == "m"
        assert band["y"] < t.y <= band["y"] + band["h"] == rect["y"]  # baseline in the band above
        assert rect["w"] >= 256 and rect["h"] >= 256
        # The text fits its band.
        assert annotate.text_width(t.text, t.size) < band["w"]
    # And is drawn: ink in each title band.
    picture = ndtrace.composite(retina, **options)
    for panel in layout["panels"]:
        b = panel["title_band"]
        band = picture[b["y"]:b["y"] + b["h"], b["x"]:b["x"] + b["w"], :3]
        assert band.max() > 0.5


def test_caption_and_stereo_titles():
    retina = ndtrace.trace(tesseract())
    picture = ndtrace.composite(retina, layout="stereo", title="A stereo pair")
    assert picture.shape == (540, 960, 4)  # the stereo layout's default size
    layout = _ndtrace.picture_layout(list(retina.shape), {"layout": "stereo", "title": "A stereo pair"})
    assert [p["title"] for p in layout["panels"]] == ["left", "right"]
    cap = layout["caption"]
    assert picture[cap["y"]:cap["y"] + cap["h"], :, :3].max() > 0.5
    # A size given is kept.
    assert ndtrace.composite(retina, layout="stereo", size=(300, 200)).shape == (200, 300, 4)


# -- options through every door -------------------------------------------------------------------

def test_the_options_round_trip_through_toml_dicts_the_command_line_and_the_viewer(tmp_path):
    text = open(os.path.join(ROOT, "scenes", "tesseract.toml")).read().replace("resolution = 64", "resolution = 16")
    table = ('\n[composite]\nlegend = false\naxes = true\ntitle = "Edges by direction"\n'
             'edge_color_by = "direction"\n')
    scene = ndtrace.load_toml(text + table)
    comp = scene.to_dict()["composite"]
    assert comp == {"legend": False, "axes": True, "title": "Edges by direction", "edge_color_by": "direction"}
    assert ndtrace.load_toml(scene.to_toml()) == scene
    assert ndtrace.load_dict(scene.to_dict()) == scene
    # A bad value is located in a file, named as a keyword.
    with pytest.raises(ValueError, match=r'^t\.toml:\d+:\d+: composite\.legend: .*"auto", true or false'):
        ndtrace.load_toml(text + '\n[composite]\nlegend = "yes"\n', name="t.toml")
    with pytest.raises(ValueError, match="^edge_color_by: unknown edge_color_by \"colour\""):
        ndtrace.composite(np.zeros((2, 2, 2, 4), np.float32), edge_color_by="colour")
    # The command line's flags set the same keys.
    path = tmp_path / "t.toml"
    path.write_text(text)
    from ndtrace import cli

    args = cli._parser().parse_args([str(path), "-o", "x.png", "--legend", "false", "--axes", "true",
                                     "--title", "Edges by direction", "--edge-color-by", "direction"])
    assert cli._composite_flags(args) == comp
    out = tmp_path / "t.png"
    cli.run([str(path), "-o", str(out), "--quiet", "--legend", "false", "--axes", "true", "--size", "96x96",
             "--title", "Edges by direction", "--edge-color-by", "direction", "--color-by", "cell"])
    from PIL import Image

    got = np.asarray(Image.open(out).convert("RGB"))
    cells = ndtrace.load_dict({**scene.to_dict(), "objects": [
        {**o, "material": {**o["material"], "color_by": "cell"}} for o in scene.to_dict()["objects"]]})
    want = ndtrace.files.to_srgb8(ndtrace.composite(ndtrace.trace(cells), **{**comp, "size": (96, 96),
                                                    "background": scene.to_dict()["background"]}), opaque=True)
    assert np.abs(got.astype(int) - want[..., :3].astype(int)).max() <= 1
    with pytest.raises(SystemExit):
        cli._parser().parse_args([str(path), "-o", "x.png", "--palette", "tab11"])
    # The viewer's controls: legend and axes are choices of "auto", true, false; the title text.
    from ndtrace.viewer.session import ViewSession, display_aids

    aids = {a["name"]: a for a in display_aids()}
    assert aids["legend"]["kind"] == "choice" and aids["legend"]["choices"] == ["auto", True, False]
    assert aids["axes"]["choices"] == ["auto", True, False]
    assert aids["edge_color_by"]["choices"] == ["direction", "depth", "none"]
    assert aids["title"]["kind"] == "string"
    assert "axes_frame" not in aids  # the session sets it from the rotation
    s = ViewSession(ndtrace.load_toml(text))
    state, _ = s.handle({"type": "set", "options": {"legend": False, "axes": True, "title": "Edges by direction",
                                                    "edge_color_by": "direction"}})
    assert {k: state["options"][k] for k in comp} == comp
    back = ndtrace.load_toml(s.view_toml()).to_dict()["composite"]
    assert {k: back[k] for k in comp} == comp
    with pytest.raises(ValueError, match="legend"):
        s.handle({"type": "set", "options": {"legend": "sometimes"}})


def test_svg_has_the_caption_legend_and_glyph_as_elements():
    data = tesseract().to_dict()
    data["objects"][0]["label"] = "tesseract"
    from ndtrace.svg import svg_text

    text = svg_text(ndtrace.load_dict(data), fill=False, title="Caption & more", edge_color_by="direction",
                            size=(300, 300))
    assert '<g id="annotations">' in text
    assert '<text class="caption"' in text and "Caption &amp; more" in text
    assert text.count('class="axes-label"') == 4
    assert '<text class="key-label"' in text and ">tesseract<" in text
    # Edges take their direction's colours: four strokes.
    strokes = {part.split('"')[0] for part in text.split('<path')[1:] for part in part.split('stroke="')[1:2]}
    assert len(strokes) >= 4
