"""Tests of curve frames, quaternion frames and tubes (``ndtrace.frames``; course notes Part II(A)).

Expectations come from closed forms computed here: the helix's Frenet frame, curvature and
torsion; the moving-frame equations T' = k1 N + k2 B, N' = −k1 T + σ B, B' = −k2 T − σ N checked
by finite differences; the tube meshes' combinatorics (every edge / face shared by exactly two
simplices with opposite induced orientations) and geometry (outward normals, enclosed volume).
"""

from __future__ import annotations

import os
import runpy
import textwrap

import numpy as np
import pytest

import ndtrace
from ndtrace import frames as fr, rotation as rot
from ndtrace.rotation import quat_multiply, quat_to_matrix

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# The helix x = (r cos t, r sin t, c t): speed w = √(r² + c²), κ = r/w², τ = c/w², and
# T = (−r sin t, r cos t, c)/w, N = (−cos t, −sin t, 0), B = (c sin t, −c cos t, r)/w.
R_HELIX, C_HELIX = 1.0, 0.5
W_HELIX = np.hypot(R_HELIX, C_HELIX)
KAPPA, TAU = R_HELIX / W_HELIX**2, C_HELIX / W_HELIX**2


def helix(n: int = 400, turns: float = 2.0):
    t = np.linspace(0.0, 2 * np.pi * turns, n)
    r, c, w = R_HELIX, C_HELIX, W_HELIX
    points = np.stack([r * np.cos(t), r * np.sin(t), c * t], axis=1)
    T = np.stack([-r * np.sin(t), r * np.cos(t), np.full_like(t, c)], axis=1) / w
    N = np.stack([-np.cos(t), -np.sin(t), np.zeros_like(t)], axis=1)
    B = np.stack([c * np.sin(t), -c * np.cos(t), np.full_like(t, r)], axis=1) / w
    return points, (T, N, B), w * t  # arclength s = w t


def assert_frame(T, N, B, tol=1e-10):
    R = np.stack([T, N, B], axis=-1)
    np.testing.assert_allclose(np.einsum("nji,njk->nik", R, R), np.broadcast_to(np.eye(3), R.shape), atol=tol)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=tol)
    np.testing.assert_allclose(np.cross(T, N), B, atol=tol)


KNOT = fr.torus_knot(3, 5, 400)
WOBBLY = np.stack([np.cos(np.linspace(0, 5, 300)), np.sin(2 * np.linspace(0, 5, 300)),
                   np.linspace(0, 5, 300) ** 1.5 / 4], axis=1)


# ---------------------------------------------------------------------------------------------
# Frames
# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("make", [
    lambda: fr.frenet(KNOT, closed=True),
    lambda: fr.parallel_transport(KNOT, closed=True),
    lambda: fr.parallel_transport(WOBBLY, normal=[0.3, 0.2, 1.0]),
    lambda: fr.geodesic_reference(KNOT, closed=True, reference=[0.2, 0.1, 1.0]),
    lambda: fr.geodesic_reference(WOBBLY),
    lambda: fr.optimal_periodic(KNOT),
    lambda: fr.optimal_periodic(KNOT, method="arclength"),
], ids=["frenet", "transport", "transport-normal", "geodesic", "geodesic-default", "optimal", "linear-twist"])
def test_frames_are_orthonormal_right_handed_and_follow_the_tangent(make):
    T, N, B = make()
    assert_frame(T, N, B)
    points = KNOT if len(T) == len(KNOT) else WOBBLY
    closed = len(T) == len(KNOT)
    # T is the unit central difference (p_{i+1} − p_{i−1}) for interior samples.
    chord = points[2:] - points[:-2]
    np.testing.assert_allclose(T[1:-1], chord / np.linalg.norm(chord, axis=1)[:, None], atol=1e-12)
    if closed:
        np.testing.assert_allclose(T[0], fr.tangents(points[[-1, 0, 1]])[1], atol=1e-12)


def test_module_example_runs_and_closes():
    """The module docstring's example (the text after "Example") runs and gives a closed frame."""
    example = textwrap.dedent(fr.__doc__.split("Example", 1)[1].split("::\n", 1)[1])
    namespace: dict = {}
    exec(example, namespace)
    T, N, B = namespace["T"], namespace["N"], namespace["B"]
    assert_frame(T, N, B)
    assert namespace["triangles"].shape == (2 * 16 * 400, 3)


def test_tangents_and_arclength_are_correct_in_any_dimension():
    circle = np.stack([np.cos(np.arange(12) * np.pi / 6), np.sin(np.arange(12) * np.pi / 6),
                       np.zeros(12), np.ones(12)], axis=1)
    T = fr.tangents(circle, closed=True)
    np.testing.assert_allclose(T, np.stack([-circle[:, 1], circle[:, 0], 0 * circle[:, 2], 0 * circle[:, 3]], 1),
                               atol=1e-12)
    s = fr.arclength(circle, closed=True)
    assert s.shape == (13,) and s[0] == 0
    np.testing.assert_allclose(s[-1], 12 * 2 * np.sin(np.pi / 12))
    # Open ends use second-order one-sided differences: exact for a parabola's direction.
    t = np.linspace(0, 1, 5)
    parabola = np.stack([t, t**2, 0 * t], axis=1)
    np.testing.assert_allclose(fr.tangents(parabola)[[0, -1]], [[1, 0, 0], [1 / np.sqrt(5), 2 / np.sqrt(5), 0]],
                               atol=1e-12)


def test_frenet_matches_the_analytic_helix_frame():
    points, (T, N, B), _ = helix()
    Tf, Nf, Bf = fr.frenet(points)
    h = (points[1, 2] - points[0, 2]) / C_HELIX  # parameter step; the error is O(h²)
    for got, want in ((Tf, T), (Nf, N), (Bf, B)):
        err = np.abs(got - want).max(axis=1)
        assert err[2:-2].max() < h**2  # central differences (N uses T of the neighbours)
        assert err.max() < 20 * h**2  # one-sided at the ends: still O(h²), a larger constant
    assert np.abs(Tf - T).max() > 1e-9  # (a genuinely discrete estimate, not the formula)


def test_frenet_refuses_zero_curvature_and_names_the_sample():
    t = np.linspace(0, 1, 20)
    bent = np.stack([t, np.where(t > 0.5, (t - 0.5) ** 2, 0.0), 0 * t], axis=1)  # straight, then curving
    with pytest.raises(ValueError, match="curvature vanishes at sample 0"):
        fr.frenet(bent)
    T, N, B = fr.frenet(bent, on_zero_curvature="nan")
    flat = np.isnan(N).any(axis=1)
    assert flat[:8].all() and not flat[12:].any()
    assert_frame(T[~flat], N[~flat], B[~flat])
    with pytest.raises(ValueError, match="on_zero_curvature"):
        fr.frenet(bent, on_zero_curvature="ignore")


def test_minimal_rotation_takes_a_to_b_and_fixes_the_rest():
    rng = np.random.default_rng(3)
    for dim in (3, 4, 6):
        a, b = (v / np.linalg.norm(v) for v in rng.normal(size=(2, dim)))
        M = fr.minimal_rotation(a[None], b[None], np.eye(dim))  # rows: images of the axes = Mᵀ
        np.testing.assert_allclose(M @ M.T, np.eye(dim), atol=1e-12)
        np.testing.assert_allclose(np.linalg.det(M), 1.0, atol=1e-12)
        np.testing.assert_allclose(fr.minimal_rotation(a, b, a), b, atol=1e-12)
        u = rng.normal(size=dim)
        u -= np.linalg.lstsq(np.stack([a, b], 1), u, rcond=None)[0] @ np.stack([a, b])
        np.testing.assert_allclose(fr.minimal_rotation(a, b, u), u, atol=1e-12)
    with pytest.raises(ValueError, match="antiparallel"):
        fr.minimal_rotation([1.0, 0, 0], [-1.0, 0, 0], [0, 1.0, 0])


def test_minimal_rotation_is_rotation_between_and_checks_its_input():
    rng = np.random.default_rng(4)
    a, b = (v / np.linalg.norm(v, axis=1, keepdims=True) for v in rng.normal(size=(2, 7, 4)))
    v = rng.normal(size=(7, 4))
    want = np.einsum("nij,nj->ni", rot.rotation_between(a, b), v)
    np.testing.assert_allclose(fr.minimal_rotation(a, b, v), want, atol=1e-15)
    # Several vectors (K, N) moved by one rotation, and one a against many b.
    np.testing.assert_allclose(fr.minimal_rotation(a[0], b[0], v), v @ rot.rotation_between(a[0], b[0]).T,
                               atol=1e-15)
    np.testing.assert_allclose(fr.minimal_rotation(a[0], b, v)[3], rot.rotation_between(a[0], b[3]) @ v[3],
                               atol=1e-15)
    for call, match in [
        (lambda: fr.minimal_rotation(2 * a[0], b[0], v[0]), r"^a: not a unit vector"),
        (lambda: fr.minimal_rotation(a[0], b[0] + 1e-6, v[0]), r"^b: not a unit vector"),
        (lambda: fr.minimal_rotation(a[0], b[0], [np.nan, 0, 0, 0]), r"^v: non-finite"),
        (lambda: fr.minimal_rotation(a[0], b[0], "xyzw"), r"^v: expected real numbers"),
        (lambda: fr.minimal_rotation(a[0], b[0], v[0, :3]), r"^a, b, v: expected vectors of the same length"),
        (lambda: fr.minimal_rotation(a[:3], b[:3], v[:2]), r"^a, b, v: batch axes do not broadcast"),
        (lambda: fr.minimal_rotation(a[:2], np.stack([b[0], -a[1]]), v[:2]), r"^a, b: antiparallel at index \(1,\)"),
    ]:
        with pytest.raises(ValueError, match=match):
            call()


def test_parallel_transport_has_zero_twist():
    points, _, s = helix()
    T, N, B = fr.parallel_transport(points)
    # N'·B = σ = 0 (finite differences along the curve) while N' itself is not small.
    dN = np.gradient(N, s, axis=0)
    assert np.abs(np.sum(dN * B, axis=1))[1:-1].max() < 1e-3 * KAPPA  # (|N'| = |k1| ≤ κ)
    k1, k2, sigma = fr.frame_curvatures(T, N, B, s)
    assert np.abs(sigma).max() < 1e-10
    np.testing.assert_allclose(np.hypot(k1, k2)[2:-2], KAPPA, rtol=1e-4)  # Bishop: k1² + k2² = κ²
    np.testing.assert_allclose(fr.twist_angles(T, N, B), 0.0, atol=1e-12)


def test_parallel_transport_honours_the_starting_normal():
    T, N, B = fr.parallel_transport(WOBBLY, normal=[0.0, 0.0, 2.0])
    want = np.array([0.0, 0.0, 2.0]) - 2.0 * T[0, 2] * T[0]
    np.testing.assert_allclose(N[0], want / np.linalg.norm(want), atol=1e-12)
    with pytest.raises(ValueError, match="parallel"):
        fr.parallel_transport(WOBBLY, normal=T[0] * 3)


def test_geodesic_reference_is_the_minimal_rotation_of_the_reference_frame():
    T, N, B = fr.geodesic_reference(KNOT, closed=True)
    up = np.argmax(T[:, 2])  # where T is closest to ẑ the frame is closest to (ẑ, x̂, ŷ)
    z = np.array([0, 0, 1.0])
    for i in (0, up, 123):
        # N_i is x̂ rotated in the plane of ẑ and T_i, by the angle between them.
        axis = np.cross(z, T[i]) / np.linalg.norm(np.cross(z, T[i]))
        angle = np.arccos(T[i] @ z)
        x = np.array([1.0, 0, 0])
        rodrigues = x * np.cos(angle) + np.cross(axis, x) * np.sin(angle) + axis * (axis @ x) * (1 - np.cos(angle))
        np.testing.assert_allclose(N[i], rodrigues, atol=1e-12)
    straight_down = np.stack([0 * np.arange(5.0), 0 * np.arange(5.0), -np.arange(5.0)], axis=1)
    with pytest.raises(ValueError, match="opposite to the reference"):
        fr.geodesic_reference(straight_down)
    fr.geodesic_reference(straight_down, reference=[0, 0, -1])


# ---------------------------------------------------------------------------------------------
# Tait's quaternion frame equation
# ---------------------------------------------------------------------------------------------
def test_tait_matrix_reproduces_the_frame_equations():
    """d/ds of the columns of R(q(s)) along q' = ½ A q, by central differences, equals the
    moving-frame equations (eq. 9's R, columns T, N, B)."""
    rng = np.random.default_rng(11)
    for _ in range(20):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        k1, k2, sigma = rng.normal(size=3)
        dq = 0.5 * fr.tait_matrix(k1, k2, sigma) @ q
        np.testing.assert_allclose(dq, 0.5 * quat_multiply(q, [0, sigma, -k2, k1]), atol=1e-14)
        assert abs(q @ dq) < 1e-14  # antisymmetry keeps q on S³
        h = 1e-5
        dR = (quat_to_matrix(q + h * dq) - quat_to_matrix(q - h * dq)) / (2 * h)
        T, N, B = quat_to_matrix(q).T
        np.testing.assert_allclose(dR[:, 0], k1 * N + k2 * B, atol=1e-8)
        np.testing.assert_allclose(dR[:, 1], -k1 * T + sigma * B, atol=1e-8)
        np.testing.assert_allclose(dR[:, 2], -k2 * T - sigma * N, atol=1e-8)
    # The matrix printed in the notes does not (so the test can fail).
    k1, k2, sigma = 0.7, -0.4, 0.3
    printed = np.array([[0, -sigma, -k2, -k1], [sigma, 0, k1, k2], [k2, -k1, 0, sigma], [k1, -k2, -sigma, 0]])
    q = np.array([0.5, 0.5, 0.5, 0.5])
    dR = (quat_to_matrix(q + 1e-5 * printed @ q / 2) - quat_to_matrix(q - 1e-5 * printed @ q / 2)) / 2e-5
    T, N, B = quat_to_matrix(q).T
    assert np.abs(dR[:, 0] - (k1 * N + k2 * B)).max() > 0.1


def test_tait_normalizes_q0_and_checks_coefficient_callables():
    s = np.linspace(0.0, 1.0, 11)
    q0 = np.array([1 + 5e-10, 0.0, 0.0, 0.0])  # within UNIT_TOLERANCE, not exactly unit
    q = fr.tait(q0, 0.0, 0.0, 0.0, s)
    assert np.array_equal(q[0], [1.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-15)
    with pytest.raises(ValueError, match=r"^q0: not a unit quaternion"):
        fr.tait([1 + 1e-6, 0, 0, 0], 0.0, 0.0, 0.0, s)
    with pytest.raises(ValueError, match=r"^k1: the callable returned nan at s = 0\.5"):
        fr.tait([1, 0, 0, 0], lambda x: np.nan if x >= 0.5 else 1.0, 0.0, 0.0, s)
    with pytest.raises(ValueError, match=r"^k2: the callable returned .* expected one real number"):
        fr.tait([1, 0, 0, 0], 0.0, lambda x: np.array([x, x]), 0.0, s)
    with pytest.raises(ValueError, match=r"^sigma: the callable returned 'x'"):
        fr.tait([1, 0, 0, 0], 0.0, 0.0, lambda x: "x", s)
    with pytest.raises(ValueError, match=r"^sigma: the callable returned inf"):
        fr.tait([1, 0, 0, 0], 0.0, 0.0, lambda x: np.inf, s)
    with pytest.raises(ValueError, match=r"^k1: expected a callable, a number or 11 finite values"):
        fr.tait([1, 0, 0, 0], "fast", 0.0, 0.0, s)
    with pytest.raises(ValueError, match=r"^s: non-finite"):
        fr.tait([1, 0, 0, 0], 0.0, 0.0, 0.0, [0.0, np.nan, 1.0])


def test_tait_matrix_rejects_bad_coefficients():
    np.testing.assert_array_equal(fr.tait_matrix([1.0, 2.0], 0.0, 0.0)[:, 3, 0], [1.0, 2.0])
    with pytest.raises(ValueError, match=r"^k1: non-finite value nan"):
        fr.tait_matrix(np.nan, 0, 0)
    with pytest.raises(ValueError, match=r"^sigma: non-finite value inf"):
        fr.tait_matrix(0, 0, np.inf)
    with pytest.raises(ValueError, match=r"^k2: expected real numbers"):
        fr.tait_matrix(0, "a", 0)
    with pytest.raises(ValueError, match=r"batch axes do not broadcast"):
        fr.tait_matrix([1.0, 2.0], [1.0, 2.0, 3.0], 0)


def test_tait_with_frenet_curvatures_reproduces_the_helix_frenet_frame():
    _, (T, N, B), s = helix(200)
    q0 = fr.frame_quaternions(T, N, B)[0]
    for k1 in (KAPPA, lambda x: np.full_like(x, KAPPA)):  # constants and callables
        q = fr.tait(q0, k1, 0.0, TAU, s)
        np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-14)
        R = quat_to_matrix(q)
        np.testing.assert_allclose(R, np.stack([T, N, B], axis=-1), atol=1e-6)
    # and the curvatures measured from the Frenet frame are κ, 0, τ
    k1, k2, sigma = fr.frame_curvatures(T, N, B, s)
    np.testing.assert_allclose(k1, KAPPA, atol=1e-12)
    np.testing.assert_allclose(k2, 0.0, atol=1e-12)
    np.testing.assert_allclose(sigma, TAU, atol=1e-12)


def test_tait_with_zero_twist_reproduces_parallel_transport():
    points = WOBBLY
    s = fr.arclength(points)
    T, N, B = fr.parallel_transport(points)
    k1, k2, sigma = fr.frame_curvatures(T, N, B, s)
    np.testing.assert_allclose(sigma, 0.0, atol=1e-10)
    q = fr.tait(fr.frame_quaternions(T, N, B)[0], k1, k2, 0.0, s)
    R = quat_to_matrix(q)
    err = np.abs(R - np.stack([T, N, B], axis=-1)).max()
    assert err < 3e-3
    # halving the spacing shrinks the error about fourfold (second order)
    fine = np.stack([np.cos(np.linspace(0, 5, 599)), np.sin(2 * np.linspace(0, 5, 599)),
                     np.linspace(0, 5, 599) ** 1.5 / 4], axis=1)
    s2 = fr.arclength(fine)
    T2, N2, B2 = fr.parallel_transport(fine)
    q2 = fr.tait(fr.frame_quaternions(T2, N2, B2)[0], *fr.frame_curvatures(T2, N2, B2, s2)[:2], 0.0, s2)
    err2 = np.abs(quat_to_matrix(q2) - np.stack([T2, N2, B2], axis=-1)).max()
    assert err2 < err / 3


def test_quaternion_curve_is_sign_continuous_and_rebuilds_the_frame():
    T, N, B = fr.frenet(KNOT, closed=True)
    q = fr.frame_quaternions(T, N, B)
    assert np.all(np.sum(q[1:] * q[:-1], axis=1) > 0.9)
    np.testing.assert_allclose(quat_to_matrix(q), np.stack([T, N, B], axis=-1), atol=1e-12)
    # The Frenet frame closes in SO(3); its quaternion loop closes possibly after twice around.
    loop = fr.quaternion_loop(q)
    assert len(loop) in (len(q), 2 * len(q))
    assert np.dot(loop[-1], loop[0]) > 0.9


# ---------------------------------------------------------------------------------------------
# The closed minimal-length frame
# ---------------------------------------------------------------------------------------------
def seam_error(T, N, rule) -> float:
    """Transports the last frame across the seam, turns it by the twist ``rule`` predicts for the
    seam segment, and returns the distance to the first frame's normal."""
    moved = fr.minimal_rotation(T[-1], T[0], N[-1])
    a = rule
    turned = np.cos(a) * moved + np.sin(a) * np.cross(T[0], moved)
    return float(np.linalg.norm(turned - N[0]))


def test_optimal_periodic_closes_on_the_35_torus_knot():
    T0, N0, _ = fr.parallel_transport(KNOT, closed=True)
    holonomy = -fr.twist_angles(*fr.parallel_transport(KNOT, closed=True), closed=True)[-1]
    assert abs(holonomy) > 0.5
    assert seam_error(T0, N0, 0.0) > 0.4  # parallel transport does not close
    s = fr.arclength(KNOT, closed=True)
    ell = np.diff(s)
    # Linear twist: a constant twist per unit length on every segment, the seam included.
    T, N, B = fr.optimal_periodic(KNOT, method="arclength")
    twist = fr.twist_angles(T, N, B, closed=True)
    rate = np.median(twist[:-1] / ell[:-1])
    np.testing.assert_allclose(rate * s[-1], -holonomy, atol=1e-9)
    assert seam_error(T, N, rate * ell[-1]) < 1e-6
    # Minimal quaternion length: sin(Δ_i/2) = μ tan(θ_i/2) on every segment, the seam included.
    T, N, B = fr.optimal_periodic(KNOT)
    twist = fr.twist_angles(T, N, B, closed=True)
    theta = np.arccos(np.clip(np.sum(T * np.roll(T, -1, axis=0), axis=1), -1, 1))
    mu = np.median(np.sin(twist[:-1] / 2) / np.tan(theta[:-1] / 2))
    assert seam_error(T, N, 2 * np.arcsin(mu * np.tan(theta[-1] / 2))) < 1e-6
    np.testing.assert_allclose(np.sin(twist / 2), mu * np.tan(theta / 2), atol=1e-9)
    np.testing.assert_allclose(twist.sum(), -holonomy, atol=1e-9)


def test_optimal_periodic_minimizes_quaternion_length():
    T0, N0, B0 = fr.parallel_transport(KNOT, closed=True)
    opt = fr.optimal_periodic(KNOT)
    lin = fr.optimal_periodic(KNOT, method="arclength")
    L_opt = fr.quaternion_length(fr.frame_quaternions(*opt), closed=True)
    L_lin = fr.quaternion_length(fr.frame_quaternions(*lin), closed=True)
    L_pt = fr.quaternion_length(fr.frame_quaternions(T0, N0, B0), closed=True)
    assert L_opt <= L_lin < L_pt
    # ⟨q_i, q_{i+1}⟩ = cos(θ_i/2) cos(Δ_i/2) exactly
    theta = np.arccos(np.clip(np.sum(opt[0] * np.roll(opt[0], -1, axis=0), axis=1), -1, 1))
    twist = fr.twist_angles(*opt, closed=True)
    np.testing.assert_allclose(L_opt, np.sum(np.arccos(np.cos(theta / 2) * np.cos(twist / 2))), rtol=1e-10)
    # Any closure-preserving change of the twist angles φ_i makes it longer.
    phi = np.arctan2(np.sum(opt[1] * B0, axis=1), np.sum(opt[1] * N0, axis=1))
    rng = np.random.default_rng(5)
    for scale in (1e-2, 1e-3):
        d = rng.normal(size=len(phi)) * scale
        N = np.cos(phi + d)[:, None] * N0 + np.sin(phi + d)[:, None] * B0
        assert fr.quaternion_length(fr.frame_quaternions(T0, N, np.cross(T0, N)), closed=True) > L_opt


# ---------------------------------------------------------------------------------------------
# Tubes
# ---------------------------------------------------------------------------------------------
def induced_faces(simplices: np.ndarray) -> dict:
    """{sorted face: [±1, …]}: each (k−1)-face of each k-simplex with its induced orientation
    (−1)^j · parity(sorting permutation) for the face opposite vertex j."""
    faces: dict = {}
    for simplex in simplices:
        for j in range(len(simplex)):
            face = np.delete(simplex, j)
            order = np.argsort(face)
            parity = np.linalg.det(np.eye(len(face))[order])
            faces.setdefault(tuple(face[order]), []).append(int(round((-1) ** j * parity)))
    return faces


def assert_closed_oriented(simplices):
    faces = induced_faces(simplices)
    counts = np.array([len(v) for v in faces.values()])
    assert np.all(counts == 2), f"{np.sum(counts != 2)} faces not shared by exactly two simplices"
    assert all(sum(v) == 0 for v in faces.values()), "inconsistent orientation"


def nearest_curve_point(x, curve):
    return curve[np.argmin(np.linalg.norm(x[:, None, :] - curve[None], axis=2), axis=1)]


@pytest.mark.parametrize("closed", [True, False])
def test_tube_3d_is_closed_and_faces_outward(closed):
    points = KNOT[::4] if closed else helix(60)[0]
    T, N, B = fr.optimal_periodic(points) if closed else fr.parallel_transport(points)
    radius = 0.05
    V, S = fr.tube_3d(points, T, N, B, radius=radius, sides=8, closed=closed)
    assert S.dtype == np.int64 and S.min() >= 0 and S.max() < len(V)
    assert_closed_oriented(S)
    tri = V[S]
    normal = ndtrace.geometry.generalized_cross(tri[:, 1:] - tri[:, :1])
    centre = tri.mean(axis=1)
    body = 2 * 8 * (len(points) if closed else len(points) - 1)
    away = centre[:body] - nearest_curve_point(centre[:body], points)
    assert np.all(np.sum(normal[:body] * away, axis=1) > 0)
    if not closed:
        np.testing.assert_allclose(normal[body:body + 8] / np.linalg.norm(normal[body:body + 8], axis=1)[:, None],
                                   np.broadcast_to(-T[0], (8, 3)), atol=1e-12)
    # Divergence theorem: Σ det[x0 x1 x2]/6 is the enclosed volume, ≈ (octagon area)·length.
    volume = np.sum(np.linalg.det(tri)) / 6
    length = fr.arclength(points, closed=closed)[-1]
    octagon = 8 / 2 * radius**2 * np.sin(2 * np.pi / 8)
    np.testing.assert_allclose(volume, octagon * length, rtol=0.02)


def test_tube_3d_sides_layout_and_aspect():
    points = KNOT[::8]
    T, N, B = fr.optimal_periodic(points)
    V, S = fr.tube_3d(points, T, N, B, radius=0.1, sides=6, closed=True, aspect=0.25)
    ring = V[:6] - points[0]
    np.testing.assert_allclose(ring @ N[0], 0.1 * np.cos(2 * np.pi * np.arange(6) / 6), atol=1e-12)
    np.testing.assert_allclose(ring @ B[0], 0.025 * np.sin(2 * np.pi * np.arange(6) / 6), atol=1e-12)
    k = 2 * (3 * 6 + 4)  # segment 3, side 4: between ring vertices 4 and 5 of rings 3 and 4
    assert set(S[k]) | set(S[k + 1]) == {3 * 6 + 4, 3 * 6 + 5, 4 * 6 + 4, 4 * 6 + 5}


def quaternion_curve(samples: int):
    return fr.quaternion_loop(fr.frame_quaternions(*fr.optimal_periodic(fr.torus_knot(3, 5, samples))))


@pytest.mark.parametrize("closed", [True, False])
def test_tube_4d_boundary_is_a_closed_outward_3_manifold(closed):
    # (the radius stays below the curve's smallest radius of curvature, 0.045, so the tube is
    # embedded and "outward" is well defined everywhere)
    curve = quaternion_curve(100) if closed else quaternion_curve(100)[:25]
    radius = 0.03
    V, S = fr.tube_4d(curve, radius, closed=closed)
    assert V.shape[1] == 4 and S.shape[1] == 4 and S.max() < len(V)
    segments = len(curve) if closed else len(curve) - 1
    prisms = 60 * segments
    assert len(S) == prisms + (0 if closed else 40)
    assert_closed_oriented(S)
    # Ring vertices lie at distance `radius` from their curve point, in its normal space.
    T = fr.tangents(curve, closed)
    ring = V[: 12 * len(curve)].reshape(len(curve), 12, 4) - curve[:, None, :]
    np.testing.assert_allclose(np.linalg.norm(ring, axis=2), radius, rtol=1e-12)
    np.testing.assert_allclose(np.einsum("nvd,nd->nv", ring, T), 0.0, atol=1e-12)
    # Outward: each tetrahedron's normal (eq. 6) points away from the curve.
    tet = V[S]
    normal = ndtrace.geometry.generalized_cross(tet[:, 1:] - tet[:, :1])
    centre = tet[:prisms].mean(axis=1)
    midpoint = np.repeat(0.5 * (curve + np.roll(curve, -1, axis=0))[:segments], 60, axis=0)
    assert np.all(np.sum(normal[:prisms] * (centre - midpoint), axis=1) > 0)
    if not closed:
        caps = normal[prisms:] / np.linalg.norm(normal[prisms:], axis=1)[:, None]
        np.testing.assert_allclose(caps[:20], np.broadcast_to(-T[0], (20, 4)), atol=1e-12)
        np.testing.assert_allclose(caps[20:], np.broadcast_to(T[-1], (20, 4)), atol=1e-12)
    # Divergence theorem in 4D: the cones from the origin over the outward facets have volumes
    # det[0; x0 … x3]/4! = −det[x0 … x3]/24 = x0·N/24 (N = the eq. 6 normal, the cofactors of
    # the last column of [e1 e2 e3 | ·]); they add up to the enclosed 4-volume ≈ (icosahedron
    # volume)·length for a thin tube.
    volume = -np.sum(np.linalg.det(tet)) / 24
    V0, F0 = fr.icosphere(0)
    icosahedron = np.sum(np.linalg.det(V0[F0])) / 6 * radius**3
    length = fr.arclength(curve, closed=closed)[-1]
    np.testing.assert_allclose(volume, icosahedron * length, rtol=0.03)


def test_tube_4d_closes_without_a_seam():
    curve = quaternion_curve(60)
    V, _ = fr.tube_4d(curve, 0.05, closed=True)
    rings = V.reshape(len(curve), 12, 4) - curve[:, None, :]  # closed: no cap centres
    step = np.linalg.norm(np.diff(np.concatenate([rings, rings[:1]]), axis=0), axis=2).max(axis=1)
    assert step[-1] <= 1.5 * np.median(step[:-1])  # the seam is an ordinary step
    # The uncorrected parallel transport would jump there: its holonomy is far from identity.
    T = fr.tangents(curve, closed=True)
    basis = np.linalg.qr(np.column_stack([T[0], np.eye(4)]))[0][:, 1:].T
    moved = basis
    for i in range(len(curve)):
        moved = fr.minimal_rotation(T[i], T[(i + 1) % len(curve)], moved)
    assert np.abs(moved @ basis.T - np.eye(3)).max() > 0.1


def test_tube_4d_starts_from_the_completed_frame_and_checks_the_radius():
    curve = quaternion_curve(60)[:20]
    V, _ = fr.tube_4d(curve, 0.03)
    T = fr.tangents(curve)
    first = rot.frame(T[:1])  # columns T_0, F_0,1, F_0,2, F_0,3 with det +1
    dirs, _ = fr.icosphere(0)
    np.testing.assert_allclose(V[:12], curve[0] + 0.03 * dirs @ first[:, 1:].T, atol=1e-15)
    extent = np.linalg.norm(np.ptp(curve, axis=0))
    for radius in (1e200, 2 * extent):
        with pytest.raises(ValueError, match=r"^radius: expected a radius below the curve's extent"):
            fr.tube_4d(curve, radius)
    with pytest.raises(ValueError, match=r"^radius: .*degenerate"):
        fr.tube_4d(curve, 1e-300)
    with pytest.raises(ValueError, match=r"^radius: expected a finite number > 0"):
        fr.tube_4d(curve, "thin")


def test_icosphere_is_a_closed_outward_sphere():
    for level in (0, 1):
        V, F = fr.icosphere(level)
        assert len(F) == 20 * 4**level and len(V) == 10 * 4**level + 2
        np.testing.assert_allclose(np.linalg.norm(V, axis=1), 1.0)
        assert_closed_oriented(F)
        assert np.all(np.linalg.det(V[F]) > 0)


# ---------------------------------------------------------------------------------------------
# Bad input
# ---------------------------------------------------------------------------------------------
GOOD = KNOT[::10]


@pytest.mark.parametrize("call,match", [
    (lambda: fr.tangents(np.zeros((2, 3))), "at least 3 samples"),
    (lambda: fr.frenet(np.ones((5, 2))), r"shape \(n, 3\)"),
    (lambda: fr.frenet(np.ones((5, 3, 1))), "shape"),
    (lambda: fr.parallel_transport([[0, 0, 0], [1, 0, np.nan], [2, 0, 0]]), "sample 1 is not finite"),
    (lambda: fr.parallel_transport([[0, 0, 0], [1, 0, 0], [1, 0, 0], [2, 1, 0]]), "samples 1 and 2 coincide"),
    (lambda: fr.optimal_periodic(np.concatenate([GOOD, GOOD[:1]])), "must not repeat its first point"),
    (lambda: fr.optimal_periodic(GOOD, method="fast"), "method"),
    (lambda: fr.parallel_transport([[0, 0, 0], [1, 0, 0], [2, 0, 0], [1, 0, 0], [0, 0, 1]]), "sample 2 .*doubles back"),
    (lambda: fr.parallel_transport(GOOD, normal=[1, 2]), "normal"),
    (lambda: fr.geodesic_reference(GOOD, reference=[0, 0, 0]), "reference"),
    (lambda: fr.geodesic_reference(GOOD, reference="z"), r"^reference: expected real numbers"),
    (lambda: fr.geodesic_reference(GOOD, reference=[0, 0, np.nan]), r"^reference: non-finite"),
    (lambda: fr.parallel_transport(GOOD, normal="up"), r"^normal: expected real numbers"),
    (lambda: fr.frenet("points"), r"^points: expected a real"),
    (lambda: fr.frame_quaternions(*fr.frenet(GOOD, closed=True)[:2], "B"), r"^B: expected real numbers"),
    (lambda: fr.quaternion_length([[1, 0, 0, 0], [1 + 1e-6, 0, 0, 0]]), r"^q: not a unit quaternion .* at batch index 1"),
    (lambda: fr.frame_curvatures(*fr.frenet(GOOD, closed=True), np.r_[np.arange(len(GOOD)), np.nan], closed=True),
     r"^s: non-finite"),
    (lambda: fr.frame_quaternions(*fr.frenet(GOOD, closed=True)[:2], -fr.frenet(GOOD, closed=True)[2]),
     "right-handed"),
    (lambda: fr.frame_quaternions(np.ones((4, 3)), np.ones((4, 3)), np.ones((5, 3))), "shapes differ|orthonormal"),
    (lambda: fr.tait([1, 0, 0, 0], 1.0, 0.0, 0.0, [0, 1, 1]), "increasing"),
    (lambda: fr.tait([2, 0, 0, 0], 1.0, 0.0, 0.0, [0, 1, 2]), "unit quaternion"),
    (lambda: fr.tait([1, 0, 0, 0], [1.0, 2.0], 0.0, 0.0, [0, 1, 2]), "k1"),
    (lambda: fr.quaternion_length(np.ones((4, 4))), "not a unit quaternion"),
    (lambda: fr.torus_knot(3, 5, 100, R=1.0, r=1.5), "smaller than R"),
    (lambda: fr.torus_knot(3, 0, 100), "q"),
    (lambda: fr.tube_3d(GOOD, *fr.frenet(GOOD, closed=True), radius=0.0), "radius"),
    (lambda: fr.tube_3d(GOOD, *fr.frenet(GOOD, closed=True), radius=0.1, sides=2), "sides"),
    (lambda: fr.tube_3d(GOOD[:-1], *fr.frenet(GOOD, closed=True), radius=0.1), "frames"),
    (lambda: fr.tube_4d(GOOD, 0.1), r"shape \(n, 4\)"),
    (lambda: fr.tube_4d(np.ones((5, 4)) * np.arange(5)[:, None], -1.0), "radius"),
    (lambda: fr.frame_curvatures(*fr.frenet(GOOD, closed=True), np.arange(len(GOOD)), closed=True), "arclengths"),
    (lambda: fr.frame_curvatures(*fr.frenet(GOOD, closed=True), -np.arange(len(GOOD))), "arclengths"),
])
def test_bad_input_is_a_clear_value_error(call, match):
    with pytest.raises(ValueError, match=match):
        call()


# ---------------------------------------------------------------------------------------------
# The example scenes (also rendered by tests/test_golden.py and docs/gallery/render_gallery.py)
# ---------------------------------------------------------------------------------------------
def small_render(name: str, resolution: int):
    scene = runpy.run_path(os.path.join(ROOT, "scenes", f"{name}.py"))["scene"]()
    data = scene.to_dict()
    data["camera"]["resolution"] = resolution
    data["render"]["samples"] = 1
    data["render"]["mode"] = "primitive_id"
    return scene, ndtrace.trace(ndtrace.load_dict(data))


def test_torus_knot_frames_scene_shows_three_knots_in_two_colours():
    scene, retina = small_render("torus_knot_frames", 64)
    assert scene.dim == 3 and len(scene.to_dict()["objects"]) == 6
    hit = retina.hit
    # Three knots: top left, top right, bottom centre; the corners of the picture stay empty.
    quads = {"top-left": hit[:30, :30], "top-right": hit[:30, 34:], "bottom": hit[34:, 16:48]}
    for name, part in quads.items():
        assert 0.1 < part.mean() < 0.7, name
    assert not hit[58:, :6].any() and not hit[58:, 58:].any()
    # Both faces of each ribbon (the +B and −B objects) are seen.
    seen = set(np.unique(retina.object_id[hit]))
    assert seen == set(range(6))


def test_quaternion_frame_curve_scene_images_a_thin_closed_tube():
    scene, retina = small_render("quaternion_frame_curve", 24)
    assert scene.dim == 4 and retina.rgba.shape == (24, 24, 24, 4)
    hit = retina.hit
    # A thin tube: a small fraction of the retina volume, but seen from every side of the cube
    # (it is a curve winding around S³, not a blob).
    assert 0.005 < hit.mean() < 0.15
    for axis in range(3):
        shadow = hit.any(axis=axis)
        assert 0.05 < shadow.mean() < 0.6
    assert len(np.unique(retina.object_id[hit])) == 8  # every colour band is visible
