"""Tests of the N-dimensional tracer (``ndtrace.trace``) and of scene loading and validation.

Every expectation is computed here, independently of the library, from the documented
conventions (``docs/scene-format.md``, ``crates/ndtrace/src/camera.rs``):

* the orientation's columns are u_1 ... u_{N-1} and then the viewing direction;
* cell (i_1, ..., i_{N-1}) is centred at u_k = (i_k + 1/2 - R_k/2) s, except
  u_2 = (R_2/2 - i_2 - 1/2) s; retina arrays are indexed [i_{N-1}, ..., i_1];
* s = 2 tan(fov/2) / R_1 (perspective) or 2 extent / R_1 (orthographic);
* perspective rays leave the position along col_N + sum u_k col_k and depth is the Euclidean
  distance; orthographic rays leave position + sum u_k col_k along col_N and depth is t.

Ray-simplex references are brute-force numpy (an SVD normal and the inverse of the
[edges | normal] matrix), slab / half-space clipping for convex polytopes, and exact grids of
cell centres for the watertightness tests. Random inputs come from ``numpy.random.default_rng``
with fixed seeds.
"""

from __future__ import annotations

import itertools
import math
import re
import time
import warnings

import numpy as np
import pytest

import ndtrace

# ---------------------------------------------------------------------------------------------
# Helpers: the camera convention, brute-force intersection, meshes built in numpy
# ---------------------------------------------------------------------------------------------


def rng_for(seed: int, n: int) -> np.random.Generator:
    return np.random.default_rng(7919 * seed + n)


def axis_orientation(n: int) -> np.ndarray:
    """Columns e_1 ... e_{N-1}, -e_N: the course's camera looking down -x_N."""
    o = np.eye(n)
    o[n - 1, n - 1] = -1.0
    return o


def retina_u(res, s: float) -> np.ndarray:
    """Retina coordinates (u_1 ... u_{N-1}) of every cell centre, in numpy order
    [i_{N-1}, ..., i_1, k]."""
    axes = []
    for k, r in enumerate(res):
        i = np.arange(r, dtype=float)
        axes.append((r / 2 - i - 0.5) * s if k == 1 else (i + 0.5 - r / 2) * s)
    grids = np.meshgrid(*axes[::-1], indexing="ij")  # grids[j] is u_{m-j}
    return np.stack(grids[::-1], axis=-1)


def cell_size(res, *, fov=None, extent=None) -> float:
    if fov is not None:
        return 2 * math.tan(math.radians(fov) / 2) / res[0]
    return 2 * extent / res[0]


def camera_rays(position, orientation, res, s, projection="perspective"):
    """(origins, directions), each of shape retina + (N,), from the documented convention."""
    position = np.asarray(position, float)
    o = np.asarray(orientation, float)
    n = position.size
    u = retina_u(res, s)
    offset = u @ o[:, : n - 1].T
    view = o[:, n - 1]
    if projection == "perspective":
        return np.broadcast_to(position, offset.shape).copy(), view + offset
    return position + offset, np.broadcast_to(view, offset.shape).copy()


def brute_force(origins, dirs, pts, projection="perspective", amb=1e-7, chunk=1024):
    """Nearest hit of every ray with every simplex (S, N, N) by dense numpy algebra.

    Returns (hit, index, depth, normal, usable): ``usable`` is False where the answer is
    ambiguous (a ray within ``amb`` of a simplex boundary in barycentric terms, nearly parallel
    to a simplex, or two simplices at nearly equal depth)."""
    s_count, n, _ = pts.shape
    x0 = pts[:, 0]
    e = pts[:, 1:] - x0[:, None]
    _, _, vt = np.linalg.svd(e)
    nrm = vt[:, -1]  # unit normal (null vector of the edges)
    minv = np.linalg.inv(np.concatenate([e, nrm[:, None]], axis=1).transpose(0, 2, 1))
    o = origins.reshape(-1, n)
    d = dirs.reshape(-1, n)
    out_hit, out_idx, out_depth, out_normal, out_ok = [], [], [], [], []
    for a in range(0, len(o), chunk):
        oc, dc = o[a:a + chunk], d[a:a + chunk]
        dlen = np.linalg.norm(dc, axis=1)
        den = dc @ nrm.T
        num = np.einsum("sk,csk->cs", nrm, x0[None] - oc[:, None])
        with np.errstate(divide="ignore", invalid="ignore"):
            t = num / den
        parallel = np.abs(den) < 1e-9 * dlen[:, None]
        t = np.where(parallel, np.nan, t)
        x = oc[:, None] + t[..., None] * dc[:, None]
        lam = np.einsum("sij,csj->csi", minv, x - x0[None])[..., : n - 1]
        bary_min = np.minimum(1 - lam.sum(-1), lam.min(-1))
        front = t > 0
        hit = front & (bary_min >= 0)
        near_edge = front & (np.abs(bary_min) < amb)
        depth_all = np.where(hit, t * (dlen[:, None] if projection == "perspective" else 1.0), np.inf)
        order = np.argsort(depth_all, axis=1)
        best = order[:, 0]
        rows = np.arange(len(oc))
        d1 = depth_all[rows, best]
        d2 = depth_all[rows, order[:, 1]] if s_count > 1 else np.full(len(oc), np.inf)
        with np.errstate(invalid="ignore"):
            tie = np.isfinite(d1) & (d2 - d1 <= 1e-6 * np.abs(d1))
        ok = ~(near_edge.any(1) | parallel.any(1) | tie)
        any_hit = np.isfinite(d1)
        nb = nrm[best] * np.where(np.sum(nrm[best] * dc, 1) > 0, -1.0, 1.0)[:, None]
        out_hit.append(any_hit)
        out_idx.append(np.where(any_hit, best, -1))
        out_depth.append(d1)
        out_normal.append(nb)
        out_ok.append(ok)
    shape = origins.shape[:-1]
    return (np.concatenate(out_hit).reshape(shape), np.concatenate(out_idx).reshape(shape),
            np.concatenate(out_depth).reshape(shape), np.concatenate(out_normal).reshape(shape + (n,)),
            np.concatenate(out_ok).reshape(shape))


def orient_outward(vertices: np.ndarray, simplices: np.ndarray) -> np.ndarray:
    """Reorders simplices so that det[x_1 - x_0 ... x_{N-1} - x_0 | c] > 0, with c the simplex
    centroid (outward for a convex mesh around the origin)."""
    p = vertices[simplices]
    e = p[:, 1:] - p[:, :1]
    det = np.linalg.det(np.concatenate([e, p.mean(1)[:, None]], axis=1))
    assert np.all(np.abs(det) > 1e-9)
    s = simplices.copy()
    s[det < 0, 0], s[det < 0, 1] = simplices[det < 0, 1], simplices[det < 0, 0]
    return s


def kuhn_hypercube(n: int):
    """Boundary of [-1, 1]^N: each facet Kuhn-triangulated, simplices oriented outward."""
    corners = np.array(list(itertools.product([-1.0, 1.0], repeat=n)))
    index = {tuple(c): i for i, c in enumerate(corners)}
    simplices = []
    for a in range(n):
        for sign in (-1.0, 1.0):
            free = [k for k in range(n) if k != a]
            for perm in itertools.permutations(free):
                p = -np.ones(n)
                p[a] = sign
                chain = [index[tuple(p)]]
                for k in perm:
                    p = p.copy()
                    p[k] = 1.0
                    chain.append(index[tuple(p)])
                simplices.append(chain)
    return corners, orient_outward(corners, np.array(simplices))


def cross_polytope_mesh(n: int):
    vertices = np.concatenate([np.eye(n), -np.eye(n)])
    simplices = np.array([[i + n * ((signs >> i) & 1) for i in range(n)] for signs in range(2 ** n)])
    return vertices, orient_outward(vertices, simplices)


def flipped(simplices: np.ndarray) -> np.ndarray:
    s = simplices.copy()
    s[:, [0, 1]] = s[:, [1, 0]]
    return s


def random_simplices(rng, n, count, spread=0.35, box=1.0):
    """``count`` well-shaped random (N-1)-simplices in R^N, (count, N, N)."""
    out = []
    while len(out) < count:
        c = rng.uniform(-box, box, n)
        p = c + rng.normal(0.0, spread, (n, n))
        sv = np.linalg.svd(p[1:] - p[0], compute_uv=False)
        if sv[-1] > 0.05 * sv[0]:
            out.append(p)
    return np.array(out)


def facing_simplex(rng, n, radius, tilt):
    """A random simplex roughly facing the x_N axis: spread ``radius`` across it, ``tilt`` along it."""
    while True:
        flat = rng.normal(size=(n, n - 1))
        flat *= radius / np.linalg.norm(flat, axis=1, keepdims=True)
        if np.linalg.svd(flat[1:] - flat[0], compute_uv=False)[-1] > 0.4 * radius:
            return np.column_stack([flat, rng.uniform(-tilt, tilt, n)])


def random_up(rng, n):
    return rng.normal(size=(n - 2, n))


# ---------------------------------------------------------------------------------------------
# 1. Analytic: a simplex and a hypercube seen head-on
# ---------------------------------------------------------------------------------------------

HEAD_ON_RES = {3: [32, 27], 4: [16, 13, 11], 5: [10, 9, 8, 7]}


def head_on_setup(n, seed):
    rng = rng_for(seed, n)
    while True:
        flat = rng.normal(size=(n, n - 1))
        flat *= 1.2 / np.linalg.norm(flat, axis=1, keepdims=True)
        sv = np.linalg.svd(flat[1:] - flat[0], compute_uv=False)
        if sv[-1] > 0.5:
            break
    h = rng.uniform(-0.5, 0.5)
    vertices = np.column_stack([flat, np.full(n, h)])
    position = np.concatenate([rng.uniform(-0.2, 0.2, n - 1), [3.0]])
    res = HEAD_ON_RES[n]
    extent = 1.1
    s = cell_size(res, extent=extent)
    q = position[: n - 1] + retina_u(res, s)  # projections of the cell centres
    lam = np.linalg.solve((flat[1:] - flat[0]).T, (q - flat[0]).reshape(-1, n - 1).T).T
    bary = np.column_stack([1 - lam.sum(1), lam]).reshape(q.shape[:-1] + (n,))
    inside = bary.min(-1) >= 0
    clear = np.abs(bary.min(-1)) > 1e-7
    return vertices, position, res, extent, h, inside, clear


@pytest.mark.parametrize("n", [3, 4, 5])
def test_head_on_simplex_coverage_depth_and_lambert(n):
    vertices, position, res, extent, h, inside, clear = head_on_setup(n, 1)
    color = np.array([0.9, 0.5, 0.25])
    light = np.array([1.0, 0.8, 0.5])
    normal = np.zeros(n)
    normal[-1] = 1.0  # toward the camera at x_N = 3
    theta = math.radians(50)
    tilted = math.cos(theta) * normal + math.sin(theta) * np.eye(n)[0]

    def scene(direction, ambient=(0, 0, 0), flip=False):
        simplex = [list(range(n))]
        if flip:
            simplex = [[1, 0] + list(range(2, n))]
        return (ndtrace.Scene(n, ambient=list(ambient))
                .set_camera(position, orientation=axis_orientation(n), projection="orthographic",
                            extent=extent, resolution=res)
                .add_object("mesh", vertices=vertices, simplices=simplex,
                            material={"color": color, "diffuse": 0.8, "ambient": 0.5})
                .add_light("directional", direction=direction, color=light)
                # A light behind the simplex adds nothing (max(0, n.l)).
                .add_light("directional", direction=-normal, color=[5, 5, 5]))

    assert inside[clear].sum() > 20 and (~inside[clear]).sum() > 20
    for flip in (False, True):
        r = ndtrace.trace(scene(2.5 * normal, flip=flip))
        assert r.shape == tuple(res[::-1])
        np.testing.assert_array_equal(r.hit[clear], inside[clear])
        hit = r.hit
        np.testing.assert_allclose(r.depth[hit], 3.0 - h, rtol=1e-6)
        assert np.all(np.isinf(r.depth[~hit]))
        np.testing.assert_allclose(r.normal[hit], np.broadcast_to(normal, r.normal[hit].shape), atol=1e-6)
        assert np.all(r.normal[~hit] == 0)
        assert np.all(r.object_id[hit] == 0) and np.all(r.primitive_id[hit] == 0)
        assert np.all(r.object_id[~hit] == -1) and np.all(r.primitive_id[~hit] == -1)
        np.testing.assert_allclose(r.rgba[hit], np.broadcast_to(np.r_[0.8 * color * light, 1.0], (hit.sum(), 4)),
                                   rtol=1e-6)
        assert np.all(r.rgba[~hit] == 0)

    r = ndtrace.trace(scene(tilted))
    np.testing.assert_allclose(r.rgba[r.hit][:, :3], np.broadcast_to(0.8 * color * light * math.cos(theta),
                                                                    (r.hit.sum(), 3)), rtol=1e-6)
    ambient = np.array([0.1, 0.2, 0.3])
    r = ndtrace.trace(scene(tilted, ambient=ambient))
    expected = 0.5 * ambient * color + 0.8 * color * light * math.cos(theta)
    np.testing.assert_allclose(r.rgba[r.hit][:, :3], np.broadcast_to(expected, (r.hit.sum(), 3)), rtol=1e-6)


@pytest.mark.parametrize("n", [3, 4])
def test_point_light_falloff_specular_and_one_sided_lighting(n):
    """Point light at P: light * d^-falloff * (diffuse color max(0, n.l) + specular max(0, n.h)^shininess)
    with h the unit half-vector of l and the direction to the eye (+e_N for this camera)."""
    vertices, position, res, extent, h, inside, clear = head_on_setup(n, 7)
    color = np.array([0.9, 0.5, 0.25])
    light_pos = np.r_[0.3, -0.2, 0.1][: n - 1].tolist() + [2.0]
    normal = np.eye(n)[-1]

    def scene(simplex, **render):
        return (ndtrace.Scene(n, ambient=[0, 0, 0])
                .set_camera(position, orientation=axis_orientation(n), projection="orthographic",
                            extent=extent, resolution=res)
                .add_object("mesh", vertices=vertices, simplices=[simplex],
                            material={"color": color, "diffuse": 0.8, "specular": [0.5, 0.25, 0.0], "shininess": 7})
                .add_light("point", position=light_pos, color=[1, 2, 3], falloff=2)
                .set_render(**render))

    # Order the vertices so that the normal (eq. 6) faces the viewer: det[x_1 - x_0 ... | e_N] > 0.
    toward = np.linalg.det(np.vstack([vertices[1:] - vertices[0], normal])) > 0
    facing = list(range(n)) if toward else [1, 0] + list(range(2, n))
    away = [1, 0] + list(range(2, n)) if toward else list(range(n))
    r = ndtrace.trace(scene(facing, two_sided=False))
    q = position[: n - 1] + retina_u(res, cell_size(res, extent=extent))
    x = np.concatenate([q, np.full(q.shape[:-1] + (1,), h)], -1)
    to_light = np.array(light_pos) - x
    dist = np.linalg.norm(to_light, axis=-1, keepdims=True)
    l = to_light / dist
    half = (l + normal) / np.linalg.norm(l + normal, axis=-1, keepdims=True)
    expected = dist ** -2 * np.array([1, 2, 3]) * (0.8 * color * (l @ normal)[..., None]
                                                     + np.array([0.5, 0.25, 0.0]) * ((half @ normal) ** 7)[..., None])
    m = r.hit & clear
    assert m.sum() > 20
    np.testing.assert_allclose(r.rgba[m][:, :3], expected[m], rtol=1e-5, atol=1e-7)
    same_retina(r, ndtrace.trace(scene(away)))
    # One-sided: the flipped simplex's normal points away from the viewer and the light.
    r = ndtrace.trace(scene(away, two_sided=False))
    assert np.all(r.rgba[r.hit][:, :3] == 0) and np.all(r.rgba[r.hit][:, 3] == 1)
    np.testing.assert_allclose(r.normal[r.hit], np.broadcast_to(-normal, (r.hit.sum(), n)), atol=1e-7)


def test_smooth_normals_follow_the_sphere():
    """Interpolated vertex normals of a sphere are much closer to the radial direction than the
    flat facet normals."""
    res = [32, 32]

    def trace(smooth):
        scene = (ndtrace.Scene(3).set_camera([0, 0, 4], look_at=[0, 0, 0], up=[0, 1, 0], fov=40, resolution=res)
                 .add_object("sphere", subdivisions=2, material={"smooth": smooth}))
        return scene, ndtrace.trace(scene)

    scene, smooth = trace(True)
    _, flat = trace(False)
    same = ("depth", "object_id", "primitive_id")
    for name in same:
        np.testing.assert_array_equal(getattr(smooth, name), getattr(flat, name))
    origins, dirs = camera_rays([0, 0, 4], np.array(scene.compiled().camera_orientation), res, cell_size(res, fov=40))
    hit = smooth.hit
    x = origins[hit] + smooth.depth[hit][:, None] * dirs[hit] / np.linalg.norm(dirs[hit], axis=-1, keepdims=True)
    radial = x / np.linalg.norm(x, axis=-1, keepdims=True)
    err_smooth = 1 - np.sum(smooth.normal[hit] * radial, -1)
    err_flat = 1 - np.sum(flat.normal[hit] * radial, -1)
    assert err_smooth.max() < 0.01 and err_smooth.mean() < 0.3 * err_flat.mean()
    np.testing.assert_allclose(np.linalg.norm(smooth.normal[hit], axis=-1), 1, atol=1e-6)


def test_mesh_from_npz_file(tmp_path):
    rng = rng_for(8, 3)
    pts = facing_simplex(rng, 3, 1.6, 0.3)
    (tmp_path / "meshes").mkdir()
    np.savez(tmp_path / "meshes" / "tri.npz", vertices=pts, simplices=np.array([[0, 1, 2]], dtype=np.int32))
    text = GOOD_TOML.split("[[objects]]")[0] + '[[objects]]\nshape = "mesh"\nfile = "meshes/tri.npz"\n'
    (tmp_path / "scene.toml").write_text(text)
    from_file = ndtrace.trace(ndtrace.load_file(tmp_path / "scene.toml"))
    from_dict = ndtrace.trace(ndtrace.load_dict(
        {**base_dict(), "objects": [{"shape": "mesh", "file": "meshes/tri.npz"}]}, base=str(tmp_path)))
    inline = ndtrace.trace(ndtrace.load_dict(
        {**base_dict(), "objects": [{"shape": "mesh", "vertices": pts, "simplices": [[0, 1, 2]]}]}))
    assert inline.hit.sum() > 3
    same_retina(inline, from_file)
    same_retina(inline, from_dict)
    (tmp_path / "scene.toml").write_text(text.replace("tri.npz", "missing.npz"))
    with pytest.raises(ValueError, match=r"scene\.toml:\d+:\d+: objects\[0\]\.file: .*missing\.npz"):
        ndtrace.load_file(tmp_path / "scene.toml")


@pytest.mark.parametrize("n", [3, 4])
def test_hard_shadow_of_an_occluder(n):
    """A small simplex above a large one casts the shadow computed by clipping shadow rays."""
    rng = rng_for(2, n)
    corner = np.vstack([np.zeros(n - 1), 20 * np.eye(n - 1)]) - 5.0
    base = np.column_stack([corner, np.zeros(n)])
    while True:
        occ2 = rng.uniform(-0.6, 0.6, (n, n - 1))
        if np.linalg.svd(occ2[1:] - occ2[0], compute_uv=False)[-1] > 0.3:
            break
    occ = np.column_stack([occ2, np.full(n, 0.6)])
    theta = math.radians(35)
    ldir = np.zeros(n)
    ldir[0], ldir[-1] = math.sin(theta), math.cos(theta)
    res = HEAD_ON_RES[n]
    extent = 1.6
    position = np.r_[np.zeros(n - 1), 4.0]
    scene = (ndtrace.Scene(n, ambient=[0.25, 0.25, 0.25])
             .set_camera(position, orientation=axis_orientation(n), projection="orthographic",
                         extent=extent, resolution=res)
             .add_object("mesh", vertices=base, simplices=[list(range(n))], material={"color": [1, 1, 1]})
             .add_object("mesh", vertices=occ, simplices=[list(range(n))], material={"color": [1, 0, 0]})
             .add_light("directional", direction=ldir))
    r = ndtrace.trace(scene)
    q = retina_u(res, cell_size(res, extent=extent)).reshape(-1, n - 1)

    def bary(points2, x):
        lam = np.linalg.solve((points2[1:] - points2[0]).T, (x - points2[0]).T).T
        return np.minimum(1 - lam.sum(1), lam.min(1))

    on_occ = bary(occ2, q)
    shadow_foot = q + (0.6 / ldir[-1]) * ldir[: n - 1]  # where the shadow ray crosses x_N = 0.6
    shadowed = bary(occ2, shadow_foot)
    clear = (np.abs(on_occ) > 1e-7) & (np.abs(shadowed) > 1e-7) & (np.abs(bary(base[:, :-1], q)) > 1e-7)
    base_cells = (on_occ < 0).reshape(r.shape)
    in_shadow = (base_cells.ravel() & (shadowed >= 0)).reshape(r.shape)
    lit = base_cells & ~in_shadow
    clear = clear.reshape(r.shape)
    assert (in_shadow & clear).sum() > 5 and (lit & clear).sum() > 5
    np.testing.assert_array_equal(r.object_id[clear], np.where(base_cells, 0, 1)[clear])
    np.testing.assert_allclose(r.rgba[in_shadow & clear][:, :3], 0.25, rtol=1e-6)
    np.testing.assert_allclose(r.rgba[lit & clear][:, :3], 0.25 + math.cos(theta), rtol=1e-6)
    # Without shadows every base cell is lit.
    r2 = ndtrace.trace(scene.copy().set_render(shadows=False))
    np.testing.assert_allclose(r2.rgba[base_cells & clear][:, :3], 0.25 + math.cos(theta), rtol=1e-6)


@pytest.mark.parametrize("n", [3, 4, 5])
def test_hypercube_face_on_covers_the_projected_face(n):
    res = {3: [16, 12], 4: [12, 10, 8], 5: [8, 8, 6, 6]}[n]
    shift = np.array([0.3, -0.2, 0.1, -0.15][: n - 1] + [0.0])
    position = np.r_[np.zeros(n - 1), 5.0]
    extent = 2.0
    scene = (ndtrace.Scene(n)
             .set_camera(position, orientation=axis_orientation(n), projection="orthographic",
                         extent=extent, resolution=res)
             .add_object("hypercube", transform=[{"translate": shift}]))
    r = ndtrace.trace(scene)
    q = retina_u(res, cell_size(res, extent=extent)) - shift[: n - 1]
    margin = np.abs(np.abs(q) - 1).min(-1)
    clear = margin > 1e-9
    inside = np.all(np.abs(q) < 1, axis=-1)
    assert clear.all() and inside.sum() > 0 and (~inside).sum() > 0
    np.testing.assert_array_equal(r.hit, inside)
    np.testing.assert_allclose(r.depth[inside], 4.0, rtol=1e-7)
    np.testing.assert_allclose(r.normal[inside], np.broadcast_to(np.eye(n)[-1], (inside.sum(), n)), atol=1e-7)


# ---------------------------------------------------------------------------------------------
# 2. Independent oracle: random simplex soups against brute-force numpy
# ---------------------------------------------------------------------------------------------

ORACLE_RES = {3: [32, 24], 4: [16, 14, 12], 5: [12, 10, 9, 8]}
SOUP = {3: dict(spread=0.45, box=0.8, fov=50.0), 4: dict(spread=0.6, box=0.5, fov=32.0),
        5: dict(spread=0.9, box=0.45, fov=28.0)}
"""Simplex size, spread of their centres and field of view: large enough simplices for about a
third of the rays to hit something in every dimension."""


def soup_scene(n, rng, camera: dict):
    count = int(rng.integers(30, 61))
    pts = random_simplices(rng, n, count, spread=SOUP[n]["spread"], box=SOUP[n]["box"])
    split = count // 3
    scene = ndtrace.Scene(n).set_camera(**camera).add_light("directional", direction=rng.normal(size=n))
    for lo, hi in ((0, split), (split, count)):
        m = hi - lo
        verts = pts[lo:hi].reshape(-1, n)
        perm = rng.permutation(len(verts))  # a nontrivial vertex order
        inv = np.argsort(perm)
        scene.add_object("mesh", vertices=verts[perm], simplices=inv[np.arange(m * n).reshape(m, n)])
    return scene, pts, split


@pytest.mark.parametrize("n", [3, 4, 5])
@pytest.mark.parametrize("kind", ["look_at", "orientation", "orthographic"])
def test_random_soup_matches_brute_force(n, kind):
    rng = rng_for({"look_at": 11, "orientation": 12, "orthographic": 13}[kind], n)
    res = ORACLE_RES[n]
    fov = SOUP[n]["fov"]
    if kind == "look_at":
        direction = rng.normal(size=n)
        position = 4.5 * direction / np.linalg.norm(direction)
        camera = dict(position=position, look_at=rng.normal(0, 0.1, n), up=random_up(rng, n),
                      fov=fov, resolution=res)
        if n == 3:
            camera["up"] = camera["up"][0]
        s, projection = cell_size(res, fov=fov), "perspective"
    else:
        q, rr = np.linalg.qr(rng.normal(size=(n, n)))
        q = q * np.sign(np.diag(rr))  # Haar-random, either determinant
        position = -4.5 * q[:, -1] + rng.normal(0, 0.1, n)
        projection = "perspective" if kind == "orientation" else "orthographic"
        camera = dict(position=position, orientation=q, resolution=res, projection=projection)
        if projection == "perspective":
            camera["fov"] = fov
            s = cell_size(res, fov=fov)
        else:
            camera["extent"] = 4.5 * math.tan(math.radians(fov) / 2)
            s = cell_size(res, extent=camera["extent"])
    scene, pts, split = soup_scene(n, rng, camera)
    orientation = np.array(scene.compiled().camera_orientation)
    if kind != "look_at":
        np.testing.assert_array_equal(orientation, camera["orientation"])  # used exactly as given
    origins, dirs = camera_rays(position, orientation, res, s, projection)
    hit, idx, depth, normal, ok = brute_force(origins, dirs, pts, projection)
    r = ndtrace.trace(scene)
    assert r.shape == tuple(res[::-1])
    assert ok.mean() > 0.97, f"too many ambiguous cells: {(~ok).sum()}"
    assert 0.15 < hit[ok].mean() < 0.95
    assert len(np.unique(idx[ok & hit])) > 15
    np.testing.assert_array_equal(r.hit[ok], hit[ok])
    exp_obj = np.where(idx < 0, -1, np.where(idx < split, 0, 1))
    exp_prim = np.where(idx < 0, -1, np.where(idx < split, idx, idx - split))
    np.testing.assert_array_equal(r.object_id[ok], exp_obj[ok])
    np.testing.assert_array_equal(r.primitive_id[ok], exp_prim[ok])
    h = ok & hit
    np.testing.assert_allclose(r.depth[h], depth[h], rtol=1e-5)
    assert np.all(np.isinf(r.depth[ok & ~hit]))
    # Two-sided: the unit normal of the hit simplex, turned toward the viewer.
    np.testing.assert_allclose(r.normal[h], normal[h], atol=1e-5)


@pytest.mark.parametrize("n", [3, 4, 5])
def test_look_at_frame(n):
    """look_at: orthonormal, last column the view direction, up vectors Gram-Schmidt'ed in order
    into u_2 ... u_{N-1}, u_1 completing det[u_1 ... u_{N-1}, -view] = +1."""
    rng = rng_for(3, n)
    for _ in range(5):
        position, target = rng.normal(size=n) * 3, rng.normal(size=n)
        up = random_up(rng, n)
        scene = ndtrace.Scene(n).set_camera(position, look_at=target, up=up, fov=30, resolution=4)
        o = np.array(scene.compiled().camera_orientation)
        np.testing.assert_allclose(o.T @ o, np.eye(n), atol=1e-12)
        view = (target - position) / np.linalg.norm(target - position)
        np.testing.assert_allclose(o[:, -1], view, atol=1e-12)
        basis = [view]
        for k in range(n - 2):
            w = up[k] - sum(np.dot(up[k], b) * b for b in basis)
            w /= np.linalg.norm(w)
            np.testing.assert_allclose(o[:, k + 1], w, atol=1e-10)
            basis.append(w)
        np.testing.assert_allclose(np.linalg.det(np.column_stack([o[:, :-1], -o[:, -1]])), 1.0, atol=1e-12)


# ---------------------------------------------------------------------------------------------
# 3. Watertightness: rays through vertices, edges and ridges of closed meshes
# ---------------------------------------------------------------------------------------------

SPHERE_SUB = 2


def halfspaces(shape, n):
    """(A, b) with the solid = {x : A x <= b}."""
    if shape == "hypercube":
        return np.concatenate([np.eye(n), -np.eye(n)]), np.ones(2 * n)
    signs = np.array(list(itertools.product([-1.0, 1.0], repeat=n)))
    return signs, np.ones(len(signs))


def interior_chord(origins, dirs, a, b):
    """Length of the chord of each ray (t >= 0, unit direction) inside {A x <= b}."""
    lo, hi = chord_interval(origins, dirs, a, b)
    return hi - lo


def chord_interval(origins, dirs, a, b):
    """(entry, exit) distances of each ray (t >= 0) through {A x <= b}; exit < entry: none."""
    d = dirs / np.linalg.norm(dirs, axis=-1, keepdims=True)
    ad = d @ a.T
    slack = b - origins @ a.T
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = slack / ad
    lo = np.max(np.where(ad < 0, ratio, 0.0), axis=-1)
    lo = np.maximum(lo, 0.0)
    hi = np.min(np.where(ad > 0, ratio, np.inf), axis=-1)
    parallel_out = np.any((ad == 0) & (slack <= 0), axis=-1)
    return lo, np.where(parallel_out, -np.inf, hi)


def sphere_lattice(n, sub):
    """Lattice points on the surface of [-1, 1]^N (k = 2^sub cells per edge), their small cubes
    (lists of 2^(N-1) corners) and the radius of a ball inside the projected mesh."""
    k = 2 ** sub
    grid = -1 + 2 * np.arange(k + 1) / k
    cubes = []
    for a in range(n):
        for sign in (-1.0, 1.0):
            free = [j for j in range(n) if j != a]
            for low in itertools.product(range(k), repeat=n - 1):
                corners = []
                for bits in itertools.product([0, 1], repeat=n - 1):
                    p = np.empty(n)
                    p[a] = sign
                    p[free] = grid[np.array(low) + np.array(bits)]
                    corners.append(p)
                cubes.append(corners)
    cubes = np.array(cubes)  # (cubes, 2^(N-1), N)
    proj = cubes / np.linalg.norm(cubes, axis=-1, keepdims=True)
    diam2 = ((proj[:, :, None] - proj[:, None]) ** 2).sum(-1).max(axis=(1, 2))
    # A point of a simplex with vertices on the unit sphere: |x|^2 >= 1 - D^2 (N-1) / (2N).
    rho = math.sqrt(1 - diam2.max() * (n - 1) / (2 * n))
    return cubes, rho


def watertight_targets(shape, n, rng, count):
    """Vertices, edge midpoints and face centroids of the mesh."""
    if shape == "hypercube":
        pts = np.array([p for p in itertools.product([-1.0, 0.0, 1.0], repeat=n) if np.max(np.abs(p)) == 1])
    elif shape == "cross_polytope":
        pts = []
        for size in range(1, n + 1):
            for axes in itertools.combinations(range(n), size):
                for signs in itertools.product([-1.0, 1.0], repeat=size):
                    p = np.zeros(n)
                    p[list(axes)] = np.array(signs) / size
                    pts.append(p)
        pts = np.array(pts)
    else:
        cubes, _ = sphere_lattice(n, SPHERE_SUB)
        proj = cubes / np.linalg.norm(cubes, axis=-1, keepdims=True)
        # vertices, axis edges (corner 0 to corner 2^j) and the main diagonal (corner 0 to last)
        pts = [proj[:, 0]]
        pts += [(proj[:, 0] + proj[:, 2 ** j]) / 2 for j in range(n - 1)]
        pts.append((proj[:, 0] + proj[:, -1]) / 2)
        pts = np.concatenate(pts)
    return pts[rng.choice(len(pts), size=min(count, len(pts)), replace=False)]


def shape_scene(shape, n):
    scene = ndtrace.Scene(n)
    if shape == "sphere":
        scene.add_object("sphere", subdivisions=SPHERE_SUB)
    else:
        scene.add_object(shape)
    return scene


@pytest.mark.parametrize("n", [3, 4, 5])
@pytest.mark.parametrize("shape", ["hypercube", "cross_polytope", "sphere"])
def test_watertight_rays_through_vertices_and_edges(shape, n):
    rng = rng_for(4, n)
    scene = shape_scene(shape, n)
    if shape == "sphere":
        _, rho = sphere_lattice(n, SPHERE_SUB)
        assert rho > 0.6

    def interior(origins, dirs):
        if shape != "sphere":
            return interior_chord(origins, dirs, *halfspaces(shape, n)) > 1e-7
        d = dirs / np.linalg.norm(dirs, axis=-1, keepdims=True)
        tc = -np.sum(origins * d, -1)
        closest = np.linalg.norm(origins + tc[..., None] * d, axis=-1)
        return (tc > 0) & (closest < rho - 1e-7)

    # (a) Orthographic cameras along coordinate axes whose cell centres lie exactly on the
    # lattice {-1, -3/4, ..., 1}^(N-1): through vertices, edges, ridges and Kuhn diagonals.
    res = [9] * (n - 1)
    for view_axis, sign in ((n - 1, -1.0), (0, 1.0)):
        cols = [np.eye(n)[j] for j in range(n) if j != view_axis] + [sign * np.eye(n)[view_axis]]
        orientation = np.column_stack(cols)
        position = -5.0 * cols[-1]
        scene.set_camera(position, orientation=orientation, projection="orthographic",
                         extent=1.125, resolution=res)
        r = ndtrace.trace(scene)
        origins, dirs = camera_rays(position, orientation, res, 0.25, "orthographic")
        u = retina_u(res, 0.25)
        assert set(np.unique(u)) == set(np.arange(-4, 5) * 0.25)
        inside = interior(origins, dirs)
        assert inside.sum() >= 3 ** (n - 1)
        missed = inside & ~r.hit
        assert not missed.any(), f"{missed.sum()} interior rays slipped through, e.g. u = {u[missed][:5].tolist()}"
        # Rays clearly outside the solid miss.
        outside = {"hypercube": np.abs(u).max(-1) > 1 + 1e-6, "cross_polytope": np.abs(u).sum(-1) > 1 + 1e-6,
                   "sphere": np.linalg.norm(u, axis=-1) > 1 + 1e-6}[shape]
        assert not (outside & r.hit).any()

    # (b) Perspective cameras in random directions aimed exactly at vertices, edge midpoints and
    # face centroids (the centre cell's ray is the view direction through the target).
    res = [5] * (n - 1)
    aimed_interior = 0
    targets = watertight_targets(shape, n, rng, 8)
    for target in targets:
        w = -target / np.linalg.norm(target) + rng.normal(0, 0.2, n)
        w /= np.linalg.norm(w)
        position = target - 4 * w
        scene.set_camera(position, look_at=target, up=random_up(rng, n), fov=12, resolution=res)
        r = ndtrace.trace(scene)
        orientation = np.array(scene.compiled().camera_orientation)
        origins, dirs = camera_rays(position, orientation, res, cell_size(res, fov=12))
        inside = interior(origins, dirs)
        centre = (2,) * (n - 1)
        aimed_interior += inside[centre]
        missed = inside & ~r.hit
        assert not missed.any(), f"target {target.tolist()}: {missed.sum()} interior rays missed"
    assert aimed_interior >= len(targets) // 2


# ---------------------------------------------------------------------------------------------
# 4. Back-face culling
# ---------------------------------------------------------------------------------------------


def same_retina(a, b):
    for name in ("rgba", "depth", "normal", "object_id", "primitive_id"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


@pytest.mark.parametrize("n", [3, 4, 5])
def test_backface_culling(n):
    """Culling discards exactly the simplices with det[x_1 - x_0 ... x_{N-1} - x_0 | C - x_0] < 0
    (orthographic: C - x_0 replaced by -view)."""
    rng = rng_for(5, n)
    res = {3: [24, 20], 4: [12, 11, 10], 5: [8, 7, 7, 6]}[n]
    direction = rng.normal(size=n)
    position = 4.0 * direction / np.linalg.norm(direction)
    light = dict(direction=rng.normal(size=n), color=[1.0, 0.9, 0.8])
    cam_persp = dict(look_at=rng.normal(0, 0.1, n), up=random_up(rng, n).tolist(), fov=35, resolution=res)
    q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    cam_ortho = dict(orientation=q, projection="orthographic", extent=1.3, resolution=res)

    def scene(obj, cull, cam, pos, **render):
        shape, keys = obj
        return (ndtrace.Scene(n).set_camera(pos, **cam)
                .add_object(shape, **keys).add_light("directional", **light)
                .set_render(cull_backfaces=cull, **render))

    def trace(obj, cull, cam=cam_persp, pos=position, **render):
        return ndtrace.trace(scene(obj, cull, cam, pos, **render))

    # Generated closed shapes are oriented outward: culling changes nothing.
    for obj in (("hypercube", {}), ("sphere", {"subdivisions": 1}), ("cross_polytope", {}), ("simplex", {})):
        a, b = trace(obj, False), trace(obj, True)
        assert a.hit.sum() > (0 if obj[0] == "simplex" else 10)
        same_retina(a, b)

    for name, (vertices, simplices) in (("hypercube", kuhn_hypercube(n)), ("cross_polytope", cross_polytope_mesh(n))):
        mesh = lambda s, vertices=vertices, **k: ("mesh", dict(vertices=vertices, simplices=s, **k))  # noqa: E731
        outward, inward = mesh(simplices), mesh(flipped(simplices))
        # A reflection (negative determinant) keeps the orientation: the builder reorders.
        reflected = mesh(simplices, transform=[{"scale": [-1.0] + [1.0] * (n - 1)}])
        for cam, pos, projection in ((cam_persp, position, "perspective"),
                                     (cam_ortho, -4.0 * q[:, -1], "orthographic")):
            orientation = np.array(scene(outward, False, cam, pos).compiled().camera_orientation)
            p = vertices[simplices]
            eye = pos - p[:, 0] if projection == "perspective" else np.broadcast_to(-orientation[:, -1], (len(p), n))
            facing = np.linalg.det(np.concatenate([p[:, 1:] - p[:, :1], eye[:, None]], axis=1)) > 0
            assert facing.any() and (~facing).any()

            base = trace(outward, False, cam, pos)
            assert base.hit.sum() > 10
            same_retina(base, trace(outward, True, cam, pos))
            # Culling off: two-sided lighting does not care about orientation.
            same_retina(base, trace(inward, False, cam, pos))
            rb = trace(reflected, False, cam, pos)
            same_retina(rb, trace(reflected, True, cam, pos))
            # The simplices facing the eye alone: unchanged by culling; flipped, they vanish.
            front = trace(mesh(simplices[facing]), True, cam, pos)
            np.testing.assert_array_equal(front.depth, base.depth)
            assert not trace(mesh(flipped(simplices[facing])), True, cam, pos).hit.any()
            # Those facing away vanish; flipped, they are the far side of the solid.
            assert not trace(mesh(simplices[~facing]), True, cam, pos).hit.any()
            # The whole flipped (inward) mesh with culling shows its far side: every ray through
            # the solid hits where it leaves it.
            far = trace(inward, True, cam, pos)
            origins, dirs = camera_rays(pos, orientation, res, cell_size(res, **({"fov": 35} if projection ==
                                                                                  "perspective" else {"extent": 1.3})),
                                        projection)
            dirs = dirs / np.linalg.norm(dirs, axis=-1, keepdims=True)
            lo, hi = chord_interval(origins, dirs, *halfspaces(name, n))
            through = hi - lo > 1e-6
            assert through.sum() > 10
            assert far.hit[through].all()
            np.testing.assert_allclose(far.depth[through], hi[through], rtol=1e-6)
            np.testing.assert_allclose(base.depth[through], lo[through], rtol=1e-6)
            assert not far.hit[hi - lo < -1e-6].any()
        # One-sided lighting of the inward mesh: every visible face has its normal away from the
        # viewer, so where it faces the light the shadow ray hits the solid: ambient only.
        one_sided = trace(inward, False, two_sided=False)
        hit = one_sided.hit
        assert hit.sum() > 10
        np.testing.assert_allclose(one_sided.rgba[hit][:, :3], 0.2 * 0.7, rtol=1e-6)
        # The outward mesh's visible normals already face the viewer.
        same_retina(trace(outward, False, two_sided=False), trace(outward, False))


# ---------------------------------------------------------------------------------------------
# 5, 6. Determinism and samples
# ---------------------------------------------------------------------------------------------


def busy_scene(n=4, res=20, samples=1, seed=0):
    return (ndtrace.Scene(n, ambient=[0.1, 0.1, 0.1])
            .set_camera([0.7, 1.1, 1.9, 4.0][:n - 1] + [4.0], look_at=[0] * n,
                        up=np.eye(n)[1:n - 1].tolist(), fov=50, resolution=res)
            .add_object("sphere", subdivisions=1, material={"color": [0.9, 0.4, 0.2], "specular": 0.4},
                        transform=[{"translate": [0.6] + [0.0] * (n - 1)}])
            .add_object("hypercube", transform=[{"scale": 0.6}, {"rotate": {"plane": [0, n - 1], "degrees": 25}},
                                                {"translate": [-0.8] + [0.1] * (n - 1)}])
            .add_light("directional", direction=list(range(1, n + 1)))
            .add_light("point", position=[2.0] * n, color=[3, 3, 3], falloff=n - 1)
            .set_render(samples=samples, seed=seed))


def test_thread_count_does_not_change_the_result():
    for samples, seed in ((1, 0), (4, 12345)):
        scene = busy_scene(samples=samples, seed=seed)
        a = ndtrace.trace(scene, threads=1)
        b = ndtrace.trace(scene, threads=2)
        c = ndtrace.trace(scene)
        assert a.hit.sum() > 100
        same_retina(a, b)
        same_retina(a, c)
    # Different seeds with samples > 1: slightly different jitter, mostly the same image.
    a = ndtrace.trace(busy_scene(samples=4, seed=1), threads=2)
    b = ndtrace.trace(busy_scene(samples=4, seed=2), threads=2)
    assert not np.array_equal(a.rgba, b.rgba)
    assert np.abs(a.rgba - b.rgba).mean() < 0.02
    assert (a.rgba[..., 3] == b.rgba[..., 3]).mean() > 0.8


def test_freed_retinas_lend_their_buffers_to_the_next_trace_which_overwrites_them():
    """Once numpy frees a retina's arrays, the next trace reuses their memory (no fresh pages
    to fault in, nothing cleared) and overwrites all of it: a retina with many hits, freed,
    then one of the same shape that sees nothing must hold no trace of the first (misses
    included: their normals are written as zeros)."""
    import gc

    n = 4
    full = busy_scene(n=n, res=20)
    empty = (ndtrace.Scene(n)
             .set_camera([0.7, 1.1, 1.9, 4.0], look_at=[0] * n, up=np.eye(n)[1:n - 1].tolist(),
                         fov=50, resolution=20)
             .add_object("sphere", subdivisions=1, transform=[{"translate": [0, 0, 0, 50.0]}]))
    gc.collect()  # retinas of earlier tests, freed now rather than during this one
    ndtrace.release_buffers()
    a = ndtrace.trace(full, threads=1)
    assert a.hit.sum() > 100 and np.abs(a.normal).sum() > 100
    assert ndtrace.release_buffers() == 0  # nothing kept while the arrays live
    del a
    gc.collect()
    b = ndtrace.trace(empty, threads=1)
    # b took every buffer that freeing a's arrays handed back.
    assert ndtrace.release_buffers() == 0
    assert b.hit.sum() == 0
    assert (b.rgba == 0).all() and (b.normal == 0).all() and np.isinf(b.depth).all()
    assert (b.object_id == -1).all() and (b.primitive_id == -1).all()
    kept = b.rgba.nbytes + b.depth.nbytes + b.normal.nbytes + b.object_id.nbytes + b.primitive_id.nbytes
    del b
    gc.collect()
    assert ndtrace.release_buffers() == kept
    assert ndtrace.release_buffers() == 0


def test_threads_argument_is_checked():
    scene = busy_scene(res=4)
    for bad in (0, -1, 1.5, "2"):
        with pytest.raises(ValueError, match="threads"):
            ndtrace.trace(scene, threads=bad)
    with pytest.raises(TypeError):
        ndtrace.trace(scene.to_dict())


@pytest.mark.parametrize("n", [3, 4])
def test_samples_give_fractional_alpha_on_edges_and_premultiplied_colour(n):
    """A face-on cube [-1.1, 1.1]^N on cells of side 1/4: the silhouette crosses the edge cells
    [1, 1.25] at 0.4 of their width, so with 16 Latin-hypercube samples (one per stratum along
    every axis) exactly 6 or 7 samples of an edge cell are covered."""
    res = [16] * (n - 1)
    color = np.array([0.9, 0.6, 0.3])
    scene = (ndtrace.Scene(n, ambient=[0.1, 0.1, 0.1])
             .set_camera(np.r_[np.zeros(n - 1), 5.0], orientation=axis_orientation(n), projection="orthographic",
                         extent=2.0, resolution=res)
             .add_object("hypercube", transform=[{"scale": 1.1}], material={"color": color})
             .add_light("directional", direction=np.r_[0.3, np.zeros(n - 2), 1.0])
             .set_render(samples=16, seed=3))
    r = ndtrace.trace(scene)
    alpha = r.rgba[..., 3]
    u = np.abs(retina_u(res, 0.25))
    inner = (u < 1).all(-1)
    edge_axes = (np.abs(u - 1.125) < 1e-12).sum(-1)
    edge = (edge_axes == 1) & ((u < 1) | (np.abs(u - 1.125) < 1e-12)).all(-1)
    corner = (edge_axes >= 2) & ((u < 1) | (np.abs(u - 1.125) < 1e-12)).all(-1)
    outside = ~(inner | edge | corner)
    assert np.all(alpha[inner] == 1)
    assert set(np.unique(alpha[edge] * 16).tolist()) <= {6.0, 7.0}
    assert np.all((alpha[corner] >= 0) & (alpha[corner] < 0.5))
    assert np.all(alpha[outside] == 0) and np.all(r.rgba[outside] == 0)
    # Premultiplied: every covered sample sees the same flat face colour c, so rgb = alpha * c.
    c = r.rgba[inner][0, :3]
    np.testing.assert_allclose(r.rgba[inner][:, :3], np.broadcast_to(c, (inner.sum(), 3)), rtol=1e-6)
    lit = 0.1 * color + color * (1 / math.hypot(0.3, 1.0))
    np.testing.assert_allclose(c, lit, rtol=1e-6)
    covered = alpha > 0
    np.testing.assert_allclose(r.rgba[covered][:, :3], alpha[covered][:, None] * c, rtol=1e-5, atol=1e-7)
    assert np.all(r.rgba[..., :3] <= alpha[..., None] * r.rgba[..., :3].max() + 1e-6)
    # The nearest sample's depth and ids are recorded for every partly covered cell.
    assert np.all(r.hit == covered)
    np.testing.assert_allclose(r.depth[covered], 5 - 1.1, rtol=1e-6)


# ---------------------------------------------------------------------------------------------
# 7. TOML, dict and builder describe the same scene
# ---------------------------------------------------------------------------------------------

EQUIV_TOML = """\
dim = 4
background = [0.02, 0.02, 0.03]
ambient = [0.15, 0.15, 0.18]

[camera]
position = [1.2, 1.6, 2.0, 4.5]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 50
resolution = [12, 10, 8]

[[lights]]
type = "directional"
direction = [0.4, 0.8, 0.6, 1.0]
color = [1.0, 0.95, 0.9]

[[lights]]
type = "point"
position = [2, 2, 2, 2]
falloff = 3

[[objects]]
shape = "hypercube"
material = { color = [0.9, 0.55, 0.2], specular = 0.3, shininess = 40 }
transform = [{ rotate = { plane = [0, 3], degrees = 20 } }, { scale = 0.5 }]

[[objects]]
shape = "mesh"
vertices = [[0, 0, 0, 1], [1, 0, 0, 1], [0, 1, 0, 1], [0, 0, 1, 1], [1, 1, 1, 0.5]]
simplices = [[0, 1, 2, 3], [1, 2, 3, 4]]
material = { color = [0.2, 0.4, 0.9], diffuse = [0.5, 0.6, 0.7], smooth = true }
transform = [{ translate = [-1, 0, 0, 0] }, { matrix = [[1, 0, 0, 0, 0.1], [0, 1, 0, 0, 0], [0, 0, 1, 0, 0], [0, 0, 0, 1, 0], [0, 0, 0, 0, 1]] }]

[[objects]]
shape = "sphere"
subdivisions = 1
transform = [{ scale = [0.3, 0.3, 0.3, 0.6] }, { translate = [1, 0, 0, 0] }]

[render]
samples = 2
seed = 9
two_sided = false
"""


def shear_x():
    m = np.eye(5)
    m[0, 4] = 0.1
    return m


def equiv_dict():
    return {
        "dim": 4, "background": np.array([0.02, 0.02, 0.03]), "ambient": [0.15, 0.15, 0.18],
        "camera": {"position": np.array([1.2, 1.6, 2.0, 4.5]), "look_at": np.zeros(4),
                   "up": np.eye(4)[1:3], "fov": 50, "resolution": np.array([12, 10, 8])},
        "lights": [{"type": "directional", "direction": [0.4, 0.8, 0.6, 1.0], "color": [1.0, 0.95, 0.9]},
                   {"type": "point", "position": np.full(4, 2.0), "falloff": np.float64(3)}],
        "objects": [
            {"shape": "hypercube", "material": {"color": [0.9, 0.55, 0.2], "specular": 0.3, "shininess": 40},
             "transform": [{"rotate": {"plane": [0, 3], "degrees": 20}}, {"scale": 0.5}]},
            {"shape": "mesh",
             "vertices": np.array([[0, 0, 0, 1], [1, 0, 0, 1], [0, 1, 0, 1], [0, 0, 1, 1], [1, 1, 1, 0.5]]),
             "simplices": np.array([[0, 1, 2, 3], [1, 2, 3, 4]], dtype=np.int32),
             "material": {"color": np.array([0.2, 0.4, 0.9]), "diffuse": [0.5, 0.6, 0.7], "smooth": True},
             "transform": [{"translate": [-1, 0, 0, 0]},
                           {"matrix": shear_x()}]},
            {"shape": "sphere", "subdivisions": np.int64(1),
             "transform": [{"scale": [0.3, 0.3, 0.3, 0.6]}, {"translate": [1, 0, 0, 0]}]},
        ],
        "render": {"samples": 2, "seed": 9, "two_sided": False},
    }


def equiv_builder():
    affine = shear_x().tolist()
    return (ndtrace.Scene(4, background=[0.02, 0.02, 0.03], ambient=np.array([0.15, 0.15, 0.18]))
            .set_camera([1.2, 1.6, 2.0, 4.5], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]],
                        fov=50, resolution=[12, 10, 8])
            .add_light("directional", direction=[0.4, 0.8, 0.6, 1.0], color=[1.0, 0.95, 0.9])
            .add_light("point", position=[2, 2, 2, 2], falloff=3)
            .add_object("hypercube", material={"color": [0.9, 0.55, 0.2], "specular": 0.3, "shininess": 40},
                        transform=[{"rotate": {"plane": [0, 3], "degrees": 20}}, {"scale": 0.5}])
            .add_object("mesh", vertices=[[0, 0, 0, 1], [1, 0, 0, 1], [0, 1, 0, 1], [0, 0, 1, 1], [1, 1, 1, 0.5]],
                        simplices=[[0, 1, 2, 3], [1, 2, 3, 4]],
                        material={"color": [0.2, 0.4, 0.9], "diffuse": [0.5, 0.6, 0.7], "smooth": True},
                        transform=[{"translate": [-1, 0, 0, 0]}, {"matrix": affine}])
            .add_object("sphere", subdivisions=1, transform=[{"scale": [0.3, 0.3, 0.3, 0.6]},
                                                               {"translate": [1, 0, 0, 0]}])
            .set_render(samples=2, seed=9, two_sided=False))


def test_toml_dict_and_builder_are_the_same_scene(tmp_path):
    path = tmp_path / "scene.toml"
    path.write_text(EQUIV_TOML)
    d = equiv_dict()
    assert d["objects"][1]["transform"][1]["matrix"][0, 4] == 0.1
    scenes = [ndtrace.load_file(path), ndtrace.load_toml(EQUIV_TOML), ndtrace.load_dict(d), equiv_builder()]
    for other in scenes[1:]:
        assert scenes[0] == other
    retinas = [ndtrace.trace(s) for s in scenes]
    assert retinas[0].shape == (8, 10, 12) and retinas[0].hit.sum() > 50
    assert set(np.unique(retinas[0].object_id)) == {-1, 0, 1, 2}
    for r in retinas[1:]:
        same_retina(retinas[0], r)
    # Round trips through to_toml and to_dict.
    for s in scenes:
        text = s.to_toml()
        again = ndtrace.load_toml(text)
        assert again == s
        assert ndtrace.load_toml(again.to_toml()).to_toml() == text
        assert ndtrace.load_dict(s.to_dict()) == s
    same_retina(retinas[0], ndtrace.trace(ndtrace.load_toml(scenes[3].to_toml())))
    # A change anywhere makes them differ.
    changed = equiv_builder().set_render(seed=10)
    assert changed != scenes[0]
    d2 = equiv_dict()
    d2["objects"][1]["vertices"][4, 3] = 0.25
    assert ndtrace.load_dict(d2) != scenes[0]


def test_to_toml_round_trips_awkward_values():
    rng = rng_for(6, 5)
    verts = rng.normal(size=(7, 5)) * np.array([1e-3, 1e3, 1 / 3, 2.5e-2, 1.0])
    verts[0, 0] = -0.0
    q, _ = np.linalg.qr(rng.normal(size=(5, 5)))
    scene = (ndtrace.Scene(5, background=[0, 0, 0.1])
             .set_camera(rng.normal(size=5), orientation=q, projection="orthographic", extent=0.1 + 1e-17,
                         resolution=[3, 2, 2, 1])
             .add_object("mesh", vertices=verts, simplices=[[0, 1, 2, 3, 4], [2, 3, 4, 5, 6]],
                         material={"ambient": [0.1, 0.2, 0.3], "specular": 0.0, "shininess": 0})
             .add_object("cross_polytope", transform=[{"rotate": {"plane": [4, 0], "degrees": -1e-7}}])
             .set_render(seed=2 ** 64 - 1, samples=4096, mode="barycentric", cull_backfaces=True))
    text = scene.to_toml()
    again = ndtrace.load_toml(text)
    assert again == scene
    assert again.to_dict(lists=True) == scene.to_dict(lists=True)
    assert isinstance(scene.to_dict()["objects"][0]["vertices"], np.ndarray)
    assert isinstance(again.to_dict()["objects"][0]["vertices"], list)


# ---------------------------------------------------------------------------------------------
# 8. Bad input
# ---------------------------------------------------------------------------------------------

GOOD_TOML = """\
dim = 3
# a comment
[camera]
position = [0, 0, 5]
look_at = [0, 0, 0]
up = [0, 1, 0]
fov = 40
resolution = 8

[[objects]]
shape = "sphere"

[[objects]]
shape = "hypercube"
material = { color = [0.9, 0.5, 0.1] }
"""


def located(text: str, needle: str, occurrence: int = 0):
    """1-based (line, column) of the ``occurrence``-th ``needle`` in ``text``."""
    pos = -1
    for _ in range(occurrence + 1):
        pos = text.index(needle, pos + 1)
    line = text.count("\n", 0, pos) + 1
    col = pos - (text.rfind("\n", 0, pos) + 1) + 1
    return line, col


def test_wrong_colour_length_names_file_line_column_and_path(tmp_path):
    text = GOOD_TOML.replace("[0.9, 0.5, 0.1]", "[0.9, 0.5]")
    path = tmp_path / "scene.toml"
    path.write_text(text)
    line, col = located(text, "[0.9, 0.5]")
    assert (line, col) == (15, 22)
    with pytest.raises(ValueError) as e:
        ndtrace.load_file(path)
    assert str(e.value) == f"{path}:{line}:{col}: objects[1].material.color: expected 3 numbers, got 2"
    with pytest.raises(ValueError) as e:
        ndtrace.load_toml(text, name="scene.toml")
    assert str(e.value) == "scene.toml:15:22: objects[1].material.color: expected 3 numbers, got 2"


def toml_error(text, name="scene.toml"):
    with pytest.raises(ValueError) as e:
        ndtrace.load_toml(text, name=name)
    return str(e.value)


def dict_error(data):
    with pytest.raises(ValueError) as e:
        ndtrace.load_dict(data)
    return str(e.value)


def base_dict(n=3, **extra):
    d = {"dim": n, "camera": {"position": [0] * (n - 1) + [5], "look_at": [0] * n,
                              "up": np.eye(n)[1:n - 1].tolist(), "fov": 40, "resolution": 8},
         "objects": [{"shape": "hypercube"}]}
    d.update(extra)
    return d


def test_unknown_keys_and_shapes_get_suggestions():
    text = GOOD_TOML.replace("material = { color", "material = { colr")
    line, key_col = located(text, "colr")
    _, value_col = located(text, "[0.9")
    msg = toml_error(text)
    # The location is the unknown key or (as implemented) its value, on the same line.
    assert msg in [f'scene.toml:{line}:{col}: objects[1].material.colr: unknown key "colr" (did you mean "color"?)'
                   for col in (key_col, value_col)], msg
    text = GOOD_TOML.replace('"hypercube"', '"hypercub"')
    line, col = located(text, '"hypercub"')
    assert toml_error(text) == (f'scene.toml:{line}:{col}: objects[1].shape: '
                                f'unknown shape "hypercub" (did you mean "hypercube"?)')
    assert dict_error(base_dict(objects=[{"shape": "sphere"}, {"shape": "hypercub"}])) == \
        '<dict>: objects[1].shape: unknown shape "hypercub" (did you mean "hypercube"?)'
    msg = toml_error(GOOD_TOML.replace("fov = 40", "fvo = 40"))
    assert msg.startswith(f"scene.toml:{located(GOOD_TOML, 'fov')[0]}:") and "camera.fvo" in msg
    assert 'unknown key "fvo"' in msg
    msg = dict_error(base_dict(render={"sampels": 4}))
    assert msg == '<dict>: render.sampels: unknown key "sampels" (did you mean "samples"?)'
    with pytest.raises(ValueError, match=r'^<scene>: objects\[0\]\.material\.shinyness: unknown key'):
        ndtrace.Scene(3).set_camera([0, 0, 5], look_at=[0, 0, 0], up=[0, 1, 0], fov=40, resolution=4) \
            .add_object("sphere", material={"shinyness": 3}).compiled()


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_vertex_coordinates(bad):
    v = np.eye(3)
    v[2, 1] = bad
    msg = dict_error(base_dict(objects=[{"shape": "hypercube"}, {"shape": "mesh", "vertices": v,
                                                                 "simplices": [[0, 1, 2]]}]))
    assert msg.startswith("<dict>: objects[1].vertices[2][1]: non-finite")
    literal = {"nan": "nan"}.get(str(bad), "inf" if bad > 0 else "-inf")
    text = GOOD_TOML + f'\n[[objects]]\nshape = "mesh"\nvertices = [[1, 0, 0], [0, 1, 0], [0, {literal}, 1]]\n' \
                       'simplices = [[0, 1, 2]]\n'
    line, col = located(text, literal)
    assert toml_error(text).startswith(f"scene.toml:{line}:{col}: objects[2].vertices[2][1]: non-finite")


def test_mesh_index_errors():
    v = np.eye(3)
    assert dict_error(base_dict(objects=[{"shape": "mesh", "vertices": v, "simplices": [[0, 1, 2], [0, 1, 3]]}])) \
        == "<dict>: objects[0].simplices[1][2]: vertex index 3 out of range: the mesh has 3 vertices"
    assert dict_error(base_dict(objects=[{"shape": "mesh", "vertices": v, "simplices": [[0, -1, 2]]}])).startswith(
        "<dict>: objects[0].simplices[0][1]: vertex index -1 out of range")
    msg = dict_error(base_dict(objects=[{"shape": "mesh", "vertices": v, "simplices": [[0, 1, 2], [0, 1]]}]))
    assert msg.startswith("<dict>: objects[0].simplices[1]: ") and "got 2" in msg
    msg = dict_error(base_dict(objects=[{"shape": "mesh", "vertices": v, "simplices": [[0, 1, 2, 0]]}]))
    assert msg.startswith("<dict>: objects[0].simplices[0]: ") and "got 4" in msg
    text = GOOD_TOML + '\n[[objects]]\nshape = "mesh"\nvertices = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\n' \
                       'simplices = [[0, 1, 2], [2, 1, 7]]\n'
    line, col = located(text, "7]]")
    assert toml_error(text) == (f"scene.toml:{line}:{col}: objects[2].simplices[1][2]: "
                                "vertex index 7 out of range: the mesh has 3 vertices")


def test_singular_transforms_are_errors_naming_the_transform():
    # Large transformed objects are traced in their own space (the ray mapped by the inverse
    # transform), so the transform of an object with simplices must be invertible; a singular
    # one used to flatten the object to nothing. A surface may still be flattened.
    flat = [[1, 0, 0], [0, 1, 0], [0, 0, 0]]
    objects = [{"shape": "sphere"}, {"shape": "hypercube", "transform": [{"scale": 0.5}, {"matrix": flat}]}]
    assert dict_error(base_dict(objects=objects)) == (
        "<dict>: objects[1].transform: is singular or cannot be inverted in floating point (determinant 0): "
        "an object with simplices needs an invertible transform")
    text = GOOD_TOML + '\n[[objects]]\nshape = "hypercube"\ntransform = [{ matrix = [[1, 2, 0], [2, 4, 0], [0, 0, 1]] }]\n'
    line, col = located(text, "[{ matrix")
    assert toml_error(text).startswith(f"scene.toml:{line}:{col}: objects[2].transform: is singular or cannot")
    # A mirror is invertible: the object is drawn, as its mirrored mesh.
    mirror = base_dict(objects=[{"shape": "hypercube", "transform": [{"scale": [-0.5, 0.5, 0.5]}]}])
    world = base_dict(objects=[{"shape": "hypercube", "transform": [{"scale": 0.5}]}])
    a, b = (ndtrace.trace(ndtrace.load_dict(d)) for d in (mirror, world))
    assert (a.object_id >= 0).sum() > 0
    np.testing.assert_array_equal(a.object_id, b.object_id)  # the cube is its own mirror image
    np.testing.assert_allclose(a.rgba, b.rgba, atol=1e-5)


def test_camera_errors():
    o = np.eye(3)
    o[2, 1] = 0.1
    msg = dict_error(base_dict(camera={"position": [0, 0, 5], "orientation": o, "fov": 40, "resolution": 8}))
    assert msg.startswith("<dict>: camera.orientation: must be orthonormal")
    assert dict_error(base_dict(camera={"position": [0, 0, 5], "look_at": [0, 0, 5], "up": [0, 1, 0], "fov": 40,
                                        "resolution": 8})).startswith("<dict>: camera.look_at: ")
    for res, axis in ((0, 1), ([4, 0], 2)):
        msg = dict_error(base_dict(camera={**base_dict()["camera"], "resolution": res}))
        assert msg == f"<dict>: camera.resolution: axis {axis} has zero cells"
    for res in (10 ** 6, [2 ** 31, 2 ** 31], [2 ** 63, 3]):
        msg = dict_error(base_dict(camera={**base_dict()["camera"], "resolution": res}))
        assert msg.startswith("<dict>: camera.resolution: ")
        assert re.search(r"\d+(\.\d+)? (GiB|TiB|PiB|EiB)", msg), msg
    text = GOOD_TOML.replace("resolution = 8", "resolution = 100000")
    line, col = located(text, "100000")
    msg = toml_error(text)
    assert msg.startswith(f"scene.toml:{line}:{col}: camera.resolution: a retina of 10000000000 cells needs about ")
    assert re.search(r"about 4\d\d\.\d GiB", msg), msg  # 1e10 cells of 44 bytes


def test_retina_size_estimate_is_not_saturated():
    """The refusal message of a huge retina reports its real cell count."""
    msg = dict_error(base_dict(camera={**base_dict()["camera"], "resolution": [2 ** 40, 2 ** 40]}))
    assert str(2 ** 80) + " cells" in msg, msg


def test_sphere_subdivision_limit_reports_the_real_count():
    msg = dict_error(base_dict(n=4, objects=[{"shape": "sphere", "subdivisions": 40}]))
    assert msg.startswith("<dict>: objects[0].subdivisions: 40 subdivisions would make ")
    assert str(2 * 4 * 6 * 2 ** 120) in msg, msg


@pytest.mark.parametrize("dim", [0, 1, 9, 100])
def test_unsupported_dimensions(dim):
    d = base_dict()
    d["dim"] = dim
    assert dict_error(d) == f"<dict>: dim: dimension {dim} is not supported: dim must be in 2..=8"
    text = GOOD_TOML.replace("dim = 3", f"dim = {dim}")
    assert toml_error(text).startswith("scene.toml:1:7: dim: dimension")


def test_toml_syntax_error_is_located():
    text = GOOD_TOML.replace("fov = 40", "fov = = 40")
    line, _ = located(text, "fov")
    msg = toml_error(text)
    assert re.match(rf"scene\.toml:{line}:\d+: ", msg), msg
    text = GOOD_TOML.replace("[camera]", "[camera")
    assert toml_error(text).startswith(f"scene.toml:{located(text, '[camera')[0]}:")
    with pytest.raises(ValueError, match=r"^scene\.toml:"):
        ndtrace.load_toml('dim = 3\ncamera = { position = [0, 0, 5], ', name="scene.toml")


def test_degenerate_simplices_are_skipped_with_one_warning():
    """Degenerate simplices (a repeated index, collinear vertices, a duplicate point) are skipped
    with one warning that counts them; the others keep their own indices."""
    n = 3
    verts, simplices, degenerate = [], [], []
    # A row of small triangles in the plane z = 0, with degenerate ones in between.
    for k in range(6):
        x = -1.5 + 0.6 * k
        base = len(verts)
        verts += [[x, -0.3, 0], [x + 0.4, -0.3, 0], [x, 0.3, 0], [x + 0.2, -0.3, 0], [x, -0.3, 0]]
        simplices.append([base, base + 1, base + 2])
        if k % 2 == 0:
            simplices.append([base, base + 3, base + 1])  # collinear
            degenerate.append(len(simplices) - 1)
        if k % 3 == 0:
            simplices.append([base, base + 4, base + 2])  # two equal points
            degenerate.append(len(simplices) - 1)
        if k == 5:
            simplices.append([base, base, base + 2])  # a repeated index
            degenerate.append(len(simplices) - 1)
    keep = [i for i in range(len(simplices)) if i not in degenerate]
    data = {"dim": n, "camera": {"position": [0, 0, 5], "orientation": axis_orientation(3),
                                 "projection": "orthographic", "extent": 2.0, "resolution": [64, 16]},
            "objects": [{"shape": "mesh", "vertices": np.array(verts), "simplices": np.array(simplices)}]}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = ndtrace.load_dict(data)
        r = ndtrace.trace(scene)
        ndtrace.trace(scene)
    msgs = [str(w.message) for w in caught]
    assert msgs == [f"skipped {len(degenerate)} degenerate (zero-volume) simplices"]
    assert scene.warnings == msgs
    with pytest.warns(UserWarning, match=rf"skipped {len(degenerate)} degenerate"):
        ndtrace.load_toml(scene.to_toml())
    ids = set(np.unique(r.primitive_id[r.hit]).tolist())
    assert ids == set(keep)
    # The builder warns once too, on first use.
    b = ndtrace.Scene(n).set_camera(**{k: v for k, v in data["camera"].items()})
    b.add_object("mesh", vertices=verts, simplices=simplices)
    with pytest.warns(UserWarning) as rec:
        ndtrace.trace(b)
        ndtrace.trace(b)
    assert len(rec) == 1


# ---------------------------------------------------------------------------------------------
# 9. Debug modes
# ---------------------------------------------------------------------------------------------


def modes_scene(n, mode, **render):
    rng = rng_for(9, n)
    q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    return (ndtrace.Scene(n)
            .set_camera(-4.0 * q[:, -1], orientation=q, fov=50, resolution={3: 24, 4: 12, 5: 7}.get(n, 24))
            .add_object("sphere", subdivisions=1)
            .add_object("simplex", transform=[{"scale": 0.5}, {"translate": 0.8 * q[:, 0]}])
            .set_render(mode=mode, **render))


@pytest.mark.parametrize("n", [3, 4, 5])
def test_normal_mode(n):
    r = ndtrace.trace(modes_scene(n, "normal"))
    hit = r.hit
    assert hit.sum() > 20
    np.testing.assert_array_equal(r.rgba[..., 3], hit.astype(np.float32))
    np.testing.assert_allclose(r.rgba[hit][:, :3], 0.5 + 0.5 * r.normal[hit][:, :3], atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(r.normal[hit], axis=-1), 1, atol=1e-6)
    assert np.all(r.rgba[~hit] == 0)
    # The same geometry as the shaded render.
    shaded = ndtrace.trace(modes_scene(n, "shaded"))
    for name in ("depth", "normal", "object_id", "primitive_id"):
        np.testing.assert_array_equal(getattr(r, name), getattr(shaded, name))


@pytest.mark.parametrize("n", [3, 4])
def test_depth_mode_is_grey_and_brighter_when_nearer(n):
    r = ndtrace.trace(modes_scene(n, "depth"))
    hit = r.hit
    rgb = r.rgba[hit][:, :3]
    np.testing.assert_array_equal(rgb[:, 0], rgb[:, 1])
    np.testing.assert_array_equal(rgb[:, 0], rgb[:, 2])
    grey, depth = rgb[:, 0], r.depth[hit]
    assert grey.min() >= 0.2 - 1e-6 and grey.max() <= 1 + 1e-6
    order = np.argsort(depth, kind="stable")
    assert np.all(np.diff(grey[order]) <= 1e-6), "grey must not increase with depth"
    assert grey.max() - grey.min() > 0.1


@pytest.mark.parametrize("n", [3, 4])
def test_primitive_id_mode(n):
    r = ndtrace.trace(modes_scene(n, "primitive_id"))
    hit = r.hit
    rgb = r.rgba[hit][:, :3]
    key = r.object_id[hit].astype(np.int64) * 10 ** 6 + r.primitive_id[hit]
    colours = {}
    for k, c in zip(key.tolist(), map(tuple, rgb.tolist())):
        assert colours.setdefault(k, c) == c, "one colour per primitive"
    assert len(colours) > 10
    assert len(set(colours.values())) == len(colours), "distinct primitives get distinct colours"
    assert rgb.min() >= 0 and rgb.max() <= 1


@pytest.mark.parametrize("n", [2, 3, 4])
def test_barycentric_mode(n):
    rng = rng_for(10, n)
    pts = facing_simplex(rng, n, 1.2, 0.4)
    res = {2: [40], 3: [24, 24], 4: [12, 12, 12]}[n]
    scene = (ndtrace.Scene(n)
             .set_camera(np.r_[np.zeros(n - 1), 4.0], orientation=axis_orientation(n), fov=40, resolution=res)
             .add_object("mesh", vertices=pts, simplices=[list(range(n))])
             .set_render(mode="barycentric"))
    r = ndtrace.trace(scene)
    origins, dirs = camera_rays(np.r_[np.zeros(n - 1), 4.0], axis_orientation(n), res, cell_size(res, fov=40))
    hit, _, depth, _, ok = brute_force(origins, dirs, pts[None])
    np.testing.assert_array_equal(r.hit[ok], hit[ok])
    h = hit & ok
    assert h.sum() > 5
    x = origins[h] + depth[h][:, None] * dirs[h] / np.linalg.norm(dirs[h], axis=-1, keepdims=True)
    lam = np.linalg.lstsq((pts[1:] - pts[0]).T, (x - pts[0]).T, rcond=None)[0].T
    bary = np.column_stack([1 - lam.sum(1), lam])
    expected = np.zeros((h.sum(), 3))
    expected[:, : min(n, 3)] = bary[:, :3]
    np.testing.assert_allclose(r.rgba[h][:, :3], expected, atol=1e-5)
    np.testing.assert_array_equal(r.rgba[h][:, 3], 1)


# ---------------------------------------------------------------------------------------------
# 10. Progress and cancellation
# ---------------------------------------------------------------------------------------------


def heavy_scene(res, samples):
    return (ndtrace.Scene(4)
            .set_camera([0.3, 0.2, 0.1, 3.0], look_at=[0, 0, 0, 0], up=[[0, 1, 0, 0], [0, 0, 1, 0]],
                        fov=60, resolution=res)
            .add_object("sphere", subdivisions=2)
            .add_light("directional", direction=[1, 1, 1, 1])
            .set_render(samples=samples))


def test_progress_is_reported_and_ends_at_total():
    # Several polling periods (50 ms) of work, even on a fast machine.
    scene = heavy_scene(48, 48)
    total = 48 ** 3
    calls = []
    r = ndtrace.trace(scene, threads=2, progress=lambda done, tot: calls.append((done, tot)))
    assert r.hit.sum() > 0
    assert len(calls) >= 2, calls
    assert all(t == total for _, t in calls)
    dones = [d for d, _ in calls]
    assert dones == sorted(dones) and all(0 <= d <= total for d in dones)
    assert calls[-1] == (total, total)
    assert dones[0] < total, "an intermediate report is expected for a trace of this size"


def test_exception_in_progress_cancels_and_propagates():
    class Stop(Exception):
        pass

    scene = heavy_scene(100, 64)  # tens of seconds of work if not cancelled
    scene.compiled()
    calls = []

    def progress(done, total):
        calls.append((done, total))
        raise Stop("enough")

    start = time.perf_counter()
    with pytest.raises(Stop, match="enough"):
        ndtrace.trace(scene, progress=progress)
    elapsed = time.perf_counter() - start
    assert len(calls) == 1 and calls[0][1] == 100 ** 3 and calls[0][0] < calls[0][1]
    assert elapsed < 2.0, f"cancellation took {elapsed:.2f} s"
    # The tracer is still usable afterwards.
    small = heavy_scene(6, 1)
    assert ndtrace.trace(small, threads=2).hit.sum() > 0


# ---------------------------------------------------------------------------------------------
# 11. The smallest and largest dimensions
# ---------------------------------------------------------------------------------------------


def plane_rotation(n, i, j, degrees):
    """The course's R_ij: R e_i = cos e_i + sin e_j."""
    m = np.eye(n)
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    m[i, i] = m[j, j] = c
    m[i, j], m[j, i] = -s, s
    return m


@pytest.mark.parametrize("n,res", [(2, [41]), (3, [9, 7]), (6, [5, 4, 3, 3, 3]), (7, [3] * 6), (8, [5, 3, 3, 1, 1, 1, 1])])
def test_hypercube_in_every_dimension(n, res):
    """A rotated, translated hypercube seen in perspective: hits and depths by slab clipping."""
    shift = np.r_[0.15, np.zeros(n - 1)]
    rot = plane_rotation(n, 0, n - 1, 20)
    position = np.r_[np.zeros(n - 1), 5.0]
    fov = 60 if n == 2 else 30
    scene = (ndtrace.Scene(n)
             .set_camera(position, orientation=axis_orientation(n), fov=fov, resolution=res)
             .add_object("hypercube", transform=[{"rotate": {"plane": [0, n - 1], "degrees": 20}},
                                                 {"translate": shift}])
             .add_light("directional", direction=np.ones(n)))
    r = ndtrace.trace(scene)
    assert r.shape == tuple(res[::-1]) and r.dim == n
    origins, dirs = camera_rays(position, axis_orientation(n), res, cell_size(res, fov=fov))
    # In the cube's own frame y = R^T (x - shift) the solid is |y_i| <= 1.
    o = (origins - shift) @ rot
    d = dirs @ rot
    with np.errstate(divide="ignore"):
        t1, t2 = (-1 - o) / d, (1 - o) / d
    t_in = np.max(np.minimum(t1, t2), -1)
    t_out = np.min(np.maximum(t1, t2), -1)
    chord = t_out - t_in
    inside = chord > 1e-6
    clear = np.abs(chord) > 1e-6
    np.testing.assert_array_equal(r.hit[clear], inside[clear])
    np.testing.assert_allclose(r.depth[inside], (t_in * np.linalg.norm(dirs, axis=-1))[inside], rtol=1e-6)
    centre = tuple(k // 2 for k in res[::-1])
    assert r.hit[centre]
    if n == 2:
        assert r.hit.sum() > 5 and (~r.hit).sum() > 5
        assert r.normal.shape == (41, 2)
