"""Clip hyperplanes in the tracer (``clip = [{normal, offset}]`` per object or scene, ``cap``):
the hits of clipped polytopes and spheres against brute force over every simplex and every ray
in N = 3, 4, 5; caps against the section; shadows; the same bits on any number of threads."""

import itertools

import numpy as np
import pytest

import ndtrace

pytest.importorskip("scipy.spatial")


def camera_rays(retina):
    """Origin and direction of each retina cell's centre ray, shape (…, N)."""
    info = retina._camera_info()
    n = retina.dim
    o = np.asarray(info["orientation"], float).reshape(n, n)
    shape = retina.depth.shape
    res = shape[::-1]
    s = float(info["cell"])
    idx = np.meshgrid(*[np.arange(r, dtype=float) for r in shape], indexing="ij")
    u = [(idx[n - 2 - k] + 0.5 - res[k] / 2) * s for k in range(n - 1)]
    if n >= 3:
        u[1] = -u[1]
    offset = sum(u[k][..., None] * o[:, k] for k in range(n - 1))
    position = np.asarray(info["position"], float)
    assert info["perspective"]
    return np.broadcast_to(position, offset.shape), o[:, n - 1] + offset


def brute_force(origins, dirs, vertices, simplices, planes):
    """Per ray: (t, simplex, margin) of the nearest hit kept by ``planes`` (n̂·x ≤ c), over every
    simplex; margin is how far the decision is from a tie (a boundary of a simplex or a clip)."""
    o_all = origins.reshape(-1, origins.shape[-1])
    d_all = dirs.reshape(-1, dirs.shape[-1])
    x = vertices[simplices]                       # (S, N, N)
    e = x[:, 1:] - x[:, :1]                       # (S, N−1, N)
    n = o_all.shape[1]
    chunk = max(1, 2_000_000 // (len(x) * n * n))
    out_t, out_best, out_margin = [], [], []
    for start in range(0, len(o_all), chunk):
        o, d = o_all[start:start + chunk], d_all[start:start + chunk]
        rays = len(o)
        m = np.empty((rays, len(x), n, n))
        m[:, :, :, : n - 1] = np.swapaxes(e, 1, 2)[None]
        m[:, :, :, n - 1] = -d[:, None, :]
        rhs = o[:, None, :] - x[None, :, 0, :]
        with np.errstate(all="ignore"):
            sol = np.linalg.solve(m, rhs[..., None])[..., 0]
        b = sol[..., : n - 1]
        t = sol[..., n - 1]
        bary = np.concatenate([1 - b.sum(-1, keepdims=True), b], axis=-1)
        inside = bary.min(-1)
        point = o[:, None, :] + t[..., None] * d[:, None, :]
        clip = np.full(t.shape, -np.inf)
        for normal, c in planes:
            nh = np.asarray(normal, float) / np.linalg.norm(normal)
            clip = np.maximum(clip, point @ nh - c)
        ok = (inside >= 0) & (t > 0) & (clip <= 0) & np.isfinite(t)
        tt = np.where(ok, t, np.inf)
        best = np.argmin(tt, axis=1)
        out_t.append(tt[np.arange(rays), best])
        out_best.append(best)
        # Distance from a tie: any candidate near a simplex boundary or a clip hyperplane.
        near = (np.abs(inside) < 1e-7) | ((np.abs(clip) < 1e-7) & (inside > -1e-7))
        out_margin.append(~near.any(axis=1))
    shape = dirs.shape[:-1]
    return (np.concatenate(out_t).reshape(shape), np.concatenate(out_best).reshape(shape),
            np.concatenate(out_margin).reshape(shape))


def scene_of(dim, vertices, simplices, clip, resolution, cap=False, scene_clip=None):
    position = [0.35 * (k + 1) for k in range(dim - 1)] + [3.5]
    up = [[1.0 if i == k else 0.0 for i in range(dim)] for k in range(1, dim - 1)]
    data = {"dim": dim,
            "camera": {"position": position, "look_at": [0] * dim, "up": up, "fov": 45,
                       "resolution": resolution},
            "objects": [{"shape": "mesh", "vertices": vertices, "simplices": simplices,
                         "clip": clip, "cap": cap}],
            "render": {"shadows": False}}
    if scene_clip:
        data["clip"] = scene_clip
    return ndtrace.load_dict(data)


def cube(dim):
    return ndtrace.mesh.convex_hull(list(itertools.product([-1.0, 1.0], repeat=dim)))


def sphere(dim, count=300):
    rng = np.random.default_rng(dim)
    p = rng.normal(size=(count, dim))
    return ndtrace.mesh.convex_hull(p / np.linalg.norm(p, axis=1, keepdims=True))


@pytest.mark.parametrize("dim, resolution", [(3, 24), (4, 10), (5, 7)])
@pytest.mark.parametrize("shape", ["cube", "sphere"])
def test_clipped_hits_equal_brute_force(dim, resolution, shape):
    vertices, simplices = cube(dim) if shape == "cube" else sphere(dim, 60 * dim)
    rng = np.random.default_rng(51 + dim)
    for _ in range(2):
        normal = rng.normal(size=dim)
        clip = [{"normal": normal.tolist(), "offset": float(rng.uniform(-0.3, 0.3))}]
        scene = scene_of(dim, vertices, simplices, clip, resolution)
        retina = ndtrace.trace(scene)
        origins, dirs = camera_rays(retina)
        t, prim, margin = brute_force(origins, dirs, vertices, simplices,
                                      [(c["normal"], c["offset"]) for c in clip])
        hit = np.isfinite(t)
        assert margin.mean() > 0.9
        # Hit or miss as brute force, the same simplex, the same depth.
        np.testing.assert_array_equal((retina.object_id >= 0)[margin], hit[margin])
        both = margin & hit
        assert both.sum() > 20, "the clipped object is seen"
        np.testing.assert_array_equal(retina.primitive_id[both], prim[both])
        depth = t * np.linalg.norm(dirs, axis=-1)
        np.testing.assert_allclose(retina.depth[both], depth[both], rtol=1e-5)
        # The clip removes something that is there without it.
        unclipped = ndtrace.trace(scene_of(dim, vertices, simplices, [], resolution))
        assert not np.array_equal(unclipped.depth, retina.depth)


def test_scene_clips_act_on_every_object_like_object_clips():
    vertices, simplices = cube(4)
    clip = [{"normal": [0.3, 0, 0.2, 1], "offset": 0.1}]
    a = ndtrace.trace(scene_of(4, vertices, simplices, clip, 12))
    b = ndtrace.trace(scene_of(4, vertices, simplices, [], 12, scene_clip=clip))
    np.testing.assert_array_equal(a.depth, b.depth)
    np.testing.assert_array_equal(a.rgba, b.rgba)


def test_cap_fills_the_cut_with_the_section():
    vertices, simplices = cube(4)
    normal = np.array([0.2, 0.1, 0.3, 1.0])
    c = 0.15
    clip = [{"normal": normal.tolist(), "offset": c}]
    retina = ndtrace.trace(scene_of(4, vertices, simplices, clip, 12, cap=True))
    origins, dirs = camera_rays(retina)
    t, prim, margin = brute_force(origins, dirs, vertices, simplices, [(normal, c)])
    # The cap: where the ray crosses the hyperplane inside the tesseract, before the kept hit.
    nh = normal / np.linalg.norm(normal)
    o = origins
    tp = (c - o @ nh) / (dirs @ nh)
    x = o + tp[..., None] * dirs
    inside = np.all(np.abs(x) < 1 - 1e-6, axis=-1) & (tp > 0)
    cap_first = inside & (tp < t)
    robust = margin & ~(np.abs(np.abs(x).max(-1) - 1) < 1e-6)
    assert (cap_first & robust).sum() > 20, "the cap is seen"
    np.testing.assert_array_equal((retina.object_id == 1)[robust], cap_first[robust])
    depth = tp * np.linalg.norm(dirs, axis=-1)
    sel = cap_first & robust
    np.testing.assert_allclose(retina.depth[sel], depth[sel], rtol=1e-6)
    # The cap's shading normal is the hyperplane's (turned toward the viewer).
    np.testing.assert_allclose(np.abs(retina.normal[sel] @ nh), 1, atol=1e-6)


def test_cap_of_a_non_convex_object_only_inside_it():
    # Two tesseracts side by side as one mesh (a non-convex union); the cut's cap must not
    # bridge the gap between them.
    v, s = cube(4)
    v2 = np.vstack([v + [-1.6, 0, 0, 0], v + [1.6, 0, 0, 0]]) * [1, 1, 1, 1]
    s2 = np.vstack([s, s + len(v)])
    clip = [{"normal": [0, 0, 0, 1], "offset": 0.2}]
    retina = ndtrace.trace(scene_of(4, v2 * 0.6, s2, clip, 16, cap=True))
    origins, dirs = camera_rays(retina)
    tp = (0.2 - origins[..., 3]) / dirs[..., 3]
    x = origins + tp[..., None] * dirs
    xs = x / 0.6
    in_gap = (np.abs(xs[..., 0]) < 0.5) & (np.abs(xs[..., 1:3]) < 0.9).all(-1)
    assert in_gap.sum() > 3
    assert not np.any(retina.object_id[in_gap] == 1), "no cap across the gap"
    assert np.any(retina.object_id == 1)


def test_shadows_respect_clips():
    floor = {"shape": "hypercube", "transform": [{"scale": [3, 0.05, 3, 3]},
                                                  {"translate": [0, -1, 0, 0]}]}
    blocker = {"shape": "hypercube", "transform": [{"scale": 0.5}, {"translate": [0, 1, 0, 0]}]}
    base = {"dim": 4, "camera": {"position": [0.5, 3, 1, 4], "look_at": [0, -1, 0, 0],
                                 "up": [[0, 1, 0, 0], [0, 0, 1, 0]], "fov": 60, "resolution": 16},
            "lights": [{"type": "directional", "direction": [0, 1, 0, 0]}]}
    alone = ndtrace.trace(ndtrace.load_dict({**base, "objects": [floor]}))
    shadowed = ndtrace.trace(ndtrace.load_dict({**base, "objects": [floor, blocker]}))
    # The blocker clipped away whole: its shadow goes with it.
    gone = {**blocker, "clip": [{"normal": [0, 1, 0, 0], "offset": 0.0}]}
    clipped = ndtrace.trace(ndtrace.load_dict({**base, "objects": [floor, gone]}))
    on_floor = alone.object_id == 0
    assert not np.array_equal(alone.rgba[on_floor], shadowed.rgba[on_floor])
    np.testing.assert_array_equal(clipped.rgba[on_floor & (clipped.object_id == 0)],
                                  alone.rgba[on_floor & (clipped.object_id == 0)])


def test_clipped_traces_are_bit_identical_on_any_number_of_threads():
    vertices, simplices = sphere(4, 200)
    data = scene_of(4, vertices, simplices, [{"normal": [1, 0.2, 0, 0.5], "offset": 0.1}], 16,
                    cap=True).to_dict()
    data["lights"] = [{"type": "directional", "direction": [0.3, 1, 0.2, 0.5]}]
    data["render"] = {"samples": 4, "shadows": True}
    scene = ndtrace.load_dict(data)
    one, two = ndtrace.trace(scene, threads=1), ndtrace.trace(scene, threads=2)
    for name in ("rgba", "depth", "normal", "object_id", "primitive_id"):
        np.testing.assert_array_equal(getattr(one, name), getattr(two, name))


@pytest.mark.parametrize("clip, message", [
    ([{"normal": [0, 0, 0], "offset": 0}], r"objects\[0\]\.clip\[0\]\.normal: expected 4 numbers"),
    ([{"normal": [0, 0, 0, 0], "offset": 0}], r"objects\[0\]\.clip\[0\]\.normal: must be"),
    ([{"normal": [0, 0, 0, 1], "offset": float("nan")}], r"objects\[0\]\.clip\[0\]\.offset"),
    ([{"normal": [0, 0, 0, 1]}], r"missing field `offset`"),
])
def test_bad_clips_name_the_key(clip, message):
    v, s = cube(4)
    with pytest.raises(ValueError, match=message):
        scene_of(4, v, s, clip, 4).compiled()


def test_clip_round_trips_and_slices():
    v, s = cube(4)
    scene = scene_of(4, v, s, [{"normal": [1, 0, 0, 0], "offset": 0.5}], 8, cap=True)
    assert ndtrace.load_toml(scene.to_toml()) == scene
    cut = ndtrace.slice_scene(scene, [0, 0, 0, 1], 0.0).to_dict()
    assert cut["objects"][0]["clip"] == [{"normal": [1.0, 0.0, 0.0], "offset": 0.5}]
