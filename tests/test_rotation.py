"""Tests of ``ndtrace.rotation`` (course notes Part I(B) "N-Dimensional Rotations", eqs. 5, 6, 9
and the 4D quaternion form) against independent references: numpy linear algebra, quaternion
products written out here, ``scipy.spatial.transform.Rotation`` and the scene camera.

Random inputs come from ``numpy.random.default_rng`` with a fixed seed per test and dimension;
random rotations from ``scipy.stats.special_ortho_group``.
"""

from __future__ import annotations

import math
import re
import tomllib
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation as SciRotation
from scipy.stats import special_ortho_group

import ndtrace
from ndtrace import rotation as rot

DIMS = list(range(2, 9))
DOCS = Path(__file__).resolve().parents[1] / "docs" / "scene-format.md"


def rng_for(seed: int, n: int) -> np.random.Generator:
    return np.random.default_rng(1000 * seed + n)


def random_rotations(n: int, count: int, seed: int) -> np.ndarray:
    return special_ortho_group.rvs(n, size=count, random_state=seed).reshape(count, n, n)


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def random_units(rng, shape) -> np.ndarray:
    return unit(rng.normal(size=shape))


def assert_rotations(m: np.ndarray, tol: float = 1e-12) -> None:
    n = m.shape[-1]
    np.testing.assert_allclose(np.swapaxes(m, -1, -2) @ m, np.broadcast_to(np.eye(n), m.shape), atol=tol)
    np.testing.assert_allclose(np.linalg.det(m), 1.0, atol=tol)


def angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle between vectors along the last axis, accurate at 0 and π."""
    c = np.sum(a * b, -1)
    return np.arctan2(np.linalg.norm(b - c[..., None] * a, axis=-1), c)


def qmul(a, b):
    """The notes' quaternion product, written out independently (scalar first)."""
    a0, a1, a2, a3 = np.moveaxis(np.asarray(a, float), -1, 0)
    b0, b1, b2, b3 = np.moveaxis(np.asarray(b, float), -1, 0)
    return np.stack([a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
                     a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
                     a0 * b2 + a2 * b0 + a3 * b1 - a1 * b3,
                     a0 * b3 + a3 * b0 + a1 * b2 - a2 * b1], -1)


def qconj(q):
    return np.asarray(q, float) * np.array([1, -1, -1, -1])


def pure(v):
    return np.concatenate([np.zeros(v.shape[:-1] + (1,)), v], -1)


# ---------------------------------------------------------------------------------------------
# Plane rotations, compose, frames
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", DIMS)
def test_plane_rotation_turns_i_toward_j(n):
    for i in range(n):
        for j in range(n):
            if i == j:
                continue
            m = rot.plane(n, i, j, 0.4)
            assert m.shape == (n, n) and m.dtype == np.float64
            assert_rotations(m)
            image = m[:, i]  # R e_i
            assert image[i] == pytest.approx(math.cos(0.4)) and image[j] == pytest.approx(math.sin(0.4))
            assert np.count_nonzero(np.abs(m - np.eye(n)) > 0) == 4
    thetas = np.linspace(-3, 3, 6).reshape(2, 3)
    stack = rot.plane(n, 0, n - 1, thetas)
    assert stack.shape == (2, 3, n, n)
    np.testing.assert_allclose(stack[1, 2], rot.plane(n, 0, n - 1, 3.0))


@pytest.mark.parametrize("n", DIMS)
def test_compose_applies_the_first_rotation_first(n):
    rs = random_rotations(n, 5, seed=n)
    want = np.eye(n)
    for r in rs:
        want = r @ want
    np.testing.assert_allclose(rot.compose(rs), want, atol=1e-13)
    assert_rotations(rot.compose(rs))
    # Batched over leading axes, and the empty product.
    batch = np.stack([rs[:2], rs[2:4]])
    np.testing.assert_allclose(rot.compose(batch)[1], rs[3] @ rs[2], atol=1e-14)
    np.testing.assert_array_equal(rot.compose(np.zeros((0, n, n))), np.eye(n))
    if n >= 3:
        # x → y then y → z carries x to z.
        x = rot.compose([rot.plane(n, 0, 1, np.pi / 2), rot.plane(n, 1, 2, np.pi / 2)])[:, 0]
        assert x[2] == pytest.approx(1.0)


@pytest.mark.parametrize("n", DIMS)
def test_frames_are_right_handed_gram_schmidt(n):
    rng = rng_for(1, n)
    for k in range(n):
        v = rng.normal(size=(6, k, n))
        f = rot.frame(v)
        assert f.shape == (6, n, n)
        assert_rotations(f)
        # numpy QR of the given vectors, with signs made positive along the diagonal.
        if k:
            qmat, r = np.linalg.qr(np.swapaxes(v, -1, -2))
            qmat = qmat * np.sign(np.diagonal(r, axis1=-2, axis2=-1))[..., None, :]
            np.testing.assert_allclose(f[..., :k], qmat, atol=1e-12)
    full = special_ortho_group.rvs(n, random_state=n) if n > 1 else np.eye(n)
    np.testing.assert_allclose(rot.frame(full.T), full, atol=1e-12)
    left = full.T.copy()
    left[0] *= -1
    with pytest.raises(ValueError, match="left-handed"):
        rot.frame(left)
    with pytest.raises(ValueError, match=r"vectors\[1\]: .*dependent"):
        rot.frame([full[:, 0], 2 * full[:, 0]])
    with pytest.raises(ValueError, match="K ≤ N"):
        rot.frame(np.ones((n + 1, n)))


@pytest.mark.parametrize("n", DIMS)
def test_frame_fills_missing_axes_lowest_index_first(n):
    eye = np.eye(n)
    assert np.array_equal(rot.frame(np.zeros((0, n))), eye)
    assert np.array_equal(rot.frame(eye[:1]), eye)
    assert np.array_equal(rot.frame(eye[:2]), eye)
    # One vector: the second column is the coordinate axis least aligned with it.
    a = unit(np.arange(1.0, n + 1) * (-1) ** np.arange(n))
    f = rot.frame(a[None])
    want = eye[0] - a[0] * a
    np.testing.assert_allclose(f[:, 1], want / np.linalg.norm(want), atol=1e-14)
    assert_rotations(f)


@pytest.mark.parametrize("n", DIMS)
def test_rotation_between_is_the_minimal_rotation(n):
    rng = rng_for(12, n)
    a, b = random_units(rng, (2, 5, n))
    m = rot.rotation_between(a, b)
    assert m.shape == (5, n, n)
    assert_rotations(m)
    np.testing.assert_allclose(np.einsum("bij,bj->bi", m, a), b, atol=1e-14)
    # The closed form R v = v − (a + b)((a + b)·v)/(1 + a·b) + 2b(a·v), written out here.
    v = rng.normal(size=(5, n))
    s, c = a + b, np.sum(a * b, -1, keepdims=True)
    formula = v - s * np.sum(s * v, -1, keepdims=True) / (1 + c) + 2 * b * np.sum(a * v, -1, keepdims=True)
    np.testing.assert_allclose(np.einsum("bij,bj->bi", m, v), formula, atol=1e-13)
    # Broadcasting a single a against a batch of b.
    np.testing.assert_allclose(rot.rotation_between(a[0], b), rot.rotation_between(np.broadcast_to(a[0], b.shape), b))
    # Antipodal: by π in the plane of a and its least aligned axis (frame([a])[:, 1]).
    m = rot.rotation_between(a[0], -a[0])
    assert_rotations(m)
    e = rot.frame(a[:1])[:, 1]
    np.testing.assert_allclose(m @ a[0], -a[0], atol=1e-14)
    np.testing.assert_allclose(m @ e, -e, atol=1e-14)
    with pytest.raises(ValueError, match=r"^b: not a unit vector .* at batch index 1$"):
        rot.rotation_between(a[:2], np.stack([b[0], 2 * b[1]]))
    with pytest.raises(ValueError, match=rf"^b: expected shape \(\.\.\., {n}\) to match a"):
        rot.rotation_between(a[0], np.ones(n + 1))


def test_tolerances_are_the_cores():
    assert rot.UNIT_TOLERANCE == 1e-9 and rot.ORTHOGONALITY_TOLERANCE == 1e-9
    assert rot.SCENE_UNIT_TOLERANCE == 1e-3
    rot.quat_to_matrix([1 + 0.9 * rot.UNIT_TOLERANCE, 0, 0, 0])
    with pytest.raises(ValueError, match="not a unit quaternion"):
        rot.quat_to_matrix([1 + 2 * rot.UNIT_TOLERANCE, 0, 0, 0])


@pytest.mark.parametrize("n", range(3, 9))
def test_look_at_is_the_scene_camera(n):
    rng = rng_for(2, n)
    position = rng.normal(size=n) * 3
    target = rng.normal(size=n)
    up = rng.normal(size=(n - 2, n))
    scene = ndtrace.load_dict({
        "dim": n,
        "camera": {"position": position, "look_at": target, "up": up, "fov": 40, "resolution": 2},
        "objects": [{"shape": "simplex"}],
    })
    camera = np.array(scene.compiled().camera_orientation)
    m = rot.look_at(position, target, up)
    np.testing.assert_array_equal(m, camera)
    assert np.linalg.det(m) == pytest.approx(-1.0)
    np.testing.assert_allclose(m[:, -1], unit(target - position))
    with pytest.raises(ValueError, match="target: equals position"):
        rot.look_at(position, position, up)
    with pytest.raises(ValueError, match=r"up: expected shape"):
        rot.look_at(position, target, up[:0] if n > 3 else np.ones((2, n)))


def test_look_at_3d_is_the_usual_camera():
    m = rot.look_at([0, 0, 5], [0, 0, 0], [0, 1, 0])
    np.testing.assert_array_equal(m, [[1, 0, 0], [0, 1, 0], [0, 0, -1]])


# ---------------------------------------------------------------------------------------------
# Rolling ball
# ---------------------------------------------------------------------------------------------


def notes_rolling_matrix(d, radius, angle):
    """M_N as printed in the notes (eq. 5), written out independently."""
    n = len(d) + 1
    r = np.linalg.norm(d)
    if r == 0:
        return np.eye(n)
    nh = d / r
    if angle == "course":
        D = math.hypot(radius, r)
        c, s = radius / D, r / D
    else:
        c, s = math.cos(r / radius), math.sin(r / radius)
    m = np.eye(n)
    m[:-1, :-1] -= (1 - c) * np.outer(nh, nh)
    m[:-1, -1] = s * nh
    m[-1, :-1] = -s * nh
    m[-1, -1] = c
    return m


@pytest.mark.parametrize("n", DIMS)
@pytest.mark.parametrize("angle", ["course", "arc"])
def test_rolling_ball_is_the_conjugated_plane_rotation(n, angle):
    rng = rng_for(3, n)
    d = rng.normal(size=(20, n - 1))
    radius = 1.7
    m = rot.rolling_ball(d, radius, angle)
    assert m.shape == (20, n, n)
    assert_rotations(m)
    for di, mi in zip(d, m):
        np.testing.assert_allclose(mi, notes_rolling_matrix(di, radius, angle), atol=1e-14)
        r = np.linalg.norm(di)
        theta = math.atan2(r, radius) if angle == "course" else r / radius
        # Conjugation: a rotation of the first N−1 axes taking e_1 to n̂ (from numpy's QR),
        # around R_0 = plane(N−1 → 0, θ), the notes' north pole turned toward x.
        basis = np.eye(n)
        if n > 2:
            q, _ = np.linalg.qr(np.column_stack([di / r, rng.normal(size=(n - 1, n - 2))]))
            q[:, 0] *= np.sign(q[:, 0] @ di)
            if np.linalg.det(q) < 0:
                q[:, -1] *= -1
            basis[:-1, :-1] = q
            r0 = rot.plane(n, n - 1, 0, theta)
        else:
            r0 = rot.plane(n, n - 1, 0, math.copysign(theta, di[0]))
        np.testing.assert_allclose(mi, basis @ r0 @ basis.T, atol=1e-13)
    np.testing.assert_array_equal(rot.rolling_ball(np.zeros(n - 1), 2.0), np.eye(n))


@pytest.mark.parametrize("n", range(3, 9))
def test_small_controller_loops_rotate_against_their_sense(n):
    """Commutator trick: +e_i, +e_j, −e_i, −e_j accumulated as M_4 M_3 M_2 M_1 gives
    plane(i, j, −ε²/R²): axis j turns toward axis i."""
    eps, radius = 1e-3, 1.5
    for i in range(n - 1):
        for j in range(n - 1):
            if i == j:
                continue
            steps = np.zeros((4, n - 1))
            steps[0, i], steps[1, j], steps[2, i], steps[3, j] = eps, eps, -eps, -eps
            net = rot.compose(rot.rolling_ball(steps, radius, "arc"))
            area = eps ** 2 / radius ** 2
            np.testing.assert_allclose(net, rot.plane(n, i, j, -area), atol=3 * eps * area)
            assert net[j, i] / area == pytest.approx(-1.0, rel=1e-2)
            # The reversed loop turns the other way.
            back = rot.compose(rot.rolling_ball(steps[[1, 0, 3, 2]], radius, "arc"))
            assert back[j, i] / area == pytest.approx(1.0, rel=1e-2)


def test_rolling_ball_course_numbers():
    m = rot.rolling_ball([3.0, 0.0], 4.0)  # r = 3, R = 4: c = 4/5, s = 3/5
    np.testing.assert_allclose(m, [[0.8, 0, 0.6], [0, 1, 0], [-0.6, 0, 0.8]], atol=1e-15)


# ---------------------------------------------------------------------------------------------
# Slerp and nested spheres
# ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("n", DIMS)
def test_slerp_has_constant_angular_speed(n):
    rng = rng_for(4, n)
    a, b = random_units(rng, (30, n)), random_units(rng, (30, n))
    theta = angle(a, b)
    t = np.array([-0.2, 0.0, 0.3, 0.5, 1.0, 1.1])
    s = rot.slerp(a, b, t)
    assert s.shape == (6, 30, n)
    np.testing.assert_allclose(np.linalg.norm(s, axis=-1), 1.0, atol=1e-14)
    np.testing.assert_allclose(s[1], a, atol=1e-15)
    np.testing.assert_allclose(s[4], b, atol=1e-14)
    for p in range(6):
        for q in range(6):
            want = abs(t[q] - t[p]) * theta
            ok = want < np.pi - 1e-6  # beyond π the angle between the points wraps around
            np.testing.assert_allclose(angle(s[p], s[q])[ok], want[ok], atol=1e-12)
    # Points stay in the plane of a and b.
    for k in range(30):
        basis = np.linalg.qr(np.column_stack([a[k], b[k]]))[0]
        np.testing.assert_allclose(basis @ (basis.T @ s[:, k].T), s[:, k].T, atol=1e-13)
    one = rot.slerp(a[0], b[0], 0.25)
    assert one.shape == (n,)
    np.testing.assert_allclose(rot.slerp(a[0], a[0], 0.4), a[0])


@pytest.mark.parametrize("n", DIMS)
def test_nested_spheres_round_trip(n):
    rs = random_rotations(n, 30, seed=100 + n)
    vs = rot.to_nested_spheres(rs)
    assert [v.shape for v in vs] == [(30, k) for k in range(n, 1, -1)]
    for v in vs:
        np.testing.assert_allclose(np.linalg.norm(v, axis=-1), 1.0, atol=1e-14)
    np.testing.assert_allclose(vs[0], rs[:, :, -1], atol=1e-14, rtol=0)
    back = rot.from_nested_spheres(vs)
    np.testing.assert_allclose(back, rs, atol=1e-12, rtol=0)
    # The singular point of the chart (last axis sent to −e_N) round trips too.
    flip = rot.plane(n, 0, n - 1, np.pi)
    np.testing.assert_allclose(rot.from_nested_spheres(rot.to_nested_spheres(flip)), flip, atol=1e-15)


@pytest.mark.parametrize("n", DIMS)
def test_nested_slerp_interpolates_rotations(n):
    r0, r1 = random_rotations(n, 2, seed=200 + n)
    t = np.linspace(0, 1, 7)
    path = rot.nested_slerp(r0, r1, t)
    assert path.shape == (7, n, n)
    assert_rotations(path)
    np.testing.assert_allclose(path[0], r0, atol=1e-12)
    np.testing.assert_allclose(path[-1], r1, atol=1e-12)
    # The last axis moves along the great circle at constant speed.
    total = angle(r0[:, -1], r1[:, -1])
    np.testing.assert_allclose(angle(r0[:, -1], path[:, :, -1]), t * total, atol=1e-12)
    # Each nested vector is the slerp of the endpoints' vectors.
    v0, v1, vm = rot.to_nested_spheres(r0), rot.to_nested_spheres(r1), rot.to_nested_spheres(path[3])
    for a, b, m in zip(v0, v1, vm):
        np.testing.assert_allclose(m, rot.slerp(a, b, 0.5), atol=1e-12)


# ---------------------------------------------------------------------------------------------
# Quaternions
# ---------------------------------------------------------------------------------------------


def test_quat_to_matrix_agrees_with_scipy():
    rng = rng_for(5, 4)
    q = random_units(rng, (200, 4))
    m = rot.quat_to_matrix(q)
    assert m.shape == (200, 3, 3)
    scipy_m = SciRotation.from_quat(q[:, [1, 2, 3, 0]]).as_matrix()  # scipy is scalar-last
    np.testing.assert_allclose(m, scipy_m, atol=1e-14)
    assert_rotations(m)
    # It is V ↦ q V q̄ on pure quaternions.
    v = rng.normal(size=(200, 3))
    sandwich = qmul(qmul(q, pure(v)), qconj(q))
    np.testing.assert_allclose(np.einsum("bij,bj->bi", m, v), sandwich[:, 1:], atol=1e-14)
    np.testing.assert_allclose(rot.quat_to_matrix(q.reshape(10, 20, 4)), m.reshape(10, 20, 3, 3))


def test_matrix_to_quat_agrees_with_scipy_up_to_sign():
    rng = rng_for(6, 4)
    q = random_units(rng, (300, 4))
    q[:5, 0] = 0.0  # rotations by exactly π
    q = unit(q)
    back = rot.matrix_to_quat(rot.quat_to_matrix(q), continuous=False)
    sign = np.sign(np.sum(back * q, -1))
    np.testing.assert_allclose(back, sign[:, None] * q, atol=1e-14)
    assert np.all(back[:, 0] >= 0)
    ref = SciRotation.from_matrix(rot.quat_to_matrix(q)).as_quat()[:, [3, 0, 1, 2]]
    np.testing.assert_allclose(np.abs(np.sum(back * ref, -1)), 1.0, atol=1e-12)


def test_matrix_to_quat_sequences_are_continuous():
    # A rotation about a fixed axis through 0 … 4π: q0 ≥ 0 alone would jump at 2π.
    axis = unit(np.array([0.3, -0.5, 0.8]))
    th = np.linspace(0, 4 * np.pi, 400)
    m = SciRotation.from_rotvec(th[:, None] * axis).as_matrix()
    q = rot.matrix_to_quat(m)
    assert np.all(np.sum(q[1:] * q[:-1], -1) > 0.99)
    q_single = rot.matrix_to_quat(m, continuous=False)
    assert np.any(np.sum(q_single[1:] * q_single[:-1], -1) < 0)
    np.testing.assert_allclose(rot.quat_to_matrix(q), m, atol=1e-13)
    # Two tracks side by side (n, 2, 3, 3): continuity along axis 0 for each.
    both = np.stack([m, m[::-1]], axis=1)
    q2 = rot.matrix_to_quat(both)
    assert q2.shape == (400, 2, 4)
    assert np.all(np.sum(q2[1:] * q2[:-1], -1) > 0.99)


def test_matrix_to_quat_of_unrelated_rotations_needs_continuous_false():
    """The default reads axis 0 as a sequence; unrelated rotations want q0 ≥ 0 each."""
    m = random_rotations(3, 40, seed=21)
    independent = rot.matrix_to_quat(m, continuous=False)
    assert np.all(independent[:, 0] >= 0)
    sequence = rot.matrix_to_quat(m)
    assert np.any(sequence[:, 0] < 0)  # the documented default: signs follow the sequence
    assert np.all(np.sum(sequence[1:] * sequence[:-1], -1) >= 0)
    np.testing.assert_allclose(np.abs(sequence), np.abs(independent), atol=1e-15)


def test_quat_multiply_and_conjugate():
    rng = rng_for(7, 4)
    a, b = rng.normal(size=(50, 4)), rng.normal(size=(50, 4))
    np.testing.assert_allclose(rot.quat_multiply(a, b), qmul(a, b), atol=1e-14)
    np.testing.assert_allclose(rot.quat_conjugate(a), qconj(a))
    # i·j = k, j·i = −k; broadcasting.
    np.testing.assert_array_equal(rot.quat_multiply([0, 1, 0, 0], [0, 0, 1, 0]), [0, 0, 0, 1])
    np.testing.assert_array_equal(rot.quat_multiply([0, 0, 1, 0], [0, 1, 0, 0]), [0, 0, 0, -1])
    assert rot.quat_multiply(a[:1], b).shape == (50, 4)
    # Composition: R(a b) = R(a) R(b) for unit quaternions.
    ua, ub = unit(a), unit(b)
    np.testing.assert_allclose(rot.quat_to_matrix(rot.quat_multiply(ua, ub)),
                               rot.quat_to_matrix(ua) @ rot.quat_to_matrix(ub), atol=1e-14)


def test_so4_is_q_v_pbar():
    rng = rng_for(8, 4)
    q, p = random_units(rng, (100, 4)), random_units(rng, (100, 4))
    m = rot.so4_from_quaternions(q, p)
    assert m.shape == (100, 4, 4)
    assert_rotations(m)
    v = rng.normal(size=(100, 4))
    np.testing.assert_allclose(np.einsum("bij,bj->bi", m, v), qmul(qmul(q, v), qconj(p)), atol=1e-14)
    # p = q: 1 at [0, 0] and eq. 9 in the lower-right block.
    same = rot.so4_from_quaternions(q, q)
    np.testing.assert_allclose(same[:, 0, 0], 1.0, atol=1e-15)
    np.testing.assert_allclose(same[:, 0, 1:], 0.0, atol=1e-15)
    np.testing.assert_allclose(same[:, 1:, 0], 0.0, atol=1e-15)
    np.testing.assert_allclose(same[:, 1:, 1:], rot.quat_to_matrix(q), atol=1e-15)
    # p = 1: left multiplication (an isoclinic rotation).
    left = rot.so4_from_quaternions(q, [1, 0, 0, 0])
    np.testing.assert_allclose(np.einsum("bij,bj->bi", left, v), qmul(q, v), atol=1e-14)


def test_so4_round_trips_through_quaternion_pairs():
    rs = random_rotations(4, 200, seed=9)
    q, p = rot.quaternions_from_so4(rs)
    assert q.shape == p.shape == (200, 4)
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1.0, atol=1e-14)
    np.testing.assert_allclose(rot.so4_from_quaternions(q, p), rs, atol=1e-13)
    rng = rng_for(9, 4)
    q0, p0 = random_units(rng, (200, 4)), random_units(rng, (200, 4))
    q1, p1 = rot.quaternions_from_so4(rot.so4_from_quaternions(q0, p0))
    s = np.sign(np.sum(q0 * q1, -1))[:, None]
    np.testing.assert_allclose(q1, s * q0, atol=1e-13)
    np.testing.assert_allclose(p1, s * p0, atol=1e-13)  # the same sign for both


def test_slerp_so4_is_a_geodesic_between_frames():
    rng = rng_for(10, 4)
    for _ in range(20):
        q0, p0, q1, p1 = random_units(rng, (4, 4))
        t = np.linspace(0, 1, 6)
        q, p = rot.slerp_so4((q0, p0), (q1, p1), t)
        assert q.shape == p.shape == (6, 4)
        m = rot.so4_from_quaternions(q, p)
        assert_rotations(m)
        np.testing.assert_allclose(m[0], rot.so4_from_quaternions(q0, p0), atol=1e-14)
        np.testing.assert_allclose(m[-1], rot.so4_from_quaternions(q1, p1), atol=1e-13)
        # Same result from the other lift of the second frame.
        qn, pn = rot.slerp_so4((q0, p0), (-q1, -p1), t)
        np.testing.assert_allclose(rot.so4_from_quaternions(qn, pn), m, atol=1e-13)
        # Constant speed in both factors, and the lift with the smaller total angle.
        np.testing.assert_allclose(angle(q[0], q), t * angle(q[0], q[-1]), atol=1e-12)
        np.testing.assert_allclose(angle(p[0], p), t * angle(p[0], p[-1]), atol=1e-12)
        chosen = angle(q0, q[-1]) ** 2 + angle(p0, p[-1]) ** 2
        other = angle(q0, -q[-1]) ** 2 + angle(p0, -p[-1]) ** 2
        assert chosen <= other + 1e-12


def test_arcball_4d_maps_its_point_pairs():
    rng = rng_for(11, 4)
    a0, a1, b0, b1 = random_units(rng, (4, 30, 4))
    m = rot.arcball_4d(a0, a1, b0, b1)
    assert_rotations(m)
    np.testing.assert_allclose(np.einsum("bij,bj->bi", m, qmul(a0, qconj(b0))), qmul(a1, qconj(b1)),
                               atol=1e-14)
    # b0 = b1: a0 goes to a1.
    m = rot.arcball_4d(a0, a1, b0, b0)
    np.testing.assert_allclose(np.einsum("bij,bj->bi", m, a0), a1, atol=1e-14)
    # Equal pairs of pure quaternions: Shoemake's 3D arcball, twice the arc about u0 × u1.
    u0, u1 = random_units(rng, (2, 30, 3))
    m = rot.arcball_4d(pure(u0), pure(u1), pure(u0), pure(u1))
    np.testing.assert_allclose(m[:, 0, 0], 1.0, atol=1e-15)
    rotvec = unit(np.cross(u0, u1)) * (2 * angle(u0, u1))[:, None]
    np.testing.assert_allclose(m[:, 1:, 1:], SciRotation.from_rotvec(rotvec).as_matrix(), atol=1e-13)


# ---------------------------------------------------------------------------------------------
# Bad input
# ---------------------------------------------------------------------------------------------


def test_non_unit_quaternions_are_rejected():
    with pytest.raises(ValueError, match=r"^q: not a unit quaternion \(\|q\| = 2(\.0)?\)$"):
        rot.quat_to_matrix([2, 0, 0, 0])
    with pytest.raises(ValueError, match=r"^p: not a unit quaternion .* at batch index 1$"):
        rot.so4_from_quaternions([1, 0, 0, 0], [[1, 0, 0, 0], [0.5, 0, 0, 0]])
    with pytest.raises(ValueError, match=r"^b1: not a unit quaternion"):
        rot.arcball_4d([1, 0, 0, 0], [1, 0, 0, 0], [1, 0, 0, 0], [1, 1, 0, 0])
    with pytest.raises(ValueError, match=r"^q1: not a unit quaternion"):
        rot.slerp_so4(([1, 0, 0, 0], [1, 0, 0, 0]), ([0, 0, 0, 0], [1, 0, 0, 0]), 0.5)
    with pytest.raises(ValueError, match=r"^b: not a unit vector"):
        rot.slerp([1, 0, 0], [1, 1, 0], 0.5)
    # Within tolerance is fine.
    rot.quat_to_matrix([1 + 1e-12, 0, 0, 0])


def test_matrices_that_are_not_rotations_are_rejected():
    r = random_rotations(4, 1, seed=3)[0]
    bent = r.copy()
    bent[0, 1] += 1e-6
    with pytest.raises(ValueError, match=r"^R: not orthogonal: RᵀR differs from I by"):
        rot.quaternions_from_so4(bent)
    mirror = r @ np.diag([1, 1, 1, -1.0])
    with pytest.raises(ValueError, match=r"^R: is a reflection \(det = −1\)"):
        rot.quaternions_from_so4(mirror)
    with pytest.raises(ValueError, match=r"^R: is a reflection"):
        rot.matrix_to_quat(np.diag([1, 1, -1.0]))
    with pytest.raises(ValueError, match=r"^rotations: not orthogonal: .* at batch index 1$"):
        rot.compose([np.eye(4), 2 * np.eye(4)])
    with pytest.raises(ValueError, match=r"^R1: not orthogonal"):
        rot.nested_slerp(np.eye(3), np.ones((3, 3)), 0.5)
    with pytest.raises(ValueError, match=r"^R: is a reflection"):
        rot.to_nested_spheres(np.diag([-1.0, 1, 1]))
    with pytest.raises(ValueError, match=r"^vectors\[1\]: not a unit vector"):
        rot.from_nested_spheres([[0, 0, 1.0], [1.0, 1.0]])


@pytest.mark.parametrize("call, pattern", [
    (lambda: rot.quat_to_matrix([1, 0, 0]), r"^q: expected shape \(\.\.\., 4\), got \(3,\)"),
    (lambda: rot.so4_from_quaternions(np.ones((2, 4)) / 2, np.ones((3, 4)) / 2), r"batch axes do not broadcast"),
    (lambda: rot.matrix_to_quat(np.eye(4)), r"^R: expected shape \(\.\.\., 3, 3\)"),
    (lambda: rot.quaternions_from_so4(np.eye(3)), r"^R: expected shape \(\.\.\., 4, 4\)"),
    (lambda: rot.compose(np.ones((2, 3, 4))), r"^rotations: expected shape"),
    (lambda: rot.rolling_ball(np.ones(8)), r"^displacement: .*N = 9"),
    (lambda: rot.rolling_ball([1.0, 2.0], 0.0), r"^radius: must be a positive number, got 0"),
    (lambda: rot.rolling_ball([1.0, 2.0], 1.0, "arcs"), r'^angle: expected "course" or "arc"'),
    (lambda: rot.plane(3, 0, 3, 0.1), r"^i, j: expected two different axes in 0\.\.2 \(dim = 3\), got \[0, 3\]$"),
    (lambda: rot.plane(3, 1, 1, 0.1), r"^i, j: expected two different axes in 0\.\.2 \(dim = 3\), got \[1, 1\]$"),
    (lambda: rot.plane(3, -1, 1, 0.1), r"^i: expected an axis number ≥ 0"),
    (lambda: rot.plane(9, 0, 1, 0.1), r"^n: N must be in 2\.\.8"),
    (lambda: rot.slerp([1, 0, 0], [1, 0], 0.5), r"^b: expected shape \(\.\.\., 3\)"),
    (lambda: rot.from_nested_spheres([[0, 0, 1.0]]), r"^vectors: expected 2 vectors"),
    (lambda: rot.slerp_so4(np.eye(4)[:3], np.eye(4)[:2], 0.1), r"^qp0: expected a pair"),
    (lambda: rot.look_at([0, 0, 1], [0, 0, 0], [[0, 1, 0, 0]]), r"^up: expected shape \(1, 3\)"),
])
def test_wrong_shapes_and_values_name_the_argument(call, pattern):
    with pytest.raises(ValueError, match=pattern):
        call()


@pytest.mark.parametrize("call, name", [
    (lambda: rot.quat_to_matrix([np.nan, 0, 0, 1]), "q"),
    (lambda: rot.quat_multiply([1, 0, 0, 0], [0, np.inf, 0, 0]), "b"),
    (lambda: rot.rolling_ball([np.nan, 1.0]), "displacement"),
    (lambda: rot.slerp([1, 0], [0, 1], np.nan), "t"),
    (lambda: rot.compose([np.full((3, 3), np.nan)]), "rotations"),
    (lambda: rot.plane(3, 0, 1, np.inf), "theta"),
    (lambda: rot.frame([[1, np.nan, 0]]), "vectors"),
    (lambda: rot.look_at([0, 0, np.nan], [0, 0, 0], [0, 1, 0]), "position"),
])
def test_nan_is_rejected(call, name):
    with pytest.raises(ValueError, match=rf"^{name}: non-finite value"):
        call()


# ---------------------------------------------------------------------------------------------
# Scene transforms
# ---------------------------------------------------------------------------------------------


def scene_dict(n, transform):
    return {"dim": n,
            "camera": {"position": [0.3] + [0.0] * (n - 2) + [5.0], "look_at": [0.0] * n,
                       "up": np.eye(n)[1:n - 1], "fov": 40, "resolution": 7},
            "lights": [{"type": "directional", "direction": np.ones(n)}],
            "objects": [{"shape": "hypercube", "transform": [{"scale": 0.6}, transform,
                                                             {"translate": [0.1] + [0.0] * (n - 1)}]}]}


def render(data):
    r = ndtrace.trace(ndtrace.load_dict(data))
    assert 0 < r.hit.sum() < r.hit.size
    return r.rgba, r.depth, r.normal


def assert_same_render(a, b):
    for x, y in zip(a, b):
        np.testing.assert_allclose(x, y, atol=1e-5)


def test_quaternion_transform_equals_its_matrix():
    q = unit(np.array([0.9, 0.1, -0.3, 0.2]))
    p = unit(np.array([0.8, -0.4, 0.1, 0.3]))
    by_quat = render(scene_dict(4, {"rotate": {"quaternions": [q, p]}}))
    by_matrix = render(scene_dict(4, {"matrix": rot.so4_from_quaternions(q, p)}))
    assert_same_render(by_quat, by_matrix)
    # And it is not the identity: the rotation changes the picture.
    plain = render(scene_dict(4, {"scale": 1.0}))
    assert np.abs(plain[0] - by_quat[0]).max() > 1e-2


@pytest.mark.parametrize("n", [3, 5])
@pytest.mark.parametrize("angle", ["course", "arc"])
def test_rolling_transform_equals_its_matrix(n, angle):
    d = np.linspace(0.4, -0.3, n - 1)
    by_roll = render(scene_dict(n, {"rotate": {"rolling": d, "radius": 0.8, "angle": angle}}))
    by_matrix = render(scene_dict(n, {"matrix": rot.rolling_ball(d, 0.8, angle)}))
    assert_same_render(by_roll, by_matrix)


def test_rotate_transform_round_trips_and_reports_paths():
    q = [0.5, 0.5, 0.5, 0.5]
    scene = ndtrace.load_dict(scene_dict(4, {"rotate": {"quaternions": [q, q]}}))
    again = ndtrace.load_toml(scene.to_toml())
    assert again == scene
    roll = ndtrace.load_dict(scene_dict(4, {"rotate": {"rolling": [1, 0, 0], "radius": 2, "angle": "arc"}}))
    assert ndtrace.load_toml(roll.to_toml()) == roll
    with pytest.raises(ValueError) as e:
        ndtrace.load_dict(scene_dict(4, {"rotate": {"quaternions": [q, [0.65, 0.65, 0.65, 0.65]]}}))
    assert str(e.value) == ("<dict>: objects[0].transform[1].rotate.quaternions[1]: "
                            "not a unit quaternion (|p| = 1.3)")
    with pytest.raises(ValueError, match=r"^<dict>: objects\[0\]\.transform\[1\]\.rotate\.quaternions: "
                                         r".*4D rotation, but dim = 3"):
        ndtrace.load_dict(scene_dict(3, {"rotate": {"quaternions": [q, q]}}))
    with pytest.raises(ValueError, match=r"transform\[1\]\.rotate\.rolling: give only one of"):
        ndtrace.load_dict(scene_dict(4, {"rotate": {"plane": [0, 1], "degrees": 3, "rolling": [1, 0, 0]}}))
    with pytest.raises(ValueError, match=r"transform\[1\]\.rotate: rolling needs radius"):
        ndtrace.load_dict(scene_dict(4, {"rotate": {"rolling": [1, 0, 0]}}))
    # In a file, the location is the offending quaternion.
    text = scene.to_toml().replace("0.5, 0.5, 0.5, 0.5]]", "0.5, 0.5, 0.5, 0.6]]")
    with pytest.raises(ValueError) as e:
        ndtrace.load_toml(text, name="scene.toml")
    lines = text.splitlines()
    line = next(k for k, l in enumerate(lines) if "0.6]]" in l)
    col = lines[line].index("[0.5, 0.5, 0.5, 0.6]")
    assert str(e.value).startswith(f"scene.toml:{line + 1}:{col + 1}: objects[0].transform[1].rotate.quaternions[1]: "
                                   "not a unit quaternion (|p| = ")


DOCS_SCENE = """dim = 4
[camera]
position = [0.3, 0, 0, 5]
look_at = [0, 0, 0, 0]
up = [[0, 1, 0, 0], [0, 0, 1, 0]]
fov = 40
resolution = 7
[[lights]]
type = "directional"
direction = [1, 1, 1, 1]
[[objects]]
shape = "hypercube"
transform = [{{ scale = 0.6 }}, {steps}, {{ translate = [0.1, 0, 0, 0] }}]
"""


def docs_render(steps_toml: str):
    """Renders a hypercube whose transform is a scale, the TOML list ``steps_toml``, and a
    translation, loaded from TOML text like a scene file."""
    text = DOCS_SCENE.format(steps=steps_toml.strip()[1:-1])
    r = ndtrace.trace(ndtrace.load_toml(text, name="docs"))
    assert 0 < r.hit.sum() < r.hit.size
    return r.rgba, r.depth, r.normal


def matrix_toml(m: np.ndarray) -> str:
    rows = ", ".join("[" + ", ".join(repr(float(x)) for x in row) + "]" for row in m)
    return f"[{{ matrix = [{rows}] }}]"


def test_documented_rotate_examples_equal_their_matrices():
    """Each TOML example of docs/scene-format.md's rotate forms builds the same scene as an
    explicit ``matrix`` step computed with ndtrace.rotation (and not the identity)."""
    text = DOCS.read_text()
    examples = re.findall(r"^transform = (\[\{ rotate = .*?\} \}\])", text, flags=re.M | re.S)
    assert len(examples) >= 5 and any("quaternions" in e for e in examples), examples
    plain = docs_render("[{ scale = 1.0 }]")
    for ex in examples:
        (step,) = tomllib.loads(f"transform = {ex}")["transform"]
        r = step["rotate"]
        if "plane" in r:
            m = rot.plane(4, *r["plane"], math.radians(r["degrees"]))
        elif "quaternions" in r:
            q, p = np.array(r["quaternions"], dtype=float)
            m = rot.so4_from_quaternions(q / np.linalg.norm(q), p / np.linalg.norm(p))
        else:
            m = rot.rolling_ball(r["rolling"], r["radius"], r.get("angle", "course"))
        by_docs = docs_render(ex)
        assert_same_render(by_docs, docs_render(matrix_toml(m)))
        assert np.abs(plain[0] - by_docs[0]).max() > 1e-2, ex  # the rotation shows
    c, s = math.cos(math.radians(15)), math.sin(math.radians(15))
    np.testing.assert_allclose(rot.so4_from_quaternions([c, 0, 0, s], [c, 0, 0, s]),
                               rot.plane(4, 1, 2, math.radians(30)), atol=1e-15)


def test_hand_typed_quaternions_load_normalized():
    """Scene quaternions typed to four digits (|q| ≠ 1 by ~1e-5) are accepted and normalized;
    the scene equals the one with the exact quaternions to ~1e-4. |q| = 1.01 is rejected."""
    c, s = math.cos(math.radians(15)), math.sin(math.radians(15))
    exact = [[c, 0, 0, s], [0.6, 0, 0.8, 0]]
    typed = [[0.9659, 0, 0, 0.2588], [0.6, 0, 0.8, 0]]
    assert abs(np.linalg.norm(typed[0]) - 1) > 10 * rot.UNIT_TOLERANCE  # strict check would refuse
    with pytest.raises(ValueError, match="not a unit quaternion"):
        rot.so4_from_quaternions(*typed)
    by_typed = render(scene_dict(4, {"rotate": {"quaternions": typed}}))
    by_exact = render(scene_dict(4, {"rotate": {"quaternions": exact}}))
    for x, y in zip(by_typed, by_exact):
        np.testing.assert_allclose(x, y, atol=1e-4)
    by_toml = docs_render("[{ rotate = { quaternions = [[0.9659, 0, 0, 0.2588], [0.6, 0, 0.8, 0]] } }]")
    exact_m = rot.so4_from_quaternions(*exact)
    for x, y in zip(by_toml, docs_render(matrix_toml(exact_m))):
        np.testing.assert_allclose(x, y, atol=1e-4)
    # The tolerance is 1e-3: |q| = 1.01 is a typo, reported at its path.
    with pytest.raises(ValueError) as e:
        ndtrace.load_dict(scene_dict(4, {"rotate": {"quaternions": [[1.01, 0, 0, 0], [1, 0, 0, 0]]}}))
    assert str(e.value) == ("<dict>: objects[0].transform[1].rotate.quaternions[0]: "
                            "not a unit quaternion (|q| = 1.01)")
    with pytest.raises(ValueError, match=r"rotate\.quaternions\[1\]: not a unit quaternion \(\|p\| = 0\.998"):
        ndtrace.load_dict(scene_dict(4, {"rotate": {"quaternions": [[1, 0, 0, 0], [0.998, 0, 0, 0]]}}))


def test_rotate_plane_errors_name_the_path():
    with pytest.raises(ValueError) as e:
        ndtrace.load_dict(scene_dict(4, {"rotate": {"plane": [2, 2], "degrees": 10}}))
    assert str(e.value) == ("<dict>: objects[0].transform[1].rotate.plane: "
                            "expected two different axes in 0..3 (dim = 4), got [2, 2]")
