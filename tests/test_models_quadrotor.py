"""Allocation Gamma (6.19), its saturated inverse, and the rotor lag model."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherland.config import VehicleConfig
from tetherland.models.quadrotor import RotorLayout, RotorModel, Saturation

LAYOUT = RotorLayout.from_config(VehicleConfig())
F_MIN, F_MAX = LAYOUT.f_min, LAYOUT.f_max

thrust = st.floats(F_MIN, F_MAX, allow_nan=False)
thrusts = st.tuples(thrust, thrust, thrust, thrust)
wrench = st.tuples(st.floats(-5, 40), st.floats(-3, 3), st.floats(-3, 3), st.floats(-0.5, 0.5))


def test_allocation_is_the_force_and_moment_of_the_rotor_thrusts():
    f = np.array([1.0, 2.0, 3.0, 4.0])
    w = LAYOUT.wrench(f)
    forces = f[:, None] * np.array([0.0, 0.0, 1.0])
    torque = np.cross(LAYOUT.positions_B, forces).sum(axis=0)
    assert w[0] == pytest.approx(f.sum())
    assert w[1:3] == pytest.approx(torque[:2])
    assert w[3] == pytest.approx(LAYOUT.drag_coefficient * (LAYOUT.spins @ f))
    # x layout: rotor 1 front-left; more thrust there gives +x torque (left side up) and
    # -y torque (nose down)
    assert LAYOUT.positions_B[0, 0] > 0 and LAYOUT.positions_B[0, 1] > 0
    assert LAYOUT.wrench([1, 0, 0, 0])[1] > 0 and LAYOUT.wrench([1, 0, 0, 0])[2] < 0


@settings(max_examples=200, deadline=None)
@given(thrusts)
def test_inverse_round_trip_within_limits(f):
    f = np.array(f)
    alloc = LAYOUT.allocate(LAYOUT.wrench(f))
    assert alloc.saturation is Saturation.NONE
    np.testing.assert_allclose(alloc.thrusts, f, atol=1e-9)
    np.testing.assert_allclose(LAYOUT.thrusts(LAYOUT.wrench(f)), f, atol=1e-9)


@settings(max_examples=300, deadline=None)
@given(wrench)
def test_saturation_keeps_bounds_and_priority(w):
    w = np.array(w)
    alloc = LAYOUT.allocate(w)
    assert np.all(alloc.thrusts >= F_MIN - 1e-12) and np.all(alloc.thrusts <= F_MAX + 1e-12)
    np.testing.assert_allclose(alloc.wrench, LAYOUT.wrench(alloc.thrusts), atol=1e-12)
    if alloc.saturation in (Saturation.NONE, Saturation.YAW):
        np.testing.assert_allclose(alloc.wrench[:3], w[:3], atol=1e-9)  # thrust, roll, pitch kept
    if alloc.saturation is Saturation.ROLL_PITCH:
        assert alloc.wrench[0] == pytest.approx(w[0], abs=1e-9)
        # roll/pitch scaled by one factor s in [0, 1): direction kept
        s = np.linalg.norm(alloc.wrench[1:3]) / np.linalg.norm(w[1:3])
        assert 0.0 <= s < 1.0
        np.testing.assert_allclose(alloc.wrench[1:3], s * w[1:3], atol=1e-9)
    if alloc.saturation is Saturation.THRUST:
        assert not 4 * F_MIN <= w[0] <= 4 * F_MAX


def test_yaw_is_sacrificed_first():
    hover = np.array([9.81, 0.0, 0.3, 0.0])
    w = hover + np.array([0.0, 0.0, 0.0, 0.5])  # far more yaw than the rotors can make
    alloc = LAYOUT.allocate(w)
    assert alloc.saturation is Saturation.YAW
    np.testing.assert_allclose(alloc.wrench[:3], w[:3], atol=1e-9)
    assert 0.0 < alloc.wrench[3] < w[3]
    # the yaw kept is the largest possible: one rotor sits on a limit
    assert np.isclose(alloc.thrusts, F_MIN).any() or np.isclose(alloc.thrusts, F_MAX).any()


def test_thrust_clipped_last():
    alloc = LAYOUT.allocate([100.0, 0.0, 0.0, 0.0])
    assert alloc.saturation is Saturation.THRUST
    np.testing.assert_allclose(alloc.thrusts, F_MAX)


def test_rotor_lag_step_is_the_exact_exponential():
    rotor = RotorModel.from_config(VehicleConfig())
    w0, wc = np.array([300.0, 500.0]), np.array([600.0, 400.0])
    dt = 0.01
    w1 = rotor.step(w0, wc, dt)
    expected = wc + (w0 - wc) * math.exp(-dt / rotor.time_constant)
    np.testing.assert_allclose(w1, expected)
    # many small steps agree with one large one (exact discretisation)
    w = w0.copy()
    for _ in range(10):
        w = rotor.step(w, wc, dt / 10)
    np.testing.assert_allclose(w, w1, rtol=1e-12)
    # commands are limited to the speeds of [f_min, f_max]
    w_hi = rotor.step(w0, [1e5, 1e5], 10.0)
    np.testing.assert_allclose(rotor.thrust(w_hi), rotor.f_max)
    assert rotor.speed_rate(w0, wc) == pytest.approx((wc - w0) / rotor.time_constant)


def test_rotor_thrust_speed_round_trip_and_instant_lag():
    rotor = RotorModel(thrust_coefficient=1e-5, time_constant=0.0, f_min=0.2, f_max=6.0)
    f = np.array([0.2, 1.0, 3.3, 6.0])
    np.testing.assert_allclose(rotor.thrust(rotor.speed(f)), f)
    np.testing.assert_allclose(rotor.step(np.zeros(4), rotor.speed(f), 1e-3), rotor.speed(f))
    with pytest.raises(ValueError):
        RotorModel(thrust_coefficient=1e-5, time_constant=0.03, f_min=2.0, f_max=1.0)


def test_lead_compensated_command_tracks_a_thrust_ramp():
    """With the planned thrust rate, the command cancels the lag; without, thrust lags."""
    rotor = RotorModel.from_config(VehicleConfig())
    dt, rate = 1e-4, 4.0  # ramp of 4 N/s
    t = np.arange(0.0, 0.5, dt)
    f_des = 1.0 + rate * t
    for compensate in (True, False):
        w = rotor.speed(f_des[0])
        errors = []
        for k in range(len(t) - 1):
            cmd = rotor.speed_command(f_des[k], rate if compensate else None)
            w = rotor.step(w, cmd, dt)
            errors.append(abs(rotor.thrust(w) - f_des[k + 1]))
        if compensate:
            assert max(errors[-100:]) < 2e-3
        else:
            assert max(errors[-100:]) > 0.05  # about rate * tau_m = 0.12 N behind


@pytest.mark.parametrize("tau", [(0.0, 0.05), (0.03, -0.02), (0.0, 3.0)])
def test_below_the_floor_the_roll_pitch_torque_is_kept(tau):
    """A thrust below 4 f_min with a roll/pitch torque (a vehicle tilted 90 deg, its wanted
    thrust along z_B near zero, turning level): the rotors are raised above f_min by the
    differential Gamma^-1 [0, tau] needs, which sums to zero, so the torque is delivered
    whole (scaled down together only where the spread exceeds f_max - f_min) and the total
    thrust is 4 f_min - 4 min(s d) >= 4 f_min; the lowest rotor sits at f_min. Clipped to
    the floor with zero torque, the safe hover after a fault on a wall never levelled."""
    w = np.array([0.3, *tau, 0.02])
    alloc = LAYOUT.allocate(w)
    assert alloc.saturation is Saturation.THRUST
    d = LAYOUT.allocation_inverse[:, 1:3] @ np.asarray(tau)
    assert d.sum() == pytest.approx(0.0, abs=1e-12)
    spread = d.max() - d.min()
    s = min(1.0, (F_MAX - F_MIN) / spread)
    np.testing.assert_allclose(alloc.wrench[1:3], s * np.asarray(tau), atol=1e-12)
    assert alloc.wrench[3] == pytest.approx(0.0, abs=1e-12)  # no yaw
    assert alloc.wrench[0] == pytest.approx(4 * F_MIN - 4 * s * d.min(), abs=1e-12)
    assert alloc.thrusts.min() == pytest.approx(F_MIN, abs=1e-12)
    assert alloc.thrusts.max() <= F_MAX + 1e-12
