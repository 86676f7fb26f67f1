"""``render.shading = "gouraud"`` (lighting at the vertices, interpolated) against Phong, and
``[composite] cubes = { size }`` (occupied cells as small opaque cubes with gaps)."""

import numpy as np
import pytest

import ndtrace


def facet_scene(shading, normals_vary=False, specular=0.0):
    """A 3D scene: one triangle facing the camera head-on, lit by a directional light."""
    return ndtrace.load_dict({
        "dim": 3, "camera": {"position": [0, 0, 3], "look_at": [0, 0, 0], "up": [0, 1, 0],
                             "fov": 40, "resolution": 32},
        "lights": [{"type": "directional", "direction": [0.3, 0.2, 1.0]}],
        "objects": [{"shape": "mesh", "vertices": [[-1, -1, 0], [1, -1, 0], [0, 1, 0]],
                     "simplices": [[0, 1, 2]],
                     "material": {"specular": specular, "smooth": normals_vary}}],
        "render": {"shading": shading, "shadows": False}})


def test_gouraud_equals_phong_where_lighting_is_linear():
    # A flat facet, a directional light, no specular term: n̂·l̂ is the same everywhere, so the
    # interpolated lighting is the per-point lighting.
    a = ndtrace.trace(facet_scene("phong")).rgba
    b = ndtrace.trace(facet_scene("gouraud")).rgba
    np.testing.assert_allclose(a, b, atol=1e-6)


def test_gouraud_interpolates_the_vertex_lighting_of_a_smooth_sphere():
    def sphere(shading):
        return ndtrace.load_dict({
            "dim": 3, "camera": {"position": [0, 0, 4], "look_at": [0, 0, 0], "up": [0, 1, 0],
                                 "fov": 40, "resolution": 48},
            "lights": [{"type": "directional", "direction": [0.6, 0.5, 1.0]}],
            "objects": [{"shape": "sphere", "subdivisions": 1,
                         "material": {"smooth": True, "specular": 0.6, "shininess": 30}}],
            "render": {"shading": shading}})
    phong, gouraud = ndtrace.trace(sphere("phong")), ndtrace.trace(sphere("gouraud"))
    hit = phong.object_id >= 0
    np.testing.assert_array_equal(hit, gouraud.object_id >= 0)
    diff = np.abs(phong.rgba[hit, :3] - gouraud.rgba[hit, :3]).max(axis=-1)
    # The highlight is smeared across facets by Gouraud: the pictures differ, but the
    # diffuse shading agrees closely on most of the sphere.
    assert diff.max() > 0.05
    assert np.median(diff) < 0.05


def test_gouraud_round_trips_and_is_checked():
    s = facet_scene("gouraud")
    assert s.to_dict()["render"]["shading"] == "gouraud"
    assert ndtrace.load_toml(s.to_toml()) == s
    assert "shading" not in facet_scene("phong").to_dict()["render"]
    data = s.to_dict()
    data["render"]["shading"] = "flat"
    with pytest.raises(ValueError, match=r"render\.shading"):
        ndtrace.load_dict(data)


def tesseract_retina():
    return ndtrace.trace(ndtrace.load_dict({
        "dim": 4, "camera": {"position": [1.2, 1.6, 2.0, 4.5], "look_at": [0, 0, 0, 0],
                             "up": [[0, 1, 0, 0], [0, 0, 1, 0]], "fov": 50, "resolution": 12},
        "objects": [{"shape": "hypercube"}]}))


def test_cubes_leave_gaps_between_the_cells():
    r = tesseract_retina()
    bg = [0.0, 0.0, 0.0]
    # (Without the axes glyph, whose anti-aliased arrows are not cubes.)
    full = ndtrace.composite(r, cubes={"size": 1.0}, size=(200, 200), background=bg, axes=False)
    small = ndtrace.composite(r, cubes={"size": 0.5}, size=(200, 200), background=bg, axes=False)
    covered_full = (full[..., 3] > 0.99).sum()
    covered_small = (small[..., 3] > 0.99).sum()
    # Opaque: every pixel is a cube or background.
    assert np.all((small[..., 3] > 0.99) | (small[..., 3] < 0.01))
    # Half-size cubes leave gaps: a smaller covered area, and background inside the outline.
    assert covered_small < 0.8 * covered_full
    rows = np.flatnonzero(full[..., 3].max(axis=1) > 0.99)
    mid = rows[len(rows) // 2]
    line = small[mid, :, 3] > 0.99
    inside = np.flatnonzero(line)
    assert np.any(~line[inside[0]:inside[-1]]), "gaps between cubes along a row"
    # The same with the mode changed: cubes draw the cells whatever the mode.
    np.testing.assert_array_equal(
        small, ndtrace.composite(r, cubes={"size": 0.5}, mode="volume", size=(200, 200),
                                 background=bg, axes=False))


@pytest.mark.parametrize("cubes, message", [
    ({"size": 0}, r"cubes\.size: must be in \(0, 1\]"), ({"size": 1.5}, r"cubes\.size"),
    ({"side": 0.5}, r"cubes\.side: unknown key \"side\" \(did you mean \"size\"\?\)"),
])
def test_bad_cubes_name_the_key(cubes, message):
    with pytest.raises(ValueError, match=message):
        ndtrace.composite(tesseract_retina(), cubes=cubes, size=(32, 32))


def test_cubes_need_a_3d_retina():
    r = ndtrace.trace(facet_scene("phong"))
    with pytest.raises(ValueError, match=r"cubes: draws the cells of a 3D"):
        ndtrace.composite(r, cubes={"size": 0.5})
