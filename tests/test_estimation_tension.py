"""Tension estimator: force balance, filtering and the dwell rule."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland import GRAVITY as g
from tetherland.estimation import MotorLagThrust, TensionEstimator, tension_from_forces
from tetherland.estimation.tension import tension_filter_time_constant
from tetherland.geometry import link_direction
from tetherland.rotations import rotation_from_z_and_yaw


def test_inclined_hover_tension_is_recovered_from_thrust_and_specific_force():
    # robot at rest in inclined hovering on the 50 deg example: a = 0, so the specific
    # force is (f_R z_B - f_L d)/m = -g_W expressed in F_B
    phi, theta, m = -0.7725, math.radians(50), 1.0
    f_R = m * g * math.cos(phi) / math.cos(phi + theta)
    f_L = m * g * math.sin(theta) / math.cos(phi + theta)
    z_B = np.array([math.sin(theta), 0.0, math.cos(theta)])
    R_WB = rotation_from_z_and_yaw(z_B, 0.0)
    specific_force_B = R_WB.T @ np.array([0.0, 0.0, g])
    d_B = R_WB.T @ link_direction(phi, 0.0)
    assert tension_from_forces(f_R, specific_force_B, m, d_B) == pytest.approx(f_L, rel=1e-9)
    assert tension_from_forces(f_R, specific_force_B, m) == pytest.approx(f_L, rel=1e-9)


def test_free_flight_gives_zero_tension():
    assert tension_from_forces(9.81, [0.0, 0.0, 9.81], 1.0) == pytest.approx(0.0, abs=1e-12)


def test_filter_converges_and_dwell_rule():
    est = TensionEstimator(mass=1.0, threshold=1.0, dwell=0.2, time_constant=0.05)
    rng = np.random.default_rng(0)
    taut_at = None
    for k in range(1000):
        t = k * 0.002
        true = 0.0 if t < 0.5 else 3.0
        a_m = np.array([0.0, 0.0, 9.81 - true]) + rng.normal(0, 0.05, 3)
        out = est.update(t, 9.81, a_m)
        if out.taut and taut_at is None:
            taut_at = t
    assert est.value == pytest.approx(3.0, abs=0.1)
    # crosses 1 N about tau*ln(1.5) after the step, then dwells 0.2 s
    assert taut_at == pytest.approx(0.5 + 0.05 * math.log(1.5) + 0.2, abs=0.01)


def test_dwell_timer_resets_when_tension_drops():
    est = TensionEstimator(mass=1.0, threshold=1.0, dwell=0.1, time_constant=0.0)
    assert not est.update(0.0, 12.0, [0, 0, 9.81]).taut
    assert not est.update(0.05, 12.0, [0, 0, 9.81]).taut
    assert not est.update(0.08, 9.81, [0, 0, 9.81]).taut  # drops: timer resets
    assert not est.update(0.1, 12.0, [0, 0, 9.81]).taut
    assert est.update(0.2, 12.0, [0, 0, 9.81]).taut


def test_motor_lag_matches_exponential_response():
    lag = MotorLagThrust(1e-5, 0.03, w0=np.zeros(4))
    f = None
    for _ in range(30):
        f = lag.step(np.full(4, 500.0), 0.001)
    w_expected = 500.0 * (1.0 - math.exp(-0.03 / 0.03))
    np.testing.assert_allclose(f, 1e-5 * w_expected**2, rtol=1e-12)


def test_filter_value_is_the_filter_without_its_record():
    """The estimator's path (filtered value and the taut rule as an attribute) gives the
    record's filtered tension and taut flag exactly, through a step that turns the rule on
    and a drop that resets it."""
    a = TensionEstimator(mass=1.2, threshold=1.0, dwell=0.1, time_constant=0.02)
    b = TensionEstimator(mass=1.2, threshold=1.0, dwell=0.1, time_constant=0.02)
    rng = np.random.default_rng(1)
    taut = 0
    for k in range(600):
        t = k * 0.002
        raw = (3.0 if 0.2 <= t < 0.7 else 0.2) + rng.normal(0.0, 0.1)
        record = a.filter(t, raw)
        assert b.filter_value(t, raw) == record.filtered == b.value
        assert b.taut == record.taut
        taut += record.taut
    assert 0 < taut < 600


def test_estimator_last_tension_is_the_last_estimates():
    """UkfEstimator.last_tension (built on demand) holds the raw and filtered tension and
    the taut rule of the last estimate; the filtered one is the estimate's tension."""
    from tetherland.config import load_scenario
    from tetherland.estimation import UkfEstimator
    from tetherland.interfaces import ImuSample
    from tetherland.state import RigidBodyState

    sc = load_scenario("slope50")
    est = UkfEstimator(sc, RigidBodyState.at_rest(np.zeros(3)))
    assert est.last_tension is None
    stretch = sc.mission.stretch
    plain = TensionEstimator(
        sc.vehicle.mass,
        stretch.tension_threshold,
        stretch.tension_dwell,
        tension_filter_time_constant(sc.tether.stiffness, sc.vehicle.mass),
    )
    rng = np.random.default_rng(2)
    for k in range(1, 40):
        f_B = np.array([0.0, 0.0, g]) + rng.normal(0.0, 0.2, 3)
        est.predict(ImuSample(k * 1e-3, f_B, np.zeros(3)))
        e = est.estimate()
        last = est.last_tension
        # the plain filter fed the same raw tensions: the same filtered value and rule
        assert last.filtered == e.tension == plain.filter_value(e.t, last.raw)
        assert last.taut == plain.taut
        assert math.isfinite(last.raw)
    # the raw tension of the last estimate, with the motors off: the residual force's
    # projection on the link (or its norm): m |f_B - b_a| for a level vehicle at most
    assert abs(last.raw) <= sc.vehicle.mass * float(np.linalg.norm(f_B - e.accel_bias_B)) + 1e-9
