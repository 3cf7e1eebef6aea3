"""Free-flight rigid-body dynamics (6.1)-(6.2)."""

from __future__ import annotations

import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.config import VehicleConfig
from tetherland.models.rigid_body import (
    RigidBodyParams,
    kinetic_energy,
    rigid_body_derivative,
    rk4_step,
)
from tetherland.rotations import quat_to_rotmat, rotvec_to_quat
from tetherland.state import RigidBodyState

PARAMS = RigidBodyParams.from_config(VehicleConfig())


def test_hover_is_an_equilibrium_and_free_fall_accelerates_at_g():
    s = RigidBodyState.at_rest(np.zeros(3))
    d = rigid_body_derivative(s, PARAMS.mass * GRAVITY, np.zeros(3), PARAMS)
    np.testing.assert_allclose(d.v_dot_W, 0.0, atol=1e-12)
    np.testing.assert_allclose(d.omega_dot_B, 0.0, atol=1e-12)
    d = rigid_body_derivative(s, 0.0, np.zeros(3), PARAMS)
    np.testing.assert_allclose(d.v_dot_W, [0.0, 0.0, -GRAVITY])


def test_thrust_acts_along_the_body_z_axis():
    q = rotvec_to_quat([0.3, -0.2, 0.1])
    s = RigidBodyState(np.zeros(3), np.zeros(3), q, np.zeros(3))
    d = rigid_body_derivative(
        s, 5.0, np.zeros(3), PARAMS, f_ext_W=[0.0, 0.0, PARAMS.mass * GRAVITY]
    )
    np.testing.assert_allclose(d.v_dot_W, 5.0 * quat_to_rotmat(q)[:, 2] / PARAMS.mass)


def test_torque_free_rotation_keeps_energy_and_angular_momentum():
    params = RigidBodyParams(mass=1.0, inertia=np.array([0.01, 0.02, 0.03]))
    s = RigidBodyState(
        np.zeros(3), np.zeros(3), np.array([1.0, 0, 0, 0]), np.array([1.0, 0.2, 3.0])
    )

    def momentum_W(state):
        return quat_to_rotmat(state.q_WB) @ (params.inertia @ state.omega_B)

    E0, L0 = kinetic_energy(s, params), momentum_W(s)
    for _ in range(2000):
        s = rk4_step(s, 0.0, np.zeros(3), 1e-3, params, f_ext_W=[0, 0, params.mass * GRAVITY])
    assert kinetic_energy(s, params) == pytest.approx(E0, rel=1e-8)
    np.testing.assert_allclose(momentum_W(s), L0, rtol=1e-7, atol=1e-10)
    assert np.linalg.norm(s.q_WB) == pytest.approx(1.0, abs=1e-12)
    # Euler's equations made it tumble: the body rate changed
    assert np.linalg.norm(s.omega_B - np.array([1.0, 0.2, 3.0])) > 0.05


def test_constant_torque_spins_up_linearly():
    s = RigidBodyState.at_rest(np.zeros(3))
    tau = np.array([0.0, 0.0, 0.01])
    for _ in range(100):
        s = rk4_step(s, PARAMS.mass * GRAVITY, tau, 1e-3, PARAMS)
    assert s.omega_B[2] == pytest.approx(0.1 * tau[2] / PARAMS.inertia[2, 2], rel=1e-9)
    np.testing.assert_allclose(s.p_W, 0.0, atol=1e-12)
