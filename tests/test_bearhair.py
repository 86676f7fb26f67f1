"""The ``surface`` shape ("bear hair", course notes Part II(B)): a 2-surface of R^4 projected
into the retina directly and shaded by the limit of its thickening's lighting, checked against
the thickened surface traced as a mesh (``ndtrace.mesh.thicken_surface``)."""

import numpy as np
import pytest

import ndtrace
from ndtrace import surfaces
from ndtrace.mesh import thicken_surface

RES = 64
EXTENT = 0.85
CELL = 2 * EXTENT / RES


def oblique_scene(material=None, lights=True):
    """An orthographic camera looking obliquely into R^4 (so the retina cell is the same size
    everywhere: a sheet `width` cells wide is a tube of radius width·cell/2)."""
    s = ndtrace.Scene(4, ambient=[0.1, 0.1, 0.1]).set_camera(
        [1.2, 0.9, 0.7, 3.0], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]],
        projection="orthographic", extent=EXTENT, resolution=RES)
    if lights:
        s.add_light("directional", direction=[0.5, 0.8, 0.3, 0.6])
        s.add_light("directional", direction=[-0.6, 0.1, 0.7, 0.2], color=[0.4, 0.3, 0.3])
    return s.set_render(shadows=False)


def both(width, material, samples=1):
    """The Clifford torus bear-haired at `width` cells and thickened at the matching radius."""
    v, t = surfaces.clifford_torus(48)
    hair = oblique_scene().add_object("surface", vertices=v, triangles=t, width=width, material=material)
    tv, ts = thicken_surface(v, t, radius=width * CELL / 2, segments=16)
    tube = oblique_scene().add_object("mesh", vertices=tv, simplices=ts, material=material)
    tube.set_render(samples=samples)
    return ndtrace.trace(hair), ndtrace.trace(tube)


def test_the_bear_hair_mask_is_the_thin_thickened_surfaces():
    hair, tube = both(2.0, {"smooth": True})
    a, b = hair.hit, tube.hit
    iou = (a & b).sum() / (a | b).sum()
    assert a.sum() > 2000 and b.sum() > 2000
    assert iou >= 0.95, iou  # 0.99 measured; the issue asks ≥ 0.8


@pytest.mark.parametrize("material", [{"smooth": True},
                                      {"smooth": True, "specular": 0.6, "shininess": 12, "diffuse": 0.7}])
def test_the_bear_hair_shading_is_the_thickened_surfaces_average(material):
    """Each bear-hair cell is lit by the mean of the tube's lighting across its width; so its
    cells' mean colour is the thickened surface's (supersampled, a few cells thick)."""
    hair, tube = both(5.0, material, samples=8)

    def mean(r):
        return r.rgba[..., :3].sum(axis=(0, 1, 2)) / r.rgba[..., 3].sum()

    got, want = mean(hair), mean(tube)
    assert np.allclose(got, want, rtol=0.03), (got, want)  # within 1.3 % measured


def test_surfaces_occlude_and_are_occluded_in_4d():
    """A hypercube inside the torus's 4D hull: where the cube is nearer the surface does not
    show, where the surface is nearer it does; the ids say which."""
    v, t = surfaces.clifford_torus(48)
    s = oblique_scene().add_object("hypercube", transform=[{"scale": 0.3}])
    cube = ndtrace.trace(s)
    s.add_object("surface", vertices=v, triangles=t)
    both_ = ndtrace.trace(s)
    torus = ndtrace.trace(oblique_scene().add_object("surface", vertices=v, triangles=t))
    over = cube.hit & torus.hit
    assert over.sum() > 50
    nearer = torus.depth < cube.depth
    assert np.all(both_.object_id[over & nearer] == 1)
    assert np.all(both_.object_id[over & ~nearer] == 0)
    assert np.array_equal(both_.depth, np.minimum(cube.depth, torus.depth))


def test_surface_objects_round_trip_and_stay_out_of_the_bvh():
    v, t = surfaces.clifford_torus(8)
    s = oblique_scene().add_object("surface", vertices=v, triangles=t, width=1.5,
                                   material={"opacity": 0.5})
    again = ndtrace.load_toml(s.to_toml())
    assert again == s
    assert np.array_equal(ndtrace.trace(again).rgba, ndtrace.trace(s).rgba)


@pytest.mark.parametrize("change, message", [
    (dict(triangles=[[0, 1]]), "objects[0].triangles[0]: a triangle has 3 vertex indices, got 2"),
    (dict(triangles=[[0, 1, 99]]), "objects[0].triangles[0][2]: vertex index 99 out of range"),
    (dict(vertices=[[0, 0, 0, float("nan")], [1, 0, 0, 0], [0, 1, 0, 0]]), "objects[0].vertices[0][3]: non-finite"),
    (dict(width=-1), "objects[0].width: must be a number of retina cells in (0, 64], got -1"),
    (dict(material={"opacity": 2}), "objects[0].material.opacity: must be in (0, 1], got 2"),
])
def test_bad_surfaces_name_the_field(change, message):
    keys = dict(vertices=[[0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0]], triangles=[[0, 1, 2]])
    keys.update(change)
    s = oblique_scene().add_object("surface", **keys)
    with pytest.raises(ValueError) as e:
        ndtrace.trace(s)
    assert message in str(e.value)
