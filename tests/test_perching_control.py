"""Flatness feed-forward, the free-flight tracker and the perching reference source."""

from __future__ import annotations

import numpy as np
import pytest

from tetherland import GRAVITY as g
from tetherland.config import FreeFlightGains, load_scenario
from tetherland.control import PositionController, PositionReference
from tetherland.control.feedforward import attitude_feedforward
from tetherland.control.tracking import FreeFlightTracker
from tetherland.errors import TetherlandError
from tetherland.interfaces import Controller, ControlMode, Reference, ReferenceSource, StateEstimate
from tetherland.methods.contact_free import LanderGeometry, PerchingReference, PerchPhase
from tetherland.planning.perching import PerchingPlanner
from tetherland.rotations import exp_so3, rotation_from_z_and_yaw, rotmat_to_quat, vee
from tetherland.state import RigidBodyState

SC20 = load_scenario("slope50", ["surface.slope_deg=20"])


@pytest.fixture(scope="module")
def traj20():
    return PerchingPlanner().plan(SC20).require()


def test_feedforward_matches_finite_differences_of_the_attitude():
    rng = np.random.default_rng(11)
    coeffs = rng.normal(0.0, 1.0, (3, 5))  # F(t) = m g z_W + polynomial, 3D
    yaw = 0.7

    def F(t, d=0):
        c = coeffs
        for _ in range(d):
            c = np.array([np.polynomial.polynomial.polyder(ci) for ci in c])
        out = np.array([np.polynomial.polynomial.polyval(t, ci) for ci in c])
        return out + (np.array([0.0, 0.0, g]) if d == 0 else 0.0)

    h = 1e-4
    for t in rng.uniform(0.0, 0.5, 5):
        R, w, w_dot = attitude_feedforward(F(t), F(t, 1), F(t, 2), yaw)
        np.testing.assert_allclose(R, rotation_from_z_and_yaw(F(t), yaw), atol=1e-12)
        Rp, Rm = (rotation_from_z_and_yaw(F(t + s), yaw) for s in (h, -h))
        w_fd = vee(R.T @ (Rp - Rm) / (2 * h))
        np.testing.assert_allclose(w, w_fd, atol=1e-6)
        wp = attitude_feedforward(F(t + h), F(t + h, 1), F(t + h, 2), yaw)[1]
        wm = attitude_feedforward(F(t - h), F(t - h, 1), F(t - h, 2), yaw)[1]
        np.testing.assert_allclose(w_dot, (wp - wm) / (2 * h), atol=1e-5)


@pytest.mark.parametrize("drag", [True, False])
def test_feedforward_reproduces_the_planned_nominal_rates(traj20, drag):
    """The flatness feed-forward of the rows the tracker gets is the planned attitude,
    body rate and angular acceleration; with the believed rotor drag in the plan (the
    default) those rows are the thrust's (``reference_W``), not the flat outputs'."""
    traj = traj20
    if not drag:
        no_drag = load_scenario("slope50", ["surface.slope_deg=20", "controller.rotor_drag=[0, 0]"])
        traj = PerchingPlanner().plan(no_drag).require()
    assert (traj.meta.rotor_drag > 0.0) is drag
    m = traj.meta.mass
    s = traj.sample(np.linspace(0.0, traj.duration, 40))
    if not drag:
        np.testing.assert_array_equal(s.reference_W, s.p_W)
    rows = s.reference_W
    for i in range(len(s.t)):
        F = m * (rows[i, 2] + np.array([0.0, 0.0, g]))
        R, w, w_dot = attitude_feedforward(F, m * rows[i, 3], m * rows[i, 4], s.yaw[i])
        np.testing.assert_allclose(R, s.R_WB[i], atol=1e-9)
        np.testing.assert_allclose(w, s.omega_B[i], atol=1e-9)
        np.testing.assert_allclose(w_dot, s.omega_dot_B[i], atol=1e-7)
    if drag:  # the flat outputs' own rows give another attitude (the drag tilts it)
        i = int(np.argmax(np.linalg.norm(s.p_W[:, 1], axis=1)))
        F = m * (s.p_W[i, 2] + np.array([0.0, 0.0, g]))
        R = attitude_feedforward(F, m * s.p_W[i, 3], m * s.p_W[i, 4], s.yaw[i])[0]
        assert np.linalg.norm(R - s.R_WB[i]) > 1e-3


def test_position_controller_default_is_unchanged():
    J = np.array([0.015, 0.015, 0.025])
    ctrl = PositionController(1.0, J, FreeFlightGains())
    R = exp_so3([0.1, -0.2, 0.3])
    state = RigidBodyState(np.array([0.1, 0.0, 1.0]), np.array([0.2, -0.1, 0.0]),
                           rotmat_to_quat(R), np.array([0.3, 0.1, -0.2]))  # fmt: skip
    ref = PositionReference(np.zeros(3), a_W=np.array([0.5, 0.0, 0.0]))
    out = ctrl.update(state, ref)
    F, _ = ctrl.desired_force(state, ref)
    expected = ctrl.attitude.torque(state.R_WB, state.omega_B, rotation_from_z_and_yaw(F, 0.0))
    np.testing.assert_allclose(out.torque_B, expected, atol=1e-12)
    # zero jerk and snap: feed-forward of a hover-like reference changes nothing
    zero = PositionReference(np.zeros(3), a_W=ref.a_W, j_W=np.zeros(3), s_W=np.zeros(3))
    np.testing.assert_allclose(ctrl.update(state, zero).torque_B, expected, atol=1e-12)
    # a jerk changes the torque (the feed-forward is used)
    jerk = PositionReference(np.zeros(3), a_W=ref.a_W, j_W=np.array([0.0, 3.0, 0.0]))
    assert np.linalg.norm(ctrl.update(state, jerk).torque_B - expected) > 1e-3


def _estimate(p, R=None, v=None):
    R = np.eye(3) if R is None else R
    v = np.zeros(3) if v is None else v
    return StateEstimate(0.0, RigidBodyState(np.asarray(p, float), v, rotmat_to_quat(R),
                                             np.zeros(3)))  # fmt: skip


def test_tracker_modes_and_hover():
    tracker = FreeFlightTracker(SC20)
    assert isinstance(tracker, Controller)
    off = tracker.update(0.0, _estimate([0, 0, 1]), Reference(0.0, mode=ControlMode.MOTORS_OFF))
    assert np.all(off.rotor_speeds == 0.0)
    with pytest.raises(TetherlandError, match="TETHERED"):
        tracker.update(0.0, _estimate([0, 0, 1]), Reference(0.0, mode=ControlMode.TETHERED))
    hover = Reference(0.0, p_W=np.array([[0.0, 0.0, 1.0]]))
    cmd = tracker.update(0.0, _estimate([0, 0, 1]), hover)
    np.testing.assert_allclose(cmd.rotor_speeds, tracker.hover_speeds, rtol=1e-12)
    assert cmd.thrust == pytest.approx(SC20.vehicle.mass * g)


def test_lag_compensation_leads_a_rising_thrust():
    """Along a reference whose thrust rises, the lag-compensated speed command exceeds the
    uncompensated one from the second tick on (f_i' > 0 from the nominal thrusts)."""
    with_lag, without = FreeFlightTracker(SC20), FreeFlightTracker(SC20, lag_compensation=False)
    est = _estimate([0, 0, 1])
    dt = 1.0 / SC20.controller.rate_hz
    for k in range(3):
        t = k * dt
        rows = np.array([[0, 0, 1.0], [0, 0, 0], [0, 0, 2.0 * t], [0, 0, 2.0], [0, 0, 0]])
        a = with_lag.update(t, est, Reference(t, p_W=rows)).rotor_speeds
        b = without.update(t, est, Reference(t, p_W=rows)).rotor_speeds
        if k == 0:
            np.testing.assert_allclose(a, b)
        else:
            assert np.all(a > b + 1.0)


def test_reference_phases(traj20):
    sc = SC20
    w, h = sc.vehicle.lander_half_width, sc.vehicle.h_R
    geo_z = traj20.meta.z_S
    landers = LanderGeometry.create(w, h, geo_z, traj20.meta.p_L)
    ref = PerchingReference(traj20, landers, t_start=1.0, rest_time=0.5, contact_grace=0.05)
    assert isinstance(ref, ReferenceSource)
    far = _estimate(traj20.flat_outputs(0.0)[0])
    r0 = ref.reference(0.5, far)
    assert r0.mode is ControlMode.FREE_FLIGHT and r0.phase == PerchPhase.HOVER
    np.testing.assert_allclose(r0.p_W[1:], 0.0)
    r1 = ref.reference(1.5, far)
    assert r1.phase == PerchPhase.MANEUVER
    np.testing.assert_allclose(r1.p_W, traj20.reference_at(0.5)[0], atol=1e-12)
    # the plan models the believed drag: its rows carry it, the drag feed-forward keeps off
    assert traj20.meta.rotor_drag > 0.0 and r1.drag_in_rows
    # past t_L without contact: the touchdown thrust and attitude are held (constant a)
    T = traj20.duration
    r2 = ref.reference(1.0 + T + 0.02, far)
    assert r2.mode is ControlMode.FREE_FLIGHT
    np.testing.assert_allclose(r2.p_W[2], traj20.flat_outputs(T)[2])
    assert not r2.drag_in_rows  # the flat outputs' rows: the feed-forward adds the drag
    # grace over: motors off, then terminate after the rest
    r3 = ref.reference(1.0 + T + 0.06, far)
    assert r3.mode is ControlMode.MOTORS_OFF and not r3.terminate
    assert ref.reference(1.0 + T + 0.6, far).terminate
    assert [e.message.split(":")[0] for e in ref.events] == ["MANEUVER", "MOTORS_OFF"]


def test_reference_cuts_the_motors_on_estimated_contact(traj20):
    landers = LanderGeometry.create(0.15, 0.1, traj20.meta.z_S, traj20.meta.p_L)
    ref = PerchingReference(traj20, landers, t_start=0.0, rest_time=1.0)
    s = traj20.sample([traj20.duration])
    touching = _estimate(s.p_W[0, 0] - 1e-4 * traj20.meta.z_S, s.R_WB[0])  # 0.1 mm in
    r = ref.reference(0.5, touching)
    assert r.mode is ControlMode.MOTORS_OFF and ref.t_motors_off == 0.5
    assert "contact" in ref.events[-1].message


@pytest.mark.parametrize("drag", [True, False])
def test_the_reference_rows_of_a_tick_are_the_samples_numbers(traj20, drag):
    """``reference_at`` (once per control tick, a compiled call) gives ``sample``'s rows
    and thrust (numpy) bit for bit, with the believed rotor drag in the plan's model and
    without: before the start, at the nodes, between substeps, at t_L and after it; the
    continuation past t_L starts from the rows at t_L and is the same on every call."""
    if not drag:
        no_drag = load_scenario("slope50", ["surface.slope_deg=20", "controller.rotor_drag=[0, 0]"])
        traj20 = PerchingPlanner().plan(no_drag).require()
    assert (traj20.meta.rotor_drag > 0.0) == drag
    T = traj20.duration
    times = np.concatenate(([-0.3, 0.0, T, T + 0.2], traj20.times, np.linspace(0.0, T, 157)))
    for t in times:
        rows, thrust = traj20.reference_at(float(t))
        s = traj20.sample([t])
        assert rows.shape == (5, 3)
        np.testing.assert_array_equal(rows, s.reference_W[0])
        np.testing.assert_array_equal(traj20.flat_outputs(float(t)), s.p_W[0])
        assert thrust == s.thrust[0]
    end = traj20.sample([T]).p_W[0]
    first = traj20.continuation(0.05)
    np.testing.assert_array_equal(first[0], end[0] + end[1] * 0.05 + 0.5 * end[2] * 0.05**2)
    np.testing.assert_array_equal(first[2], end[2])
    np.testing.assert_array_equal(traj20.continuation(0.05), first)
