"""Surface frames and quaternion patches (``ndtrace.frames.surface_frames``,
``quaternion_patch``; course notes Part II(A), "3-Manifold of Frames for a Patch"): orthonormal
frames whose third axis is the normal, continuity, the minimal-area patch no larger than the
others on the course's examples, and its gradient against finite differences."""

import numpy as np
import pytest

import ndtrace
from ndtrace import frames as fr
from ndtrace.rotation import quat_to_matrix

METHODS = ["geodesic_reference", "parallel_transport", "minimal_area"]
PATCHES = {"smooth": lambda: fr.smooth_patch(12), "spherical": lambda: fr.spherical_patch(12, 0.9)}


@pytest.mark.parametrize("patch", sorted(PATCHES))
@pytest.mark.parametrize("method", METHODS)
def test_frames_are_orthonormal_with_the_normal_as_third_axis(patch, method):
    points = PATCHES[patch]()
    q = fr.surface_frames(points, method)
    assert q.shape == points.shape[:2] + (4,)
    np.testing.assert_allclose(np.linalg.norm(q, axis=-1), 1, atol=1e-12)
    R = quat_to_matrix(q)
    np.testing.assert_allclose(R @ np.swapaxes(R, -1, -2), np.broadcast_to(np.eye(3), R.shape),
                               atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(R), 1, atol=1e-12)
    np.testing.assert_allclose(R[..., :, 2], fr.surface_normals(points), atol=1e-9)
    # Continuous signs: neighbours on the grid are close on S³.
    assert np.all(np.sum(q[1:] * q[:-1], -1) > 0.5) and np.all(np.sum(q[:, 1:] * q[:, :-1], -1) > 0.5)


def test_surface_normals_of_the_sphere_are_radial():
    p = fr.spherical_patch(9, 0.8)
    np.testing.assert_allclose(fr.surface_normals(p), p, atol=5e-3)


@pytest.mark.parametrize("patch", sorted(PATCHES))
def test_the_minimal_area_patch_is_no_larger_than_the_others(patch):
    points = PATCHES[patch]()
    areas = {m: fr.patch_area(fr.surface_frames(points, m)) for m in METHODS}
    assert areas["minimal_area"] <= areas["geodesic_reference"] + 1e-12
    assert areas["minimal_area"] <= areas["parallel_transport"] + 1e-12
    # Parallel transport along one edge then across twists: strictly more area here.
    assert areas["parallel_transport"] > areas["minimal_area"] * 1.05


def test_parallel_transport_frames_do_not_spin_about_the_normal_along_the_first_column():
    points = fr.smooth_patch(10)
    q = fr.surface_frames(points, "parallel_transport")
    R = quat_to_matrix(q[:, 0])
    n = fr.surface_normals(points)[:, 0]
    # The first axis moves only as the normal turns: its change has no component along the
    # second axis beyond second order (discrete parallel transport).
    for i in range(len(R) - 1):
        turn = np.arccos(np.clip(n[i] @ n[i + 1], -1, 1))
        assert abs(R[i + 1][:, 0] @ R[i][:, 1]) <= turn ** 2 + 1e-12


def test_area_gradient_against_finite_differences():
    points = fr.spherical_patch(6, 0.7)
    n = fr.surface_normals(points)
    g = fr._geodesic_reference_quaternions(n)
    rng = np.random.default_rng(3)
    theta = rng.uniform(-0.5, 0.5, size=n.shape[:2])

    def area(t):
        return fr._area(fr._spin(n, t, g))[0]

    h = 0.5 * theta[..., None]
    dr = 0.5 * np.concatenate([-np.sin(h), np.cos(h) * n], axis=-1)
    _, grad = fr._area(fr._spin(n, theta, g), ndtrace.rotation.quat_multiply(dr, g))
    eps = 1e-6
    for i, j in [(0, 0), (2, 3), (5, 5), (3, 0)]:
        e = np.zeros_like(theta)
        e[i, j] = eps
        fd = (area(theta + e) - area(theta - e)) / (2 * eps)
        assert grad[i, j] == pytest.approx(fd, rel=1e-5, abs=1e-9)


def test_quaternion_patch_is_a_surface_of_s3_for_the_surface_renderer():
    points = fr.spherical_patch(8, 0.9)
    vertices, triangles = fr.quaternion_patch(points, "minimal_area")
    assert vertices.shape == (64, 4) and triangles.shape == (2 * 7 * 7, 3)
    np.testing.assert_allclose(np.linalg.norm(vertices, axis=1), 1, atol=1e-12)
    q = fr.surface_frames(points, "minimal_area")
    np.testing.assert_allclose(vertices, q.reshape(-1, 4))
    assert fr.patch_area(q) == pytest.approx(
        sum(0.5 * np.sqrt(max(0.0, np.linalg.det(np.stack([v[1] - v[0], v[2] - v[0]])
                                                   @ np.stack([v[1] - v[0], v[2] - v[0]]).T)))
            for v in vertices[triangles]), rel=1e-12)
    scene = ndtrace.load_dict({
        "dim": 4, "camera": {"position": [0.3, 0.5, 0.7, 3.5], "look_at": [0, 0, 0, 0],
                             "up": [[0, 1, 0, 0], [0, 0, 1, 0]], "fov": 50, "resolution": 24},
        "objects": [{"shape": "surface", "vertices": vertices, "triangles": triangles}]})
    assert (ndtrace.trace(scene).object_id == 0).sum() > 50


@pytest.mark.parametrize("call, name", [
    (lambda: fr.surface_frames(np.zeros((2, 5, 3))), "points"),
    (lambda: fr.surface_frames(np.zeros((5, 5, 2))), "points"),
    (lambda: fr.surface_frames(np.full((5, 5, 3), np.nan)), "points"),
    (lambda: fr.surface_frames(np.zeros((5, 5, 3))), "points"),
    (lambda: fr.surface_frames(fr.smooth_patch(5), "frenet"), "method"),
    (lambda: fr.quaternion_patch(np.zeros((4, 4, 5))), "frames"),
    (lambda: fr.quaternion_patch(np.ones((4, 4, 4))), "frames"),
])
def test_bad_input_names_the_argument(call, name):
    with pytest.raises(ValueError, match=f"^{name}"):
        call()
