"""Orientation splines (``ndtrace.rotation.quaternion_spline``, ``so4_spline``, ``so_n_spline``)
and ``[animation] keyframes``: through every key, unit length, C¹ at interior keys by finite
differences, the slerp for two keys, SO(4) as the factors' splines, bad input named."""

import numpy as np
import pytest

import ndtrace
from ndtrace import rotation


def random_keys(seed, k, *, continuous=True):
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(k, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    if continuous:
        for i in range(1, k):
            if q[i] @ q[i - 1] < 0:
                q[i] = -q[i]
    times = np.cumsum(rng.uniform(0.3, 2.0, size=k))
    return q, times


def test_passes_through_every_key_with_unit_length():
    keys, times = random_keys(1, 6, continuous=False)
    signed = keys.copy()
    for i in range(1, len(signed)):
        if signed[i] @ signed[i - 1] < 0:
            signed[i] = -signed[i]
    np.testing.assert_allclose(rotation.quaternion_spline(keys, times, times), signed, atol=1e-12)
    t = np.linspace(times[0], times[-1], 301)
    q = rotation.quaternion_spline(keys, times, t)
    assert q.shape == (301, 4)
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1, atol=1e-14)
    # The shorter arc: consecutive samples never jump to the antipode.
    assert np.all(np.einsum("ij,ij->i", q[1:], q[:-1]) > 0.9)


def test_is_c1_at_interior_keys_and_not_merely_c0():
    keys, times = random_keys(2, 5)
    h = 1e-6
    for t in times[1:-1]:
        q = rotation.quaternion_spline(keys, times, t + h * np.arange(-2, 3))
        left = (3 * q[2] - 4 * q[1] + q[0]) / (2 * h)
        right = (-3 * q[2] + 4 * q[3] - q[4]) / (2 * h)
        np.testing.assert_allclose(left, right, atol=1e-4 * max(1, np.linalg.norm(left)))
    # Piecewise slerp through the same keys has corners there (the test can fail).
    t = times[2]
    a = [ndtrace.rotation.slerp(keys[1], keys[2], 1 - 1e-6), keys[2],
         ndtrace.rotation.slerp(keys[2], keys[3], 1e-6)]
    left = (a[1] - a[0]) / ((times[2] - times[1]) * 1e-6)
    right = (a[2] - a[1]) / ((times[3] - times[2]) * 1e-6)
    assert np.linalg.norm(left - right) > 1e-2


def test_two_keys_give_the_slerp():
    keys, times = random_keys(3, 2)
    u = np.linspace(0, 1, 11)
    np.testing.assert_allclose(
        rotation.quaternion_spline(keys, times, times[0] + u * (times[1] - times[0])),
        rotation.slerp(keys[0], keys[1], u), atol=1e-12)


def test_times_outside_the_keys_are_clamped():
    keys, times = random_keys(4, 3)
    q = rotation.quaternion_spline(keys, times, [times[0] - 5, times[-1] + 5])
    np.testing.assert_allclose(q, keys[[0, -1]], atol=1e-12)


def test_so4_spline_is_orthonormal_and_the_double_quaternion_of_the_factor_splines():
    left, times = random_keys(5, 5)
    right, _ = random_keys(6, 5)
    t = np.linspace(times[0], times[-1], 40)
    m = rotation.so4_spline(left, right, times, t)
    assert m.shape == (40, 4, 4)
    np.testing.assert_allclose(m @ np.swapaxes(m, -1, -2), np.broadcast_to(np.eye(4), m.shape),
                               atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(m), 1, atol=1e-12)
    expected = rotation.so4_from_quaternions(rotation.quaternion_spline(left, times, t),
                                             rotation.quaternion_spline(right, times, t))
    np.testing.assert_allclose(m, expected, atol=1e-13)
    # Through the keys.
    np.testing.assert_allclose(rotation.so4_spline(left, right, times, times),
                               rotation.so4_from_quaternions(left, right), atol=1e-12)


@pytest.mark.parametrize("n", [2, 3, 5, 6])
def test_so_n_spline_beyond_the_course(n):
    rng = np.random.default_rng(n)
    keys = []
    for _ in range(4):
        a = rng.normal(size=(n, n)) * 0.4
        keys.append(np.linalg.qr(np.eye(n) + a - a.T)[0])
        if np.linalg.det(keys[-1]) < 0:
            keys[-1][:, 0] *= -1
    keys = np.array(keys)
    times = np.array([0.0, 0.7, 1.5, 3.0])
    np.testing.assert_allclose(rotation.so_n_spline(keys, times, times), keys, atol=1e-10)
    t = np.linspace(0, 3, 31)
    m = rotation.so_n_spline(keys, times, t)
    np.testing.assert_allclose(m @ np.swapaxes(m, -1, -2), np.broadcast_to(np.eye(n), m.shape),
                               atol=1e-10)
    np.testing.assert_allclose(np.linalg.det(m), 1, atol=1e-10)
    # C¹ at the interior keys.
    h = 1e-6
    for tk in times[1:-1]:
        r = rotation.so_n_spline(keys, times, tk + h * np.arange(-2, 3))
        left = (3 * r[2] - 4 * r[1] + r[0]) / (2 * h)
        right = (-3 * r[2] + 4 * r[3] - r[4]) / (2 * h)
        np.testing.assert_allclose(left, right, atol=1e-4)


def test_so_n_spline_equals_the_quaternion_spline_in_3d():
    keys, times = random_keys(7, 4)
    t = np.linspace(times[0], times[-1], 17)
    np.testing.assert_allclose(
        rotation.so_n_spline(rotation.quat_to_matrix(keys), times, t),
        rotation.quat_to_matrix(rotation.quaternion_spline(keys, times, t)), atol=1e-9)


@pytest.mark.parametrize("call, name", [
    (lambda: rotation.quaternion_spline([[1, 0, 0, 0], [0, 1, 0, 0]], [0, 0], 0.5), "times"),
    (lambda: rotation.quaternion_spline([[1, 0, 0, 0], [0, 1, 0, 0]], [1, 0], 0.5), "times"),
    (lambda: rotation.quaternion_spline([[1, 0, 0, 0], [0, 1, 0, 0]], [0, np.nan], 0.5), "times"),
    (lambda: rotation.quaternion_spline([[1, 0, 0, 0], [0, 1, 0, 0]], [0, 1, 2], 0.5), "times"),
    (lambda: rotation.quaternion_spline([[1, 0, 0, 0]], [0], 0.5), "keys"),
    (lambda: rotation.quaternion_spline([[1, 0, 0], [0, 1, 0]], [0, 1], 0.5), "keys"),
    (lambda: rotation.quaternion_spline([[1, 0, 0, 0], [0, 2, 0, 0]], [0, 1], 0.5), "keys"),
    (lambda: rotation.quaternion_spline([[1, 0, 0, 0], [np.nan, 1, 0, 0]], [0, 1], 0.5), "keys"),
    (lambda: rotation.quaternion_spline([[1, 0, 0, 0], [0, 1, 0, 0]], [0, 1], np.nan), "t"),
    (lambda: rotation.so4_spline([[1, 0, 0, 0]] * 2, [[1, 0, 0, 0]] * 3, [0, 1], 0.5), "right_keys"),
    (lambda: rotation.so_n_spline(np.eye(3)[None].repeat(2, 0) * 2, [0, 1], 0.5), "keys"),
])
def test_bad_input_names_the_argument(call, name):
    with pytest.raises(ValueError, match=f"^{name}"):
        call()


def keyframe_scene(interpolation=None, dim=4):
    keys = [{"time": 0, "rotation": {"plane": [0, dim - 1], "degrees": 0}},
            {"time": 1, "rotation": {"plane": [0, dim - 1], "degrees": 40}},
            {"time": 3, "rotation": {"plane": [1, 2], "degrees": 60}}]
    animation = {"frames": 7, "keyframes": keys}
    if interpolation:
        animation["interpolation"] = interpolation
    up = [[1.0 if i == k else 0.0 for i in range(dim)] for k in range(1, dim - 1)]
    return ndtrace.load_dict({
        "dim": dim, "camera": {"position": [0] * (dim - 1) + [5], "look_at": [0] * dim,
                               "up": up, "fov": 40, "resolution": 8},
        "objects": [{"shape": "hypercube"}], "animation": animation})


def frame_rotation(scene, k):
    step = ndtrace.animation.frame_scene(scene, k).to_dict()["objects"][0]["transform"][-1]
    return np.asarray(step["matrix"], float)


@pytest.mark.parametrize("dim", [3, 4, 5])
def test_keyframes_pass_through_the_keys_and_spline_differs_from_slerp(dim):
    spline, slerp = keyframe_scene(dim=dim), keyframe_scene("slerp", dim=dim)
    # Frames 0, 2 and 6 of 7 sit at times 0, 1 and 3.
    r = ndtrace.rotation
    keys = [np.eye(dim), r.plane(dim, 0, dim - 1, np.radians(40)), r.plane(dim, 1, 2, np.radians(60))]
    for k, key in zip((0, 2, 6), keys):
        np.testing.assert_allclose(frame_rotation(spline, k), key, atol=1e-9)
        np.testing.assert_allclose(frame_rotation(slerp, k), key, atol=1e-9)
    # Between keys slerp is the geodesic; the spline is not.
    a, b = frame_rotation(spline, 1), frame_rotation(slerp, 1)
    np.testing.assert_allclose(b, r.plane(dim, 0, dim - 1, np.radians(20)), atol=1e-9)
    assert np.abs(a - b).max() > 1e-3


def test_keyframe_errors_name_the_key():
    data = keyframe_scene().to_dict()
    data["animation"]["keyframes"][2]["time"] = 1
    with pytest.raises(ValueError, match=r"animation\.keyframes: times must increase strictly"):
        ndtrace.load_dict(data)
    data = keyframe_scene().to_dict()
    data["animation"]["interpolation"] = "cubic"
    with pytest.raises(ValueError, match=r"animation\.interpolation"):
        ndtrace.load_dict(data)
