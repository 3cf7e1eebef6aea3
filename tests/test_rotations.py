"""Rotation utilities against scipy (scalar-first quaternions)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tetherland.errors import SingularityError
from tetherland.rotations import (
    exp_so3,
    from_scipy_quat,
    hat,
    log_so3,
    quat_multiply,
    quat_to_rotmat,
    quat_to_rotvec,
    rotation_from_z_and_yaw,
    rotmat_to_quat,
    rotvec_to_quat,
    to_scipy_quat,
    vee,
)


@pytest.fixture
def rotations() -> Rotation:
    return Rotation.random(200, random_state=np.random.default_rng(7))


def test_quaternion_matrix_round_trip(rotations):
    for r in rotations:
        q = from_scipy_quat(r.as_quat())
        np.testing.assert_allclose(quat_to_rotmat(q), r.as_matrix(), atol=1e-12)
        q_back = rotmat_to_quat(r.as_matrix())
        assert q_back[0] >= 0
        assert abs(q_back @ q) == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose(to_scipy_quat(from_scipy_quat(r.as_quat())), r.as_quat())


def test_product_composes_rotations(rotations):
    for a, b in zip(rotations[:100], rotations[100:], strict=True):
        q = quat_multiply(from_scipy_quat(a.as_quat()), from_scipy_quat(b.as_quat()))
        np.testing.assert_allclose(quat_to_rotmat(q), (a * b).as_matrix(), atol=1e-12)


def test_exp_log_match_scipy(rotations):
    for r in rotations:
        phi = r.as_rotvec()
        np.testing.assert_allclose(exp_so3(phi), r.as_matrix(), atol=1e-12)
        np.testing.assert_allclose(log_so3(r.as_matrix()), phi, atol=1e-9)
        np.testing.assert_allclose(quat_to_rotmat(rotvec_to_quat(phi)), r.as_matrix(), atol=1e-12)
        np.testing.assert_allclose(quat_to_rotvec(rotvec_to_quat(phi)), phi, atol=1e-9)


def test_small_angles_are_exact_to_second_order():
    phi = np.array([1e-10, -2e-10, 3e-10])
    np.testing.assert_allclose(exp_so3(phi), Rotation.from_rotvec(phi).as_matrix(), atol=1e-18)
    np.testing.assert_allclose(quat_to_rotvec(rotvec_to_quat(phi)), phi, rtol=1e-9)


def test_hat_vee():
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=3), rng.normal(size=3)
    np.testing.assert_allclose(hat(a) @ b, np.cross(a, b))
    np.testing.assert_allclose(vee(hat(a)), a)


def test_rotation_from_z_and_yaw():
    z = np.array([0.3, -0.2, 0.9])
    R = rotation_from_z_and_yaw(z, 0.7)
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(R[:, 2], z / np.linalg.norm(z))
    heading = np.array([np.cos(0.7), np.sin(0.7), 0.0])
    assert R[:, 1] @ heading == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(SingularityError):
        rotation_from_z_and_yaw([1.0, 0.0, 0.0], 0.0)
