"""The controllers' model of the rotors near surfaces and of the rotor drag, from the
belief (issue 23): the ground-effect compensation leads the motor lag, the believed
rotor drag is a feed-forward of the reference. Expected values derived here."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.config import load_scenario
from tetherland.control.ground_effect import GroundEffectCompensation
from tetherland.control.rotor_drag import (
    RotorDragCompensation,
    drag_acceleration,
    link_drag_acceleration,
)
from tetherland.estimation.ground_effect import BelievedGroundEffect
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import Command, ControlMode, Reference, StateEstimate
from tetherland.rotations import rotation_from_z_and_yaw, rotmat_to_quat
from tetherland.state import RigidBodyState


class Recorder:
    """A controller that returns fixed rotor speeds and keeps the reference it was given."""

    def __init__(self, speeds):
        self.speeds = np.asarray(speeds, dtype=float)
        self.seen: list[Reference] = []

    def update(self, t, estimate, reference):
        self.seen.append(reference)
        return Command(rotor_speeds=self.speeds.copy())


def estimate_at(p_W, R_WB, v_W=(0.0, 0.0, 0.0), omega_B=(0.0, 0.0, 0.0)):
    body = RigidBodyState(
        p_W=np.asarray(p_W, dtype=float), v_W=np.asarray(v_W, dtype=float),
        q_WB=rotmat_to_quat(R_WB), omega_B=np.asarray(omega_B, dtype=float),
    )  # fmt: skip
    return StateEstimate(t=0.0, body=body)


def test_compensation_uses_the_factor_one_motor_lag_ahead():
    """Approaching the believed slope at 0.5 m/s along -z_S, aligned with it: the command is
    w / sqrt(k) with k at p + v tau_m (not at p): the factor rises over the lag."""
    sc = load_scenario("slope50")
    geo = LandingGeometry.from_scenario(sc)
    z_S = geo.surface.z_S
    R = rotation_from_z_and_yaw(z_S, 0.0)
    p = geo.p_L + 0.16 * z_S
    v = -0.5 * z_S
    w = np.full(4, 500.0)
    ctrl = GroundEffectCompensation(Recorder(w), sc)
    cmd = ctrl.update(0.0, estimate_at(p, R, v), Reference(t=0.0))
    tau = sc.vehicle.motor_time_constant
    belief = BelievedGroundEffect(sc)
    k_ahead = belief.factors_at(p + tau * v, rotmat_to_quat(R)).copy()
    k_now = belief.factors_at(p, rotmat_to_quat(R)).copy()
    assert np.all(k_ahead > k_now + 1e-4)  # closer to the surface: a larger factor
    np.testing.assert_allclose(cmd.rotor_speeds, w / np.sqrt(k_ahead), rtol=1e-12)
    # at rest the prediction is the present pose
    cmd0 = ctrl.update(0.0, estimate_at(p, R), Reference(t=0.0))
    np.testing.assert_allclose(cmd0.rotor_speeds, w / np.sqrt(k_now), rtol=1e-12)


def test_compensation_passes_the_command_through_beyond_the_rotors_reach():
    """Beyond FAR_RATIO rotor radii from the believed slope the command is the inner
    controller's own (every factor 1, nothing evaluated); the cut-off costs less than the
    Cheeseman-Bennett factor there, 1 / (1 - (R / 4z)^2) - 1 < 2e-4 for z >= 20 R - reach."""
    from tetherland.estimation.ground_effect import FAR_RATIO, PATCH_HALF_THICKNESS
    from tetherland.models.aero import rotor_disks

    sc = load_scenario("slope50")
    geo = LandingGeometry.from_scenario(sc)
    z_S = geo.surface.z_S
    R = rotation_from_z_and_yaw(z_S, 0.0)
    centres, radius = rotor_disks(sc.vehicle)
    reach = float(np.max(np.linalg.norm(centres, axis=1))) + radius
    # the believed patch is a slab: its distance is taken conservatively from its far face
    reach += 2.0 * PATCH_HALF_THICKNESS
    w = np.full(4, 500.0)
    inner = Recorder(w)
    ctrl = GroundEffectCompensation(inner, sc)
    belief = BelievedGroundEffect(sc)
    far = geo.p_L + (FAR_RATIO * radius + reach + 0.05) * z_S
    assert belief.beyond_reach(far)
    cmd = ctrl.update(0.0, estimate_at(far, R), Reference(t=0.0))
    np.testing.assert_array_equal(cmd.rotor_speeds, w)
    # just inside the reach the model is evaluated: factors above 1 by less than the bound
    near = geo.p_L + (FAR_RATIO * radius + reach - 0.05) * z_S
    assert not belief.beyond_reach(near)
    k_near = belief.factors_at(near, rotmat_to_quat(R)).copy()
    z_min = FAR_RATIO * radius - 0.05  # the nearest rotor is at least this far [m]
    bound = 1.0 / (1.0 - (radius / (4.0 * z_min)) ** 2) - 1.0
    assert bound < 2e-4
    assert np.all(k_near > 1.0) and np.all(k_near - 1.0 <= bound)


def test_drag_acceleration_is_the_drag_in_the_rotor_plane_scaled_with_rotor_speed():
    d = np.array([0.45, 0.3])
    m = 1.2
    # level, hovering thrust (a = 0): exactly D v / m in the rotor plane, none along z_B
    a = drag_acceleration(np.eye(3), np.array([1.0, -2.0, 3.0]), np.zeros(3), d, m)
    np.testing.assert_allclose(a, [0.45 / m, -0.6 / m, 0.0], atol=1e-15)
    # tilted 30 deg about y: only the velocity in the rotor plane counts
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    R = np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])
    v = 0.7 * R[:, 2] + 1.1 * R[:, 0]  # along z_B (no drag) and x_B
    a = drag_acceleration(R, v, np.zeros(3), d, m)
    np.testing.assert_allclose(a, 0.45 * 1.1 / m * R[:, 0], atol=1e-15)
    # twice the hover thrust: rotor speed sqrt(2) times hover, drag sqrt(2) times larger
    a2 = drag_acceleration(np.eye(3), np.array([1.0, 0.0, 0.0]), np.array([0, 0, GRAVITY]), d, m)
    assert a2[0] == pytest.approx(math.sqrt(2.0) * 0.45 / m, rel=1e-12)


def test_drag_feedforward_goes_on_the_acceleration_and_jerk_rows():
    sc = load_scenario("slope50", ["controller.rotor_drag=[0.4, 0.4]"])
    m = sc.vehicle.mass
    inner = Recorder(np.full(4, 500.0))
    ctrl = RotorDragCompensation(inner, sc)
    rows = np.array([[1.0, 2.0, 3.0], [1.5, 0.0, 0.0], [0.0, 0.0, 0.0], [-2.0, 0.0, 0.0]])
    est = estimate_at([0, 0, 1], np.eye(3))
    ctrl.update(0.0, est, Reference(t=0.0, p_W=rows))
    got = inner.seen[-1].p_W
    np.testing.assert_array_equal(got[0:2], rows[0:2])  # position and velocity untouched
    np.testing.assert_allclose(got[2], [0.4 * 1.5 / m, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(got[3], [-2.0, 0.0, 0.0], atol=1e-15)  # a_ref = 0: no rate
    assert rows[2, 0] == 0.0  # the caller's rows are not changed
    # a position-only reference (hover) and no reference pass through untouched
    ctrl.update(0.0, est, Reference(t=0.0, p_W=rows[:1]))
    assert inner.seen[-1].p_W is not None and inner.seen[-1].p_W.shape == (1, 3)
    ctrl.update(0.0, est, Reference(t=0.0))
    assert inner.seen[-1].p_W is None
    # rows from a plan that models the drag (the thrust's rows) are not given it twice
    planned = Reference(t=0.0, p_W=rows, drag_in_rows=True)
    ctrl.update(0.0, est, planned)
    assert inner.seen[-1] is planned


@pytest.mark.parametrize("name", ["slope50", "pipe60"])
def test_the_reach_distance_is_the_distance_to_the_slab_or_the_pipe_axis(name):
    """The scalar distance bound of the reach test against the geometry written plainly:
    the slab's far face along z_S, or the infinite cylinder of the pipe."""
    from tetherland.estimation.ground_effect import PATCH_HALF_THICKNESS
    from tetherland.geometry import surface_from_config

    sc = load_scenario(name)
    surf = surface_from_config(sc)
    belief = BelievedGroundEffect(sc)
    rng = np.random.default_rng(3)
    for p in surf.origin + rng.normal(0.0, 2.0, (50, 3)):
        d = p - surf.origin
        if surf.kind == "pipe":
            r = surf.pipe_radius
            radial = d - (d @ surf.x_S) * surf.x_S + r * surf.z_S  # from the axis
            expected = np.linalg.norm(radial) - r
        else:
            expected = abs(d @ surf.z_S) - 2.0 * PATCH_HALF_THICKNESS
        assert belief._distance(p) == pytest.approx(expected, abs=1e-12)


def test_link_drag_acceleration_cancels_the_drag_across_the_link():
    """Link vertical above the anchor (phi = 90 deg, delta = 0, F_A = F_W), level vehicle:
    phi' = w moves the link end along z_L = -x_W at l w, delta' = u along -y_L = -y_W at
    l u, both in the rotor plane. The drag D = (d_x l w, d_y l u, 0) decelerates them by
    phi'' = -d_x w / m and delta'' = -d_y u / m (m l phi'' = F.z_L, m l delta'' = -F.y_L),
    so the feed-forward is (+d_x w / m, +d_y u / m); at 4 m g of thrust the rotors spin
    twice as fast and the drag doubles."""
    d = np.array([0.45, 0.3])
    m, l, w, u = 1.3, 1.1, 0.7, -0.4
    Y = np.zeros((3, 4))
    Y[0, 0] = math.pi / 2
    Y[1, 0], Y[1, 1] = w, u
    a = link_drag_acceleration(np.eye(3), np.eye(3), Y, m * GRAVITY, d, m, l)
    assert a == pytest.approx((d[0] * w / m, d[1] * u / m), rel=1e-12, abs=1e-15)
    a4 = link_drag_acceleration(np.eye(3), np.eye(3), Y, 4 * m * GRAVITY, d, m, l)
    assert a4 == pytest.approx((2 * d[0] * w / m, 2 * d[1] * u / m), rel=1e-12, abs=1e-15)
    # link horizontal (phi = 0): phi' moves the end along z_W = z_B, no drag in the plane
    Y[0, 0], Y[1, 1] = 0.0, 0.0
    assert link_drag_acceleration(np.eye(3), np.eye(3), Y, m * GRAVITY, d, m, l) == (
        pytest.approx(0.0, abs=1e-15), pytest.approx(0.0, abs=1e-15))  # fmt: skip


def test_tethered_references_get_the_drag_on_their_acceleration_row():
    sc = load_scenario("slope50", ["controller.rotor_drag=[0.4, 0.4]"])
    geo = LandingGeometry.from_scenario(sc)
    inner = Recorder(np.full(4, 500.0))
    ctrl = RotorDragCompensation(inner, sc)
    Y = np.zeros((5, 4))
    Y[0] = [geo.phi_star + 0.3, 0.02, geo.theta_A_star, 0.0]
    Y[1, 0], Y[1, 1] = -0.4, 0.05
    est = estimate_at(geo.p_L + 0.5 * geo.surface.z_S, geo.R_WA)
    ref = Reference(t=0.0, mode=ControlMode.TETHERED, output=Y, thrust_ff=9.0)
    ctrl.update(0.0, est, ref)
    got = inner.seen[-1].output
    a_phi, a_delta = link_drag_acceleration(geo.R_WA, geo.R_WA, Y, 9.0, np.array([0.4, 0.4]),
                                            sc.vehicle.mass, geo.link_length)  # fmt: skip
    np.testing.assert_array_equal(got[[0, 1, 3, 4]], Y[[0, 1, 3, 4]])
    assert got[2, 0] == a_phi and got[2, 1] == a_delta and a_phi != 0.0
    assert np.all(Y[2] == 0.0)  # the caller's rows are not changed
    # switched off: the tethered reference passes through
    off = RotorDragCompensation(inner, load_scenario(
        "slope50", ["controller.rotor_drag=[0.4, 0.4]", "controller.rotor_drag_tethered=false"]))
    off.update(0.0, est, ref)
    assert inner.seen[-1] is ref
