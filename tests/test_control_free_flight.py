"""Free-flight geometric controller: error definitions, equilibria, limits (unit level)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherland import GRAVITY as g
from tetherland.config import FreeFlightGains
from tetherland.control import (
    AttitudeController,
    AttitudeGains,
    PositionController,
    PositionReference,
    attitude_error,
)
from tetherland.rotations import exp_so3, rotmat_to_quat
from tetherland.state import RigidBodyState

J = np.array([0.015, 0.015, 0.025])
GAINS = FreeFlightGains()


@settings(max_examples=100, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=3, max_size=3), st.floats(0.01, 2.5))
def test_attitude_error_single_axis_is_sine_of_angle(axis, angle):
    a = np.array(axis)
    if np.linalg.norm(a) < 1e-3:
        return
    a /= np.linalg.norm(a)
    R_d = exp_so3([0.2, -0.1, 0.4])
    R = R_d @ exp_so3(angle * a)
    np.testing.assert_allclose(attitude_error(R, R_d), math.sin(angle) * a, atol=1e-12)
    np.testing.assert_allclose(attitude_error(R_d, R_d), 0.0, atol=1e-15)


def test_torque_is_restoring_and_matches_linear_gains():
    ctrl = AttitudeController(J, AttitudeGains.from_config(GAINS))
    R_d = np.eye(3)
    for axis in range(3):
        e = np.zeros(3)
        e[axis] = 1e-4
        tau = ctrl.torque(exp_so3(e), np.zeros(3), R_d)
        assert tau[axis] < 0 and np.abs(np.delete(tau, axis)).max() < 1e-12
        k_R = ctrl.gains.k_R[axis]
        assert tau[axis] == pytest.approx(-J[axis] * k_R * 1e-4, rel=1e-6)
        w = np.zeros(3)
        w[axis] = 0.1
        tau_w = ctrl.torque(np.eye(3), w, R_d)
        assert tau_w[axis] == pytest.approx(-J[axis] * ctrl.gains.k_w[axis] * 0.1, rel=1e-9)


def test_hover_equilibrium_wrench():
    ctrl = PositionController(1.2, J, GAINS)
    state = RigidBodyState.at_rest(np.array([1.0, 2.0, 3.0]))
    out = ctrl.update(state, PositionReference(np.array([1.0, 2.0, 3.0])))
    assert out.thrust == pytest.approx(1.2 * g)
    np.testing.assert_allclose(out.torque_B, 0.0, atol=1e-12)
    assert not out.limited


def test_position_error_tilts_towards_the_target():
    ctrl = PositionController(1.0, J, GAINS)
    state = RigidBodyState.at_rest(np.zeros(3))
    out = ctrl.update(state, PositionReference(np.array([0.3, 0.0, 0.0])))
    assert out.R_d[0, 2] > 0  # desired thrust axis leans towards +x
    assert out.torque_B[1] > 0  # pitch torque to tilt the thrust axis towards +x


def test_tilt_and_vertical_limits():
    ctrl = PositionController(1.0, J, GAINS, min_thrust=0.8)
    state = RigidBodyState.at_rest(np.zeros(3))
    far = ctrl.update(state, PositionReference(np.array([100.0, 0.0, 0.0])))
    tilt = math.degrees(math.acos(far.R_d[2, 2]))
    assert far.limited and tilt == pytest.approx(GAINS.max_tilt_deg, abs=1e-9)
    falling = ctrl.update(state, PositionReference(np.zeros(3), a_W=np.array([0, 0, -2 * g])))
    F, limited = ctrl.desired_force(
        state, PositionReference(np.zeros(3), a_W=np.array([0, 0, -2 * g]))
    )
    assert limited and F[2] == pytest.approx(0.8) and falling.R_d[2, 2] == pytest.approx(1.0)


def test_thrust_is_projected_on_the_actual_axis():
    ctrl = PositionController(1.0, J, GAINS)
    tilted = RigidBodyState(
        np.zeros(3), np.zeros(3), rotmat_to_quat(exp_so3([0.3, 0.0, 0.0])), np.zeros(3)
    )
    out = ctrl.update(tilted, PositionReference(np.zeros(3)))
    assert out.thrust == pytest.approx(g * math.cos(0.3))
