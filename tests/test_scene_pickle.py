"""Scenes pickle and deep-copy (issue 23): the description travels, the built scene is rebuilt
on first use where it lands, and copies share the read-only field arrays.

The reference for every copy is a trace of the original, compared bit for bit."""

from __future__ import annotations

import concurrent.futures
import copy
import multiprocessing
import os
import pickle

import numpy as np
import pytest

import ndtrace

SCENES = os.path.join(os.path.dirname(__file__), "..", "scenes")


def _elevation_scene():
    axis = np.linspace(-1, 1, 6)
    x, y, z = np.meshgrid(axis, axis, axis, indexing="ij")
    f = np.exp(-2 * (x**2 + y**2 + z**2)) + 0.2 * x
    return (ndtrace.Scene(4).set_camera([0.6, 0.8, 1.0, 3.0], look_at=[0, 0, 0, 0],
                                        up=[[0, 1, 0, 0], [0, 0, 1, 0]], fov=50, resolution=10)
            .add_light("directional", direction=[0.3, 0.5, 0.2, 1.0])
            .add_object("elevation", field=f, height=0.5, smooth=True,
                        material={"colormap": "viridis"}))


def _scenes():
    # A builder scene with an array field, a file scene whose mesh file is relative to its
    # folder, and a scene loaded from a dict with numpy mesh arrays.
    v, s = ndtrace.mesh.elevation_map(np.random.default_rng(3).random((4, 4, 3)), height=0.3)
    from_dict = ndtrace.load_dict({
        "dim": 4, "camera": {"position": [0.3, 0.5, 0.4, 3.0], "look_at": [0, 0, 0, 0],
                             "up": [[0, 1, 0, 0], [0, 0, 1, 0]], "fov": 50, "resolution": 8},
        "objects": [{"shape": "mesh", "vertices": v, "simplices": s}]})
    return {"builder": _elevation_scene(),
            "file": ndtrace.load_file(os.path.join(SCENES, "icosphere.toml")),
            "dict": from_dict}


@pytest.mark.parametrize("kind", ["builder", "file", "dict"])
def test_a_pickled_scene_is_rebuilt_where_it_lands_and_traces_the_same(kind):
    scene = _scenes()[kind]
    want = ndtrace.trace(scene)
    again = pickle.loads(pickle.dumps(scene))
    assert again._compiled is None  # nothing built until it is used
    assert again == scene
    got = ndtrace.trace(again)
    for name in ("rgba", "depth", "normal", "object_id", "primitive_id"):
        assert np.array_equal(getattr(got, name), getattr(want, name)), name


def test_a_deep_copy_shares_the_field_and_the_built_scene_but_not_the_description():
    scene = _elevation_scene()
    built = scene.compiled()
    other = copy.deepcopy(scene)
    field = scene._data["objects"][0]["field"]
    assert other._data["objects"][0]["field"] is field and not field.flags.writeable
    assert other.compiled() is built
    other.set_render(samples=2)
    assert scene.compiled() is built and other.compiled() is not built
    assert "samples" not in scene._data.get("render", {})
    assert scene != other


def _trace_rgba(scene):
    return ndtrace.trace(scene).rgba


def test_a_scene_goes_to_another_process_and_comes_back_traced_the_same():
    scene = _elevation_scene()
    ctx = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(1, mp_context=ctx) as pool:
        rgba = pool.submit(_trace_rgba, scene).result(timeout=120)
    assert np.array_equal(rgba, ndtrace.trace(scene).rgba)
