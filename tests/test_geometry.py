"""Tests of ``ndtrace.geometry`` against the formulas of "Geometry for N-Dimensional Graphics"
(Hanson's SIGGRAPH '98 course notes, eqs. 1-11) and against independent numpy/scipy references.

Every random test draws from ``numpy.random.default_rng`` with a fixed seed (per test and per
dimension) and runs in every supported dimension N = 2..8 where that makes sense. References are
computed here, independently of the library: ``np.linalg.det``/``qr``/``lstsq``, an explicit
cofactor expansion of eq. 6, exact integer determinants (Bareiss, cross-checked by Leibniz),
``scipy.spatial.ConvexHull`` facet equations and ``scipy.spatial.Delaunay`` point location.
"""

from __future__ import annotations

import itertools
import math
import re
import subprocess
import sys

import numpy as np
import pytest
from scipy.spatial import ConvexHull, Delaunay
from scipy.stats import special_ortho_group

import ndtrace
from ndtrace import geometry as g

DIMS = list(range(2, 9))
"""Every supported dimension N (the documented range 2..8)."""

BATCH = 48
"""Random items per dimension in the vectorized identity tests."""


# ---------------------------------------------------------------------------------------------
# Independent references and helpers
# ---------------------------------------------------------------------------------------------


def rng_for(seed: int, n: int) -> np.random.Generator:
    """A fixed-seed generator per test (``seed``) and dimension (``n``)."""
    return np.random.default_rng(1000 * seed + n)


def edges_of(points: np.ndarray) -> np.ndarray:
    """Edges x_k - x_0 of simplices (..., K+1, N) as rows, (..., K, N)."""
    return points[..., 1:, :] - points[..., :1, :]


def as_columns(rows: np.ndarray) -> np.ndarray:
    """Rows (..., K, N) as matrix columns (..., N, K)."""
    return np.swapaxes(rows, -1, -2)


def simplex_from_edges(x0: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Points (..., K+1, N) of the simplex with vertex x0 and edge rows ``edges``."""
    return np.concatenate([x0[..., None, :], x0[..., None, :] + edges], axis=-2)


def append_point(points: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(x_0, ..., x_{N-1}, x): ``x`` appended as the last vertex."""
    x = np.broadcast_to(x, points.shape[:-2] + points.shape[-1:])
    return np.concatenate([points, x[..., None, :]], axis=-2)


def cross_reference(edge_rows: np.ndarray) -> np.ndarray:
    """Eq. 6 by explicit cofactor expansion along the last column of [e_1 ... e_{N-1} | unit]:
    N_i = (-1)^(i + N - 1) det(E without row i), rows and columns counted from 0."""
    n = edge_rows.shape[-1]
    e = as_columns(edge_rows)
    comps = [(-1) ** (i + n - 1) * np.linalg.det(np.delete(e, i, axis=-2)) for i in range(n)]
    return np.stack(comps, axis=-1)


def volume_eq2(points: np.ndarray) -> np.ndarray:
    """Eq. 2: det of [x_1 ... x_N x_0 ; 1 ... 1] (x_0 in the last column) over N!."""
    n = points.shape[-1]
    cols = np.concatenate([points[..., 1:, :], points[..., :1, :]], axis=-2)
    m = np.concatenate([as_columns(cols), np.ones(points.shape[:-2] + (1, n + 1))], axis=-2)
    return np.linalg.det(m) / math.factorial(n)


def hadamard(points: np.ndarray) -> np.ndarray:
    """Product of the edge lengths: Hadamard's bound on |det E|, the scale of rounding errors."""
    return np.prod(np.linalg.norm(edges_of(points), axis=-1), axis=-1)


def exact_det(matrix) -> int:
    """Exact determinant of an integer matrix by fraction-free Bareiss elimination."""
    a = [[int(v) for v in row] for row in matrix]
    n = len(a)
    sign, prev = 1, 1
    for k in range(n - 1):
        if a[k][k] == 0:
            for i in range(k + 1, n):
                if a[i][k] != 0:
                    a[k], a[i] = a[i], a[k]
                    sign = -sign
                    break
            else:
                return 0
        for i in range(k + 1, n):
            for j in range(k + 1, n):
                a[i][j] = (a[i][j] * a[k][k] - a[i][k] * a[k][j]) // prev
        prev = a[k][k]
    return sign * a[n - 1][n - 1]


def leibniz_det(matrix) -> int:
    """Exact determinant by the Leibniz formula (a slow cross-check of ``exact_det``)."""
    n = len(matrix)
    total = 0
    for perm in itertools.permutations(range(n)):
        inversions = sum(perm[i] > perm[j] for i in range(n) for j in range(i + 1, n))
        term = -1 if inversions % 2 else 1
        for row, col in enumerate(perm):
            term *= int(matrix[row][col])
        total += term
    return total


def random_orthogonal(rng: np.random.Generator, n: int, size: int, det: int = 1) -> np.ndarray:
    """``size`` Haar-random orthogonal n x n matrices of determinant ``det`` (QR of Gaussians)."""
    q, r = np.linalg.qr(rng.standard_normal((size, n, n)))
    q = q * np.sign(np.diagonal(r, axis1=-2, axis2=-1))[:, None, :]
    flip = np.sign(np.linalg.det(q)) * det
    q[:, :, 0] *= flip[:, None]
    assert np.allclose(q @ as_columns(q), np.eye(n), atol=1e-12)
    assert np.allclose(np.linalg.det(q), det, atol=1e-12)
    return q


def householder(rng: np.random.Generator, n: int, size: int) -> np.ndarray:
    """``size`` random reflections I - 2 v v^T (det -1)."""
    v = rng.standard_normal((size, n))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    return np.eye(n) - 2 * v[:, :, None] * v[:, None, :]


def move(points: np.ndarray, m: np.ndarray, t: np.ndarray) -> np.ndarray:
    """x -> m x + t applied to every point (rows) of a batch; m (B, N, N), t (B, N)."""
    shift = t.reshape(t.shape[:1] + (1,) * (points.ndim - 2) + t.shape[1:])
    return np.einsum("bij,b...j->b...i", m, points) + shift


def affine_combination(rng: np.random.Generator, points: np.ndarray, low=-0.5, high=1.5):
    """Random points of the affine hull: weights (..., K+1) summing to 1 and the point."""
    k1 = points.shape[-2]
    w = rng.uniform(low, high, points.shape[:-2] + (k1,))
    w[..., 0] = 1.0 - w[..., 1:].sum(axis=-1)
    return w, np.einsum("...k,...kn->...n", w, points)


def well_conditioned(rng: np.random.Generator, shape: tuple, max_cond: float = 100.0) -> np.ndarray:
    """Gaussian simplices (..., K+1, N) whose edge matrices have condition number < max_cond
    (redrawn until they do), for identities whose tolerance would otherwise depend on it."""
    pts = rng.standard_normal(shape)
    while True:
        bad = np.linalg.cond(edges_of(pts)) >= max_cond
        if not bad.any():
            return pts
        pts[bad] = rng.standard_normal((int(bad.sum()),) + shape[-2:])


def assert_volumes_close(got, want, points, k: int, rtol: float = 1e-9):
    """K-volumes agree when their squares (k! V)^2, the Gram determinants of eqs. 4-5, agree to
    rtol, or to 1e-12 of the squared Hadamard bound (the rounding scale of a Gram determinant:
    sqrt(det G) of a thin simplex is only good to about eps * cond(E)^2)."""
    f = math.factorial(k)
    w2, want2 = (f * np.asarray(got)) ** 2, (f * np.asarray(want)) ** 2
    atol = 1e-12 * hadamard(points) ** 2
    bad = np.abs(w2 - want2) > rtol * np.abs(want2) + atol
    assert not bad.any(), (np.flatnonzero(bad), np.asarray(got)[bad], np.asarray(want)[bad])


def unit_normal_ref(points: np.ndarray) -> np.ndarray:
    c = cross_reference(edges_of(points))
    return c / np.linalg.norm(c, axis=-1, keepdims=True)


# ---------------------------------------------------------------------------------------------
# Package layout and supported range
# ---------------------------------------------------------------------------------------------


def test_import_ndtrace_alone_exposes_geometry():
    code = (
        "import ndtrace; f = ndtrace.geometry.signed_volume; "
        "v = f([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]); assert v == 0.5, v; print('ok')"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


def test_supported_dimension_range_is_2_to_8():
    assert (ndtrace.MIN_DIM, ndtrace.MAX_DIM) == (2, 8)
    assert set(g.__all__) == {
        "generalized_cross", "signed_volume", "gram_volume", "hyperplane",
        "point_hyperplane_distance", "barycentric", "clip_segment", "side",
        "ray_hyperplane", "transform_normal",
    }


def test_exact_determinant_reference_agrees_with_leibniz():
    """The exact Bareiss reference used below is itself checked against Leibniz' formula."""
    rng = np.random.default_rng(7)
    for n in range(1, 6):
        for _ in range(40):
            m = rng.integers(-4, 5, (n, n))
            if rng.random() < 0.3 and n > 1:
                m[-1] = m[0] - m[1 % n]  # a dependent row
            assert exact_det(m) == leibniz_det(m)
    assert exact_det([[0, 1], [1, 0]]) == -1
    assert exact_det(np.eye(8, dtype=int)) == 1


# ---------------------------------------------------------------------------------------------
# generalized_cross (eq. 6, eq. 8)
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", DIMS)
def test_cross_matches_cofactor_expansion_and_is_orthogonal_to_every_edge(n):
    rng = rng_for(1, n)
    e = rng.standard_normal((BATCH, n - 1, n))
    c = g.generalized_cross(e)
    assert c.shape == (BATCH, n) and c.dtype == np.float64
    np.testing.assert_allclose(c, cross_reference(e), rtol=1e-9, atol=1e-12)
    dots = np.einsum("bkn,bn->bk", e, c)
    scale = np.linalg.norm(e, axis=-1) * np.linalg.norm(c, axis=-1)[:, None]
    assert np.all(np.abs(dots) <= 1e-12 * scale), np.max(np.abs(dots) / scale)


@pytest.mark.parametrize("n", DIMS)
def test_cross_norm_squared_is_gram_determinant_and_facet_volume(n):
    rng = rng_for(2, n)
    e = rng.standard_normal((BATCH, n - 1, n)) * rng.uniform(0.1, 3.0, (BATCH, 1, 1))
    c = g.generalized_cross(e)
    norm2 = np.sum(c * c, axis=-1)
    gram_det = np.linalg.det(e @ as_columns(e))
    np.testing.assert_allclose(norm2, gram_det, rtol=1e-9)
    x0 = rng.uniform(-5, 5, (BATCH, n))
    facet_volume = g.gram_volume(simplex_from_edges(x0, e))
    np.testing.assert_allclose(norm2, (math.factorial(n - 1) * facet_volume) ** 2, rtol=1e-9)


@pytest.mark.parametrize("n", DIMS)
def test_cross_completes_a_right_handed_frame(n):
    """det[e_1 ... e_{N-1} | N] = |N|^2 > 0, and det[e_1 ... e_{N-1} | v] = v . N (eq. 6)."""
    rng = rng_for(3, n)
    e = rng.standard_normal((BATCH, n - 1, n))
    c = g.generalized_cross(e)
    d = np.linalg.det(np.concatenate([as_columns(e), c[:, :, None]], axis=-1))
    assert np.all(d > 0), d.min()
    np.testing.assert_allclose(d, np.sum(c * c, axis=-1), rtol=1e-9)
    v = rng.standard_normal((BATCH, n))
    dv = np.linalg.det(np.concatenate([as_columns(e), v[:, :, None]], axis=-1))
    scale = np.linalg.norm(v, axis=-1) * np.linalg.norm(c, axis=-1)
    assert np.all(np.abs(dv - np.sum(v * c, axis=-1)) <= 1e-10 * scale)


@pytest.mark.parametrize("n", DIMS)
def test_cross_of_leading_unit_vectors_is_plus_last_unit_vector(n):
    eye = np.eye(n)
    np.testing.assert_array_equal(g.generalized_cross(eye[: n - 1]), eye[n - 1])
    # Scaling an edge scales the normal; swapping two edges flips it (antisymmetry).
    scaled = eye[: n - 1] * np.arange(2.0, n + 1)[:, None]
    np.testing.assert_allclose(g.generalized_cross(scaled), math.factorial(n) * eye[n - 1])
    if n >= 3:
        swapped = eye[: n - 1][[1, 0] + list(range(2, n - 1))]
        np.testing.assert_array_equal(g.generalized_cross(swapped), -eye[n - 1])


def test_cross_in_2d_is_minus_b_a():
    rng = np.random.default_rng(4)
    ab = rng.uniform(-10, 10, (100, 1, 2))
    c = g.generalized_cross(ab)
    np.testing.assert_array_equal(c, np.stack([-ab[:, 0, 1], ab[:, 0, 0]], axis=-1))
    np.testing.assert_array_equal(g.generalized_cross([[3.0, 5.0]]), [-5.0, 3.0])
    np.testing.assert_array_equal(g.generalized_cross([[1.0, 0.0]]), [0.0, 1.0])


def test_cross_in_3d_is_the_familiar_cross_product():
    rng = np.random.default_rng(5)
    e = rng.standard_normal((100, 2, 3))
    np.testing.assert_allclose(g.generalized_cross(e), np.cross(e[:, 0], e[:, 1]), rtol=1e-12, atol=1e-14)
    np.testing.assert_array_equal(g.generalized_cross([[1, 2, 3], [4, 5, 6]]), [-3.0, 6.0, -3.0])


@pytest.mark.parametrize("n", DIMS)
def test_dot_product_of_cross_products_is_det_of_edge_dot_products(n):
    """Eq. 8: N(a_1 .. a_{N-1}) . N(b_1 .. b_{N-1}) = det[a_i . b_j]."""
    rng = rng_for(6, n)
    a = rng.standard_normal((BATCH, n - 1, n))
    b = rng.standard_normal((BATCH, n - 1, n))
    got = np.sum(g.generalized_cross(a) * g.generalized_cross(b), axis=-1)
    want = np.linalg.det(a @ as_columns(b))
    scale = np.prod(np.linalg.norm(a, axis=-1), axis=-1) * np.prod(np.linalg.norm(b, axis=-1), axis=-1)
    assert np.all(np.abs(got - want) <= 1e-10 * scale)


@pytest.mark.parametrize("n", DIMS)
def test_cross_is_multilinear_in_each_edge(n):
    rng = rng_for(7, n)
    e = rng.standard_normal((BATCH, n - 1, n))
    f = rng.standard_normal((BATCH, n))
    alpha, beta = 1.75, -0.5
    k = n // 2 - 1 if n > 2 else 0
    e_mix, e_f = e.copy(), e.copy()
    e_f[:, k] = f
    e_mix[:, k] = alpha * e[:, k] + beta * f
    got = g.generalized_cross(e_mix)
    want = alpha * g.generalized_cross(e) + beta * g.generalized_cross(e_f)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-10)


@pytest.mark.parametrize("n", DIMS)
def test_cross_batches_over_several_leading_axes_like_single_calls(n):
    rng = rng_for(8, n)
    e = rng.standard_normal((2, 3, 4, n - 1, n))
    batched = g.generalized_cross(e)
    assert batched.shape == (2, 3, 4, n)
    for idx in np.ndindex(2, 3, 4):
        np.testing.assert_array_equal(batched[idx], g.generalized_cross(e[idx]))
    # Non-contiguous and Fortran-ordered views give the same answers.
    np.testing.assert_array_equal(g.generalized_cross(e[:, ::2]), batched[:, ::2])
    np.testing.assert_array_equal(g.generalized_cross(np.asfortranarray(e)), batched)
    np.testing.assert_allclose(batched, cross_reference(e), rtol=1e-9, atol=1e-12)


# ---------------------------------------------------------------------------------------------
# signed_volume (eqs. 2-3)
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", DIMS)
def test_signed_volume_is_det_of_edge_columns_over_n_factorial(n):
    rng = rng_for(10, n)
    pts = rng.uniform(-3, 3, (BATCH, n + 1, n))
    v = g.signed_volume(pts)
    assert v.shape == (BATCH,)
    want = np.linalg.det(as_columns(edges_of(pts))) / math.factorial(n)
    tol = 1e-12 * hadamard(pts) / math.factorial(n)
    assert np.all(np.abs(v - want) <= tol)
    # Eq. 2, with x_0 in the last column and a row of ones, gives the same signed value.
    col_norms = np.sqrt(np.sum(pts * pts, axis=-1) + 1.0)
    tol2 = 1e-12 * np.prod(col_norms, axis=-1) / math.factorial(n)
    assert np.all(np.abs(v - volume_eq2(pts)) <= tol2)


@pytest.mark.parametrize("n", DIMS)
def test_standard_simplex_has_volume_plus_one_over_n_factorial(n):
    pts = np.vstack([np.zeros(n), np.eye(n)])
    assert g.signed_volume(pts) == pytest.approx(1.0 / math.factorial(n), rel=1e-15)
    # Translated and scaled by s, the volume scales by s^N and keeps its sign.
    moved = 2.5 * pts + np.arange(n)
    assert g.signed_volume(moved) == pytest.approx(2.5**n / math.factorial(n), rel=1e-13)


@pytest.mark.parametrize("n", DIMS)
def test_swapping_two_vertices_flips_the_sign(n):
    rng = rng_for(11, n)
    pts = rng.standard_normal((16, n + 1, n))
    v = g.signed_volume(pts)
    for i, j in itertools.combinations(range(n + 1), 2):
        sw = pts.copy()
        sw[:, [i, j]] = sw[:, [j, i]]
        np.testing.assert_allclose(g.signed_volume(sw), -v, rtol=1e-9, atol=1e-12)
    # An even permutation (a 3-cycle) keeps it.
    cyc = pts[:, [1, 2, 0] + list(range(3, n + 1))]
    np.testing.assert_allclose(g.signed_volume(cyc), v, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("n", DIMS)
def test_signed_volume_is_invariant_under_rotation_and_translation(n):
    rng = rng_for(12, n)
    pts = rng.standard_normal((BATCH, n + 1, n))
    v = g.signed_volume(pts)
    rot = special_ortho_group.rvs(n, size=BATCH, random_state=rng).reshape(BATCH, n, n)
    np.testing.assert_allclose(np.linalg.det(rot), 1.0, atol=1e-12)
    t = rng.uniform(-10, 10, (BATCH, n))
    moved = move(pts, rot, t)
    tol = 1e-11 * (hadamard(pts) + 1)
    assert np.all(np.abs(g.signed_volume(moved) - v) <= tol)
    # A reflection (det -1) flips the sign; so does a reflection composed with a rotation.
    refl = householder(rng, n, BATCH)
    assert np.all(np.abs(g.signed_volume(move(pts, refl, t)) + v) <= tol)
    assert np.all(np.abs(g.signed_volume(move(pts, refl @ rot, t)) + v) <= tol)


@pytest.mark.parametrize("n", DIMS)
def test_signed_volume_equals_exact_integer_determinant(n):
    """Small-integer simplices, a third of them affinely dependent: N! V_N is an integer that
    f64 must reproduce (exactly 0 up to rounding for dependent ones, with the right sign)."""
    rng = rng_for(13, n)
    f = math.factorial(n)
    pts = rng.integers(-3, 4, (90, n + 1, n))
    for i in range(0, 90, 3):
        kind = (i // 3) % 3
        if kind == 0:  # x_N = x_1 + x_{N-1} - x_0
            pts[i, n] = pts[i, 1] + pts[i, n - 1] - pts[i, 0]
        elif kind == 1:  # repeated vertex
            pts[i, n] = pts[i, 0]
        else:  # x_N = 2 x_1 - x_0: collinear with an edge
            pts[i, n] = 2 * pts[i, 1] - pts[i, 0]
    w = g.signed_volume(pts.astype(float)) * f
    bound = np.maximum(hadamard(pts.astype(float)), 1.0)
    n_zero = 0
    for i in range(90):
        exact = exact_det(as_columns(edges_of(pts[i])))
        assert round(w[i]) == exact, (i, w[i], exact)
        assert abs(w[i] - exact) <= 1e-12 * bound[i], (i, w[i], exact)
        if exact == 0:
            n_zero += 1
            assert abs(w[i]) <= 1e-12 * bound[i]
        else:
            assert np.sign(w[i]) == np.sign(exact)
    assert n_zero >= 30


# ---------------------------------------------------------------------------------------------
# gram_volume (eqs. 4-5)
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", DIMS)
def test_gram_volume_is_sqrt_gram_det_over_k_factorial_for_every_k(n):
    rng = rng_for(20, n)
    for k in range(1, n + 1):
        pts = rng.standard_normal((BATCH, k + 1, n))
        v = g.gram_volume(pts)
        assert v.shape == (BATCH,)
        e = edges_of(pts)
        want = np.sqrt(np.linalg.det(e @ as_columns(e))) / math.factorial(k)
        assert_volumes_close(v, want, pts, k)
        # Independent reference: QR of the N x K edge matrix, W_K = prod |diag R|.
        r = np.linalg.qr(as_columns(e), mode="r")
        qr_vol = np.prod(np.abs(np.diagonal(r, axis1=-2, axis2=-1)), axis=-1) / math.factorial(k)
        assert_volumes_close(v, qr_vol, pts, k)
        # On well-conditioned simplices the plain relative agreement is tight.
        good = well_conditioned(rng, (BATCH, k + 1, n))
        r = np.linalg.qr(as_columns(edges_of(good)), mode="r")
        qr_good = np.prod(np.abs(np.diagonal(r, axis1=-2, axis2=-1)), axis=-1) / math.factorial(k)
        np.testing.assert_allclose(g.gram_volume(good), qr_good, rtol=1e-10)
        if k == 1:
            np.testing.assert_allclose(v, np.linalg.norm(e[:, 0], axis=-1), rtol=1e-12)


@pytest.mark.parametrize("n", DIMS)
def test_gram_volume_for_k_equal_n_is_abs_signed_volume(n):
    rng = rng_for(21, n)
    pts = rng.standard_normal((BATCH, n + 1, n))
    assert_volumes_close(g.gram_volume(pts), np.abs(g.signed_volume(pts)), pts, n)
    good = well_conditioned(rng, (BATCH, n + 1, n))
    np.testing.assert_allclose(g.gram_volume(good), np.abs(g.signed_volume(good)), rtol=1e-10)


@pytest.mark.parametrize("n", DIMS)
def test_gram_volume_is_rotation_and_reflection_invariant(n):
    rng = rng_for(22, n)
    rot = random_orthogonal(rng, n, BATCH)
    refl = random_orthogonal(rng, n, BATCH, det=-1)
    t = rng.uniform(-10, 10, (BATCH, n))
    for k in range(1, n + 1):
        pts = rng.standard_normal((BATCH, k + 1, n))
        v = g.gram_volume(pts)
        assert_volumes_close(g.gram_volume(move(pts, rot, t)), v, pts, k)
        assert_volumes_close(g.gram_volume(move(pts, refl, t)), v, pts, k)


@pytest.mark.parametrize("n", DIMS)
def test_gram_volume_of_a_k_face_embedded_in_coordinates_is_its_k_volume(n):
    """A K-simplex in the first K coordinates (padded with zeros), then rotated into R^N, has
    the K-volume |det|/K! of its K x K coordinate matrix."""
    rng = rng_for(23, n)
    rot = random_orthogonal(rng, n, 8)
    for k in range(1, n + 1):
        low = well_conditioned(rng, (8, k + 1, k))
        pts = np.concatenate([low, np.zeros((8, k + 1, n - k))], axis=-1)
        want = np.abs(np.linalg.det(as_columns(edges_of(low)))) / math.factorial(k)
        np.testing.assert_allclose(g.gram_volume(move(pts, rot, np.zeros((8, n)))), want, rtol=1e-9)


# ---------------------------------------------------------------------------------------------
# hyperplane (eq. 1)
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", DIMS)
def test_hyperplane_normal_is_the_normalized_cross_product_and_contains_the_points(n):
    rng = rng_for(30, n)
    pts = rng.uniform(-4, 4, (BATCH, n, n))
    normal, c = g.hyperplane(pts)
    assert normal.shape == (BATCH, n) and c.shape == (BATCH,)
    np.testing.assert_allclose(np.linalg.norm(normal, axis=-1), 1.0, rtol=1e-14)
    cross = g.generalized_cross(edges_of(pts))
    unit = cross / np.linalg.norm(cross, axis=-1, keepdims=True)
    np.testing.assert_allclose(normal, unit, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(normal, unit_normal_ref(pts), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(c, np.sum(normal * pts[:, 0], axis=-1), rtol=1e-13, atol=1e-13)
    # Every defining point satisfies n . x = c.
    on = np.einsum("bn,bkn->bk", normal, pts) - c[:, None]
    assert np.all(np.abs(on) <= 1e-11 * (1 + np.abs(pts).max()))


@pytest.mark.parametrize("n", [3, 4, 5, 6])
def test_hyperplane_matches_convex_hull_facet_equations(n):
    """Facets of a random convex polytope, oriented so its interior lies below (the signed
    volume of (facet, interior point) is negative), give scipy's outward facet equations."""
    rng = rng_for(31, n)
    pts = rng.standard_normal((30, n))
    pts *= (1.0 + 0.05 * rng.random((30, 1))) / np.linalg.norm(pts, axis=1, keepdims=True)
    pts += rng.uniform(-2, 2, n)
    hull = ConvexHull(pts)
    interior = pts[hull.vertices].mean(axis=0)
    facets = pts[hull.simplices]
    vol = g.signed_volume(append_point(facets, interior))
    assert np.all(vol != 0)
    flip = vol > 0
    facets[flip, :2] = facets[flip, 1::-1]
    assert np.all(g.signed_volume(append_point(facets, interior)) < 0)
    assert np.all(g.side(interior, facets) == -1)
    normal, c = g.hyperplane(facets)
    np.testing.assert_allclose(normal, hull.equations[:, :n], atol=1e-9)
    np.testing.assert_allclose(c, -hull.equations[:, n], atol=1e-9)
    # All hull points lie on or below every facet hyperplane.
    assert np.all(pts @ normal.T - c <= 1e-9)


@pytest.mark.parametrize("n", DIMS)
def test_hyperplane_and_side_are_invariant_under_moderate_rescaling(n):
    rng = rng_for(32, n)
    pts = rng.standard_normal((16, n, n))
    x = rng.standard_normal((16, n))
    normal, c = g.hyperplane(pts)
    sides = g.side(x, pts)
    bary = g.barycentric(x, pts)
    for s in (1e-6, 1e-3, 1e3, 1e6):
        ns, cs = g.hyperplane(s * pts)
        np.testing.assert_allclose(ns, normal, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(cs, s * c, rtol=1e-9, atol=1e-12 * s)
        np.testing.assert_array_equal(g.side(s * x, s * pts), sides)
        np.testing.assert_allclose(g.barycentric(s * x, s * pts), bary, rtol=1e-8, atol=1e-9)


# ---------------------------------------------------------------------------------------------
# point_hyperplane_distance (eq. 11)
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", DIMS)
def test_distance_is_n_times_volume_over_facet_volume(n):
    rng = rng_for(40, n)
    pts = rng.standard_normal((BATCH, n, n))
    x = rng.uniform(-3, 3, (BATCH, n))
    h, p = g.point_hyperplane_distance(x, pts)
    assert h.shape == (BATCH,) and p.shape == (BATCH, n)
    want = n * g.signed_volume(append_point(pts, x)) / g.gram_volume(pts)
    np.testing.assert_allclose(h, want, rtol=1e-8, atol=1e-10)
    # The same with numpy only: W_N / W_{N-1}, W_{N-1} from the Gram determinant (eq. 4 trick).
    e = edges_of(pts)
    w_n = np.linalg.det(np.concatenate([as_columns(e), (x - pts[:, 0])[:, :, None]], axis=-1))
    w_n1 = np.sqrt(np.linalg.det(e @ as_columns(e)))
    np.testing.assert_allclose(h, w_n / w_n1, rtol=1e-8, atol=1e-10)


@pytest.mark.parametrize("n", DIMS)
def test_foot_point_lies_on_the_hyperplane_along_the_normal(n):
    rng = rng_for(41, n)
    pts = rng.standard_normal((BATCH, n, n))
    x = rng.uniform(-3, 3, (BATCH, n))
    h, p = g.point_hyperplane_distance(x, pts)
    normal, c = g.hyperplane(pts)
    assert np.all(np.abs(np.sum(normal * p, axis=-1) - c) <= 1e-11)
    np.testing.assert_allclose(x - p, h[:, None] * normal, atol=1e-11)
    np.testing.assert_allclose(np.linalg.norm(x - p, axis=-1), np.abs(h), atol=1e-11)
    # The sign of h says which side x is on.
    np.testing.assert_array_equal(g.side(x, pts), np.sign(h).astype(np.int8))


@pytest.mark.parametrize("n", DIMS)
def test_distance_agrees_with_least_squares_projection_onto_the_affine_hull(n):
    rng = rng_for(42, n)
    pts = rng.standard_normal((BATCH, n, n))
    x = rng.uniform(-3, 3, (BATCH, n))
    h, p = g.point_hyperplane_distance(x, pts)
    for i in range(BATCH):
        e = as_columns(edges_of(pts[i]))
        coef = np.linalg.lstsq(e, x[i] - pts[i, 0], rcond=None)[0]
        proj = pts[i, 0] + e @ coef
        np.testing.assert_allclose(p[i], proj, atol=1e-9)
        assert abs(abs(h[i]) - np.linalg.norm(x[i] - proj)) <= 1e-9


@pytest.mark.parametrize("n", DIMS)
def test_distance_is_invariant_under_rotation_and_translation(n):
    rng = rng_for(43, n)
    pts = rng.standard_normal((BATCH, n, n))
    x = rng.uniform(-3, 3, (BATCH, n))
    h, p = g.point_hyperplane_distance(x, pts)
    rot = random_orthogonal(rng, n, BATCH)
    t = rng.uniform(-10, 10, (BATCH, n))
    h2, p2 = g.point_hyperplane_distance(move(x[:, None], rot, t)[:, 0], move(pts, rot, t))
    np.testing.assert_allclose(h2, h, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(p2, move(p[:, None], rot, t)[:, 0], atol=1e-9)
    # A reflection keeps |h| but flips its sign (the normal is a pseudovector).
    refl = random_orthogonal(rng, n, BATCH, det=-1)
    h3, _ = g.point_hyperplane_distance(move(x[:, None], refl, t)[:, 0], move(pts, refl, t))
    np.testing.assert_allclose(h3, -h, rtol=1e-8, atol=1e-10)


@pytest.mark.parametrize("n", DIMS)
def test_distance_broadcasts_many_points_against_one_or_many_hyperplanes(n):
    rng = rng_for(44, n)
    pts = rng.standard_normal((n, n))
    xs = rng.uniform(-3, 3, (20, n))
    h, p = g.point_hyperplane_distance(xs, pts)
    assert h.shape == (20,) and p.shape == (20, n)
    normal, c = g.hyperplane(pts)
    np.testing.assert_allclose(h, xs @ normal - c, atol=1e-11)
    for i in range(20):
        hi, pi = g.point_hyperplane_distance(xs[i], pts)
        assert hi.shape == () and pi.shape == (n,)
        assert hi == h[i]
        np.testing.assert_array_equal(pi, p[i])
    # (5, 1, N) points against (3, N, N) hyperplanes -> (5, 3).
    many = rng.standard_normal((3, n, n))
    h2, p2 = g.point_hyperplane_distance(xs[:5, None, :], many)
    assert h2.shape == (5, 3) and p2.shape == (5, 3, n)
    for i, j in np.ndindex(5, 3):
        hij, pij = g.point_hyperplane_distance(xs[i], many[j])
        assert h2[i, j] == hij
        np.testing.assert_array_equal(p2[i, j], pij)


# ---------------------------------------------------------------------------------------------
# barycentric
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", DIMS)
def test_barycentric_rebuilds_points_of_the_affine_hull_for_every_k(n):
    rng = rng_for(50, n)
    for k in range(1, n + 1):
        pts = well_conditioned(rng, (BATCH, k + 1, n))
        w, x = affine_combination(rng, pts)
        t = g.barycentric(x, pts)
        assert t.shape == (BATCH, k + 1)
        np.testing.assert_allclose(t.sum(axis=-1), 1.0, atol=1e-12)
        np.testing.assert_allclose(np.einsum("bk,bkn->bn", t, pts), x, atol=1e-8)
        np.testing.assert_allclose(t, w, atol=1e-7)


@pytest.mark.parametrize("n", DIMS)
def test_barycentric_agrees_with_lstsq_and_off_hull_points_get_their_projection(n):
    rng = rng_for(51, n)
    for k in range(1, n + 1):
        pts = well_conditioned(rng, (12, k + 1, n))
        x = rng.uniform(-2, 2, (12, n))
        t = g.barycentric(x, pts)
        np.testing.assert_allclose(t.sum(axis=-1), 1.0, atol=1e-12)
        for i in range(12):
            # The affine system x_0 + sum t_k (x_k - x_0) = x in the least-squares sense.
            e = as_columns(edges_of(pts[i]))
            tau = np.linalg.lstsq(e, x[i] - pts[i, 0], rcond=None)[0]
            want = np.concatenate([[1.0 - tau.sum()], tau])
            np.testing.assert_allclose(t[i], want, atol=1e-8)
            # ... and the stacked system [points^T; 1] t = [x; 1] when x is in the hull.
            if k == n:
                a = np.vstack([pts[i].T, np.ones(k + 1)])
                exact = np.linalg.lstsq(a, np.append(x[i], 1.0), rcond=None)[0]
                np.testing.assert_allclose(t[i], exact, atol=1e-8)
        if k < n:
            # Moving x orthogonally to the hull does not change its coordinates; they are those
            # of its projection (computed with a QR basis of the edges).
            q = np.linalg.qr(as_columns(edges_of(pts)))[0]  # (12, n, k)
            d = x - pts[:, 0]
            proj = pts[:, 0] + np.einsum("bnk,bk->bn", q, np.einsum("bnk,bn->bk", q, d))
            np.testing.assert_allclose(g.barycentric(proj, pts), t, atol=1e-8)
            off = rng.standard_normal((12, n))
            off -= np.einsum("bnk,bk->bn", q, np.einsum("bnk,bn->bk", q, off))
            np.testing.assert_allclose(g.barycentric(x + 5 * off, pts), t, atol=1e-8)


@pytest.mark.parametrize("n", DIMS)
def test_barycentric_of_full_simplex_is_ratio_of_signed_volumes(n):
    """For K = N: t_i = V(x replacing x_i) / V."""
    rng = rng_for(52, n)
    pts = rng.standard_normal((16, n + 1, n))
    x = rng.uniform(-2, 2, (16, n))
    t = g.barycentric(x, pts)
    v = g.signed_volume(pts)
    for i in range(n + 1):
        rep = pts.copy()
        rep[:, i] = x
        np.testing.assert_allclose(t[:, i], g.signed_volume(rep) / v, rtol=1e-8, atol=1e-9)
        # The same ratio from numpy determinants alone.
        ratio = np.linalg.det(as_columns(edges_of(rep))) / np.linalg.det(as_columns(edges_of(pts)))
        np.testing.assert_allclose(t[:, i], ratio, rtol=1e-8, atol=1e-9)


@pytest.mark.parametrize("n", DIMS)
def test_barycentric_inside_test_agrees_with_sampling_and_point_location(n):
    rng = rng_for(53, n)
    pts = rng.standard_normal((n + 1, n))
    # Random convex combinations are inside and their weights come back.
    w = rng.dirichlet(np.ones(n + 1), 200)
    t = g.barycentric(w @ pts, pts)
    assert np.all(t >= -1e-12)
    np.testing.assert_allclose(t, w, atol=1e-9)
    # Pushing one weight negative puts the point outside, on that vertex's coordinate.
    j = rng.integers(0, n + 1, 200)
    u = rng.uniform(0.05, 1.0, 200)
    w_out = w.copy()
    w_out[np.arange(200), j] = 0.0
    w_out *= ((1.0 + u) / w_out.sum(axis=-1))[:, None]
    w_out[np.arange(200), j] = -u
    t_out = g.barycentric(w_out @ pts, pts)
    np.testing.assert_allclose(t_out, w_out, atol=1e-9)
    assert np.all(t_out[np.arange(200), j] < 0)
    # Random points: all t_i >= 0 exactly when scipy's Delaunay locates them in the simplex.
    wc = rng.dirichlet(np.full(n + 1, 3.0), 400)
    noise = rng.normal(0.0, 0.3 / (n + 1), (400, n + 1))
    cloud = (wc + noise - noise.mean(axis=-1, keepdims=True)) @ pts
    tc = g.barycentric(cloud, pts)
    clear = np.min(np.abs(tc), axis=-1) > 1e-9
    inside = np.all(tc >= 0, axis=-1)
    located = Delaunay(pts).find_simplex(cloud) >= 0
    np.testing.assert_array_equal(inside[clear], located[clear])
    assert 0 < inside.sum() < 400


@pytest.mark.parametrize("n", DIMS)
def test_barycentric_batches_and_broadcasts(n):
    rng = rng_for(54, n)
    k = max(1, n - 1)
    pts = rng.standard_normal((3, k + 1, n))
    xs = rng.standard_normal((4, 1, n))
    t = g.barycentric(xs, pts)
    assert t.shape == (4, 3, k + 1)
    for i, j in np.ndindex(4, 3):
        np.testing.assert_array_equal(t[i, j], g.barycentric(xs[i, 0], pts[j]))


# ---------------------------------------------------------------------------------------------
# side, clip_segment (eq. 10), ray_hyperplane
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", DIMS)
def test_side_is_the_sign_of_the_signed_volume_with_x_last(n):
    rng = rng_for(60, n)
    pts = rng.standard_normal((200, n, n))
    x = rng.uniform(-3, 3, (200, n))
    s = g.side(x, pts)
    assert s.dtype == np.int8 and s.shape == (200,)
    v = g.signed_volume(append_point(pts, x))
    np.testing.assert_array_equal(s, np.sign(v).astype(np.int8))
    np.testing.assert_array_equal(s, np.sign(np.linalg.det(as_columns(edges_of(append_point(pts, x))))))
    assert set(np.unique(s)) == {-1, 1}
    # Above means where the normal points: x0 + d*n is above for d > 0, below for d < 0.
    normal, _ = g.hyperplane(pts)
    np.testing.assert_array_equal(g.side(pts[:, 0] + 0.5 * normal, pts), 1)
    np.testing.assert_array_equal(g.side(pts[:, 0] - 0.5 * normal, pts), -1)


@pytest.mark.parametrize("n", DIMS)
def test_points_on_the_hyperplane_are_on_side_zero(n):
    rng = rng_for(61, n)
    pts = rng.standard_normal((BATCH, n, n))
    _, on = affine_combination(rng, pts)
    np.testing.assert_array_equal(g.side(on, pts), 0)
    for k in range(n):
        np.testing.assert_array_equal(g.side(pts[:, k], pts), 0)
    # Nudged off by a small multiple of the normal they leave the plane on the right side.
    normal, _ = g.hyperplane(pts)
    np.testing.assert_array_equal(g.side(on + 1e-6 * normal, pts), 1)
    np.testing.assert_array_equal(g.side(on - 1e-6 * normal, pts), -1)


@pytest.mark.parametrize("n", DIMS)
def test_clip_segment_crosses_exactly_when_the_ends_are_on_opposite_sides(n):
    rng = rng_for(62, n)
    pts = rng.standard_normal((200, n, n))
    a = rng.uniform(-3, 3, (200, n))
    b = rng.uniform(-3, 3, (200, n))
    t = g.clip_segment(a, b, pts)
    hit = a + t[:, None] * (b - a)
    normal, c = g.hyperplane(pts)
    assert np.all(np.abs(np.sum(normal * hit, axis=-1) - c) <= 1e-10 * (1 + np.abs(t)))
    crosses = g.side(a, pts) * g.side(b, pts) < 0
    np.testing.assert_array_equal(crosses, (t >= 0) & (t <= 1))
    assert 0 < crosses.sum() < 200
    # Eq. 10 with numpy determinants: det[e_1 .. e_{N-1}, a - x_0] / det[e_1 .. e_{N-1}, a - b].
    e = as_columns(edges_of(pts))
    num = np.linalg.det(np.concatenate([e, (a - pts[:, 0])[:, :, None]], axis=-1))
    den = np.linalg.det(np.concatenate([e, (a - b)[:, :, None]], axis=-1))
    np.testing.assert_allclose(t, num / den, rtol=1e-8, atol=1e-10)
    # The ray form with direction b - a gives the same parameter.
    np.testing.assert_allclose(g.ray_hyperplane(a, b - a, pts), t, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("n", DIMS)
def test_clip_and_ray_parameters_for_constructed_crossings(n):
    rng = rng_for(63, n)
    pts = rng.standard_normal((BATCH, n, n))
    normal, _ = g.hyperplane(pts)
    _, q = affine_combination(rng, pts)  # a point of the hyperplane
    tangent = affine_combination(rng, pts)[1] - q  # a direction inside it
    alpha = rng.uniform(0.1, 2.0, BATCH)
    beta = rng.uniform(0.1, 2.0, BATCH)
    a = q + alpha[:, None] * normal + 0.3 * tangent
    b = q - beta[:, None] * normal - 0.7 * tangent
    t = g.clip_segment(a, b, pts)
    np.testing.assert_allclose(t, alpha / (alpha + beta), rtol=1e-9)
    # Ray from a toward the plane with an unnormalized direction, and away from it (t < 0).
    s = rng.uniform(0.5, 3.0, BATCH)
    tr = g.ray_hyperplane(a, -s[:, None] * normal, pts)
    np.testing.assert_allclose(tr, alpha / s, rtol=1e-9)
    np.testing.assert_allclose(g.ray_hyperplane(a, s[:, None] * normal, pts), -alpha / s, rtol=1e-9)
    hit = a + tr[:, None] * (-s[:, None] * normal)
    np.testing.assert_array_equal(g.side(hit, pts), 0)


@pytest.mark.parametrize("n", DIMS)
def test_parallel_segments_and_rays_raise_or_give_nan(n):
    rng = rng_for(64, n)
    pts = rng.standard_normal((6, n, n))
    a = rng.uniform(-3, 3, (6, n))
    along = pts[:, -1] - pts[:, 0]  # a direction inside the hyperplane
    d = rng.standard_normal((6, n))
    d[3] = along[3]
    d[5] = along[5]
    with pytest.raises(ValueError, match=r"parallel.*batch index 3"):
        g.ray_hyperplane(a, d, pts)
    with pytest.raises(ValueError, match=r"parallel.*batch index 3"):
        g.clip_segment(a, a + d, pts)
    with pytest.raises(ValueError, match="parallel"):
        g.clip_segment(a[0], a[0], pts[0])  # zero-length segment
    with pytest.raises(ValueError, match="parallel"):
        g.ray_hyperplane(a[0], np.zeros(n), pts[0])  # zero direction
    tr = g.ray_hyperplane(a, d, pts, degenerate="nan")
    tc = g.clip_segment(a, a + d, pts, degenerate="nan")
    bad = np.isin(np.arange(6), [3, 5])
    for got in (tr, tc):
        np.testing.assert_array_equal(np.isnan(got), bad)
    for i in np.flatnonzero(~bad):
        assert tr[i] == g.ray_hyperplane(a[i], d[i], pts[i])
        assert tc[i] == g.clip_segment(a[i], a[i] + d[i], pts[i])
    assert np.isnan(g.clip_segment(a[0], a[0], pts[0], degenerate="nan"))


# ---------------------------------------------------------------------------------------------
# transform_normal ("Are Normals Vectors? Almost!")
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", DIMS)
@pytest.mark.parametrize("kind", ["rotation", "reflection", "general", "singular"])
def test_transform_normal_matches_cross_product_of_transformed_edges(n, kind):
    rng = rng_for(70 + ["rotation", "reflection", "general", "singular"].index(kind), n)
    if kind == "rotation":
        m = random_orthogonal(rng, n, BATCH)
    elif kind == "reflection":
        m = random_orthogonal(rng, n, BATCH, det=-1)
    else:
        m = rng.standard_normal((BATCH, n, n))
        if kind == "singular":  # rank n - 1
            m[:, :, -1] = 2.0 * m[:, :, 0] if n == 2 else m[:, :, 0] - 2.0 * m[:, :, 1]
            bound = np.prod(np.linalg.norm(m, axis=-2), axis=-1)
            assert np.all(np.abs(np.linalg.det(m)) <= 1e-12 * bound)
    e = rng.standard_normal((BATCH, n - 1, n))
    normal = g.generalized_cross(e)
    got = g.transform_normal(m, normal)
    want = g.generalized_cross(e @ as_columns(m))  # edges transformed: e_k -> M e_k
    scale = np.linalg.norm(want, axis=-1, keepdims=True)
    scale = scale + np.linalg.norm(normal, axis=-1, keepdims=True) * np.abs(m).max() ** (n - 1)
    assert np.all(np.abs(got - want) <= 1e-10 * scale)
    if kind in ("rotation", "reflection"):
        det = np.linalg.det(m)
        np.testing.assert_allclose(det, 1.0 if kind == "rotation" else -1.0, atol=1e-12)
        rn = np.einsum("bij,bj->bi", m, normal)
        np.testing.assert_allclose(got, det[:, None] * rn, atol=1e-10)
    if kind == "general":
        # cof(M) N = det(M) M^{-T} N.
        ref = np.linalg.det(m)[:, None] * np.linalg.solve(as_columns(m), normal[:, :, None])[..., 0]
        np.testing.assert_allclose(got, ref, rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("n", DIMS)
def test_reflection_flips_the_transformed_normal_relative_to_r_n(n):
    rng = rng_for(75, n)
    refl = householder(rng, n, 16)
    normal = rng.standard_normal((16, n))
    rn = np.einsum("bij,bj->bi", refl, normal)
    np.testing.assert_allclose(g.transform_normal(refl, normal), -rn, atol=1e-12)
    # Broadcasting: one normal against a batch of matrices and vice versa.
    one = g.transform_normal(refl, normal[0])
    assert one.shape == (16, n)
    for i in range(16):
        np.testing.assert_array_equal(one[i], g.transform_normal(refl[i], normal[0]))
    one_matrix = g.transform_normal(refl[0], normal)
    np.testing.assert_array_equal(one_matrix[3], g.transform_normal(refl[0], normal[3]))


# ---------------------------------------------------------------------------------------------
# Degenerate input
# ---------------------------------------------------------------------------------------------


def degenerate_batch(rng, n, bad=(2, 4), rows=None):
    """A batch of 6 simplices (rows points each) with repeated points in the ``bad`` items."""
    rows = n if rows is None else rows
    pts = rng.standard_normal((6, rows, n))
    for i in bad:
        pts[i, -1] = pts[i, 0]
    return pts


@pytest.mark.parametrize("n", DIMS)
def test_repeated_points_give_zero_cross_product_and_volumes(n):
    rng = rng_for(80, n)
    pts = rng.standard_normal((n, n))
    for i, j in itertools.combinations(range(n), 2):
        rep = pts.copy()
        rep[j] = rep[i]
        # Zero up to rounding (the elimination leaves ~1e-16 * |e|^(N-1), not an exact 0).
        c = g.generalized_cross(edges_of(rep))
        assert np.linalg.norm(c) <= 1e-14 * (1 + hadamard(rep[None])[0]), c
        assert g.side(rng.standard_normal(n), rep) == 0
        full = append_point(rep, rng.standard_normal(n))
        assert abs(g.signed_volume(full)) <= 1e-14 * hadamard(full[None])[0] + 1e-300
        assert g.gram_volume(rep) <= 1e-14 * (1 + hadamard(rep[None])[0])
    # Affinely dependent without repeats: the last point is an affine combination of the others.
    if n >= 3:
        dep = pts.copy()
        dep[-1] = 0.25 * dep[0] + 0.75 * dep[1]
        c = g.generalized_cross(edges_of(dep))
        assert np.linalg.norm(c) <= 1e-12 * hadamard(dep[None])[0]
        with pytest.raises(ValueError, match=r"degenerate.*batch index 0"):
            g.hyperplane(dep)


@pytest.mark.parametrize("n", DIMS)
def test_hyperplane_of_degenerate_items_raises_with_index_or_gives_nan(n):
    rng = rng_for(81, n)
    pts = degenerate_batch(rng, n)
    with pytest.raises(ValueError, match=r"^points: degenerate simplex .*batch index 2\b"):
        g.hyperplane(pts)
    with pytest.raises(ValueError, match=r"batch index 1\b"):
        g.hyperplane(pts[3:])  # item 4 of pts is item 1 here
    normal, c = g.hyperplane(pts, degenerate="nan")
    bad = np.isin(np.arange(6), [2, 4])
    np.testing.assert_array_equal(np.isnan(c), bad)
    np.testing.assert_array_equal(np.isnan(normal), np.repeat(bad[:, None], n, axis=1))
    for i in np.flatnonzero(~bad):
        ni, ci = g.hyperplane(pts[i])
        np.testing.assert_array_equal(normal[i], ni)
        assert c[i] == ci


def test_hyperplane_degenerate_index_over_several_batch_axes():
    rng = np.random.default_rng(82)
    pts = rng.standard_normal((2, 3, 3, 3))
    pts[1, 2, 2] = pts[1, 2, 0]
    with pytest.raises(ValueError) as info:
        g.hyperplane(pts)
    # Either the flat index (5) or the index tuple (1, 2) identifies the item.
    assert re.search(r"batch index (5\b|\(1, 2\))", str(info.value)), str(info.value)
    normal, c = g.hyperplane(pts, degenerate="nan")
    expected = np.zeros((2, 3), bool)
    expected[1, 2] = True
    np.testing.assert_array_equal(np.isnan(c), expected)


@pytest.mark.parametrize("n", DIMS)
def test_degenerate_simplices_in_distance_barycentric_clip_and_ray(n):
    rng = rng_for(83, n)
    bad = np.isin(np.arange(6), [2, 4])
    pts = degenerate_batch(rng, n)
    x = rng.standard_normal((6, n))
    y = rng.standard_normal((6, n))
    calls = {
        "point_hyperplane_distance": lambda **kw: g.point_hyperplane_distance(x, pts, **kw),
        "clip_segment": lambda **kw: g.clip_segment(x, y, pts, **kw),
        "ray_hyperplane": lambda **kw: g.ray_hyperplane(x, y - x, pts, **kw),
    }
    for k in sorted({1, n - 1, n}):
        kpts = degenerate_batch(rng, n, rows=k + 1)
        calls[f"barycentric K={k}"] = lambda kpts=kpts, **kw: g.barycentric(x, kpts, **kw)
    for name, fn in calls.items():
        with pytest.raises(ValueError, match=r"degenerate simplex.*batch index 2\b"):
            fn()
        with pytest.raises(ValueError, match=r"degenerate simplex.*batch index 2\b"):
            fn(degenerate="raise")
        out = fn(degenerate="nan")
        for arr in out if isinstance(out, tuple) else (out,):
            flags = np.isnan(arr).reshape(6, -1)
            assert np.all(flags.all(axis=1) == bad) and np.all(flags.any(axis=1) == bad), name


# ---------------------------------------------------------------------------------------------
# Bad input
# ---------------------------------------------------------------------------------------------


def valid_args(n: int) -> dict:
    """Valid arguments (by function) in dimension n, as {argument name: value} dicts."""
    rng = np.random.default_rng(90 + n)
    p = rng.standard_normal
    return {
        "generalized_cross": {"edges": p((n - 1, n))},
        "signed_volume": {"points": p((n + 1, n))},
        "gram_volume": {"points": p((n, n))},
        "hyperplane": {"points": p((n, n))},
        "point_hyperplane_distance": {"x": p(n), "points": p((n, n))},
        "barycentric": {"x": p(n), "points": p((n + 1, n))},
        "side": {"x": p(n), "points": p((n, n))},
        "clip_segment": {"a": p(n), "b": p(n) + 5.0, "points": p((n, n))},
        "ray_hyperplane": {"origin": p(n), "direction": p(n) + 1.0, "points": p((n, n))},
        "transform_normal": {"matrix": p((n, n)), "normal": p(n)},
    }


def call(name: str, args: dict, **kw):
    return getattr(g, name)(*args.values(), **kw)


ARGUMENTS = [(f, a) for f, args in valid_args(3).items() for a in args]
WITH_DEGENERATE = ["hyperplane", "point_hyperplane_distance", "barycentric", "clip_segment", "ray_hyperplane"]


@pytest.mark.parametrize("func", list(valid_args(3)))
def test_valid_arguments_are_accepted(func):
    """The baseline for the bad-input tests: the unmodified arguments work."""
    out = call(func, valid_args(3)[func])
    for arr in out if isinstance(out, tuple) else (out,):
        assert np.all(np.isfinite(arr))


def test_edges_of_the_wrong_shape_are_rejected():
    with pytest.raises(ValueError, match=r"^edges: .*\(3, 5\)"):
        g.generalized_cross(np.zeros((3, 5)))
    with pytest.raises(ValueError, match=r"^edges: .*\(\.\.\., N-1, N\)"):
        g.generalized_cross(np.zeros(4))
    with pytest.raises(ValueError, match=r"^points: .*\(4, 4\)"):
        g.signed_volume(np.zeros((4, 4)))
    with pytest.raises(ValueError, match=r"^points: .*\(3, 2\)"):
        g.hyperplane(np.zeros((3, 2)))
    with pytest.raises(ValueError, match=r"^matrix: .*\(3, 4\)"):
        g.transform_normal(np.zeros((3, 4)), np.zeros(4))
    for func in ("gram_volume", "barycentric"):
        for rows in (1, 5):  # K = 0 and K = N + 1 in 3D
            args = valid_args(3)[func] | {"points": np.ones((rows, 3))}
            with pytest.raises(ValueError, match=r"^points: .*K = " + str(rows - 1)):
                call(func, args)


@pytest.mark.parametrize("func,arg", [(f, a) for f, a in ARGUMENTS if a not in ("edges", "points", "matrix")])
def test_vectors_of_the_wrong_length_are_rejected(func, arg):
    args = valid_args(3)[func] | {arg: np.ones(4)}
    with pytest.raises(ValueError, match=rf"^{arg}: expected shape \(\.\.\., 3\)"):
        call(func, args)


@pytest.mark.parametrize("n", [0, 1, 9, 10])
@pytest.mark.parametrize("func", list(valid_args(3)))
def test_dimensions_outside_2_to_8_are_rejected_naming_the_range(func, n):
    rows = {"generalized_cross": n - 1, "signed_volume": n + 1, "gram_volume": 2, "barycentric": 2}
    rows = max(rows.get(func, n), 0)
    core = np.ones((rows, n))
    args = {}
    for name, value in valid_args(3)[func].items():
        args[name] = core if np.ndim(value) == 2 else np.ones(n)
    main = next(name for name, value in args.items() if value is core)  # checked first
    with pytest.raises(ValueError, match=rf"^{main}: .*N in 2\.\.8.*N = {n}\)"):
        call(func, args)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("func,arg", ARGUMENTS)
def test_non_finite_values_are_rejected_naming_the_argument(func, arg, bad):
    args = valid_args(3)[func]
    poisoned = np.array(args[arg], dtype=float)
    poisoned.flat[poisoned.size // 2] = bad
    args[arg] = poisoned
    with pytest.raises(ValueError, match=rf"^{arg}: non-finite value"):
        call(func, args)


@pytest.mark.parametrize("junk", ["text", "none", "ragged"])
@pytest.mark.parametrize("func,arg", ARGUMENTS)
def test_non_numeric_input_is_rejected_naming_the_argument(func, arg, junk):
    args = valid_args(3)[func]
    good = np.asarray(args[arg])
    if junk == "text":
        value = np.full(good.shape, "abc", dtype=object).tolist()
    elif junk == "none":
        value = np.full(good.shape, None, dtype=object).tolist()
    else:  # ragged nested lists
        value = [[1.0, 2.0, 3.0], [1.0]]
    args[arg] = value
    with pytest.raises(ValueError, match=rf"^{arg}: "):
        call(func, args)


@pytest.mark.parametrize("func", [f for f, args in valid_args(3).items() if len(args) > 1])
def test_batch_axes_that_do_not_broadcast_are_rejected_naming_the_arguments(func):
    args = valid_args(3)[func]
    names = list(args)
    args[names[0]] = np.broadcast_to(args[names[0]], (4,) + np.shape(args[names[0]]))
    args[names[-1]] = np.broadcast_to(args[names[-1]], (3,) + np.shape(args[names[-1]]))
    with pytest.raises(ValueError, match="do not broadcast") as info:
        call(func, args)
    for name in (names[0], names[-1]):
        assert re.search(rf"\b{name} \(", str(info.value)), str(info.value)


@pytest.mark.parametrize("value", ["ignore", "NaN", "", None, True])
@pytest.mark.parametrize("func", WITH_DEGENERATE)
def test_invalid_degenerate_option_is_rejected(func, value):
    with pytest.raises(ValueError, match=r"^degenerate: expected \"raise\" or \"nan\""):
        call(func, valid_args(3)[func], degenerate=value)


# ---------------------------------------------------------------------------------------------
# Known limitations: extreme coordinate magnitudes (see the report of this test suite)
# ---------------------------------------------------------------------------------------------


def test_hyperplane_normal_stays_unit_for_huge_coordinates_in_8d():
    # det[e_k - e_1 | (1, ..., 1)] = -8 < 0, so the normal of eq. 6 is -(1, ..., 1)/sqrt(8).
    pts = 1e23 * np.eye(8)
    normal, c = g.hyperplane(pts)
    np.testing.assert_allclose(normal, np.full(8, -(8**-0.5)), rtol=1e-12)
    assert c == pytest.approx(-1e23 * 8**-0.5, rel=1e-12)
    assert np.linalg.det(np.column_stack([(pts[1:] - pts[0]).T, normal])) > 0


@pytest.mark.parametrize("scale", [1e20, 1e-21])
def test_barycentric_of_a_regular_simplex_at_extreme_scales_in_8d(scale):
    pts = scale * np.vstack([np.zeros(8), np.eye(8)])
    np.testing.assert_allclose(g.barycentric(pts.mean(axis=0), pts), np.full(9, 1 / 9), rtol=1e-12)
