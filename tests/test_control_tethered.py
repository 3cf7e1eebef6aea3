"""Tethered controllers on the analytic taut-link model (issue 5, 'on the analytic model')."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.config import load_scenario
from tetherland.control import (
    DflController,
    FreeFlightController,
    HierarchicalController,
    SwitchingController,
)
from tetherland.geometry import LandingGeometry, theta_A_from_z_B
from tetherland.interfaces import Controller, ControlMode, Feedforward, Reference
from tetherland.planning import Planner
from tetherland.planning.tracking import TrajectoryTrack
from tetherland.rotations import exp_so3, quat_to_rotmat, rotmat_to_quat
from tetherland.sim.analytic import estimate_of, simulate_tethered

CENTRED = ["vehicle.cable_attachment=[0, 0, 0]"]  # the chapter's model: cable at the CoM


@pytest.fixture(scope="module")
def scenario():
    return load_scenario("slope50", CENTRED)


@pytest.fixture(scope="module")
def plans(scenario):
    planner = Planner()
    return {m: planner.plan(scenario, m).require() for m in ("landing", "takeoff")}


def start_state(traj, d_phi: float = 0.0, d_theta: float = 0.0) -> np.ndarray:
    nom, out = traj.nominal(0.0), traj.output(0.0)
    R = nom.R_WB @ exp_so3([0.0, d_theta, 0.0])
    return np.concatenate(
        ([out.phi[0] + d_phi, 0.0, out.phi[1], 0.0], rotmat_to_quat(R), nom.omega_B)
    )


def tracking_errors(scenario, run, track):
    geo = LandingGeometry.from_scenario(scenario)
    ref = np.array([track.reference(t).output[0] for t in run.t])
    theta = np.array(
        [theta_A_from_z_B(geo.R_WA.T @ quat_to_rotmat(x[4:8])[:, 2], x[0], x[1]) for x in run.x]
    )
    return (
        np.degrees(run.x[:, 0] - ref[:, 0]),
        np.degrees(theta - ref[:, 2]),
        np.degrees(run.x[:, 1]),
    )


@pytest.mark.parametrize("maneuver", ["landing", "takeoff"])
def test_hierarchical_tracks_the_plan(scenario, plans, maneuver):
    traj = plans[maneuver]
    track = TrajectoryTrack(traj, 0.0, 500.0)
    run = simulate_tethered(
        scenario,
        HierarchicalController(scenario),
        track.reference,
        start_state(traj),
        traj.duration + 0.5,
    )
    e_phi, e_theta, delta = tracking_errors(scenario, run, track)
    assert abs(e_phi[-1]) < 1.0 and abs(e_theta[-1]) < 1.0  # the bound
    assert np.abs(e_phi).max() < 0.05 and np.abs(e_theta).max() < 0.05  # what it reaches
    assert np.abs(delta).max() < 1e-6


def test_hierarchical_recovers_from_an_initial_offset(scenario, plans):
    traj = plans["landing"]
    track = TrajectoryTrack(traj, 0.0, 500.0)
    x0 = start_state(traj, d_phi=math.radians(3.0), d_theta=math.radians(-4.0))
    run = simulate_tethered(
        scenario, HierarchicalController(scenario), track.reference, x0, traj.duration + 1.0
    )
    e_phi, e_theta, _ = tracking_errors(scenario, run, track)
    assert abs(e_phi[0]) == pytest.approx(3.0, abs=1e-6)
    assert abs(e_phi[-1]) < 0.05 and abs(e_theta[-1]) < 0.05


def test_dfl_is_exact_up_to_integration_error(scenario, plans):
    """The tracking error is the discretisation error: it halves with the control period."""
    traj = plans["landing"]
    errors = []
    for control_dt in (4e-3, 2e-3):
        track = TrajectoryTrack(traj, 0.0, 1.0 / control_dt)
        ctrl = DflController(scenario, control_dt=control_dt)
        nom = traj.nominal(0.0)
        ctrl.reset(nom.f_R, nom.f_R_dot)
        run = simulate_tethered(
            scenario, ctrl, track.reference, start_state(traj), traj.duration, control_dt=control_dt
        )
        e_phi, e_theta, _ = tracking_errors(scenario, run, track)
        errors.append(max(np.abs(e_phi).max(), np.abs(e_theta).max()))
    assert errors[1] < 0.01
    assert errors[0] / errors[1] == pytest.approx(2.0, rel=0.25)


def test_dfl_error_dynamics_are_stable(scenario, plans):
    traj = plans["landing"]
    track = TrajectoryTrack(traj, 0.0, 500.0)
    ctrl = DflController(scenario)
    run = simulate_tethered(
        scenario,
        ctrl,
        track.reference,
        start_state(traj, d_phi=math.radians(2.0)),
        traj.duration + 1.0,
    )
    e_phi, e_theta, _ = tracking_errors(scenario, run, track)
    assert abs(e_phi[-1]) < 0.02 and abs(e_theta[-1]) < 0.05


def test_singular_reference_is_reported_not_divided(scenario, plans):
    traj = plans["landing"]
    x0 = start_state(traj)
    geo = LandingGeometry.from_scenario(scenario)
    est = estimate_of(x0, 0.0, geo, geo.link_length)
    out = np.zeros((5, 4))
    out[0] = [x0[0], 0.0, math.pi / 2 - x0[0], 0.0]  # thrust axis along the link
    ref = Reference(
        t=0.0,
        mode=ControlMode.TETHERED,
        output=out,
        feedforward=Feedforward(np.zeros(3), np.zeros(3), 9.81),
    )
    ctrl = HierarchicalController(scenario)
    cmd = ctrl.update(0.0, est, ref)
    assert cmd.diagnostics["singular"] == 1.0
    assert np.all(np.isfinite(cmd.rotor_speeds))


def test_offset_torque_is_compensated():
    """At inclined hover with the offset, the commanded torque cancels r_att x (-f_L d)."""
    sc = load_scenario("slope50")  # cable 3 cm below the centre of mass
    traj = Planner().plan(load_scenario("slope50", CENTRED), "landing").require()
    geo = LandingGeometry.from_scenario(sc)
    x = start_state(traj)
    est = estimate_of(x, 0.0, geo, geo.link_length)
    tension = 2.0
    est = type(est)(t=0.0, body=est.body, link=est.link, tension=tension)
    ref = TrajectoryTrack(traj, 0.0, 500.0).reference(0.0)
    with_offset = HierarchicalController(sc).update(0.0, est, ref)
    no_comp = HierarchicalController(
        load_scenario("slope50", ["controller.tethered.offset_compensation=false"])
    ).update(0.0, est, ref)
    R = quat_to_rotmat(x[4:8])
    d_B = R.T @ (geo.R_WA @ np.array([math.cos(x[0]), 0.0, math.sin(x[0])]))
    tau_L = np.cross(np.array(sc.vehicle.cable_attachment), -tension * d_B)
    np.testing.assert_allclose(with_offset.torque_B - no_comp.torque_B, -tau_L, atol=1e-9)
    assert abs(tau_L[1]) > 0.01  # a real pitch torque


@pytest.mark.parametrize(
    "factory", [FreeFlightController, HierarchicalController, DflController, SwitchingController]
)
def test_every_controller_implements_the_role(scenario, plans, factory):
    ctrl = factory(scenario)
    assert isinstance(ctrl, Controller)
    traj = plans["landing"]
    x0 = start_state(traj)
    geo = LandingGeometry.from_scenario(scenario)
    est = estimate_of(x0, 0.0, geo, geo.link_length)
    ref = TrajectoryTrack(traj, 0.0, 500.0).reference(0.0)
    if factory is FreeFlightController:
        ref = Reference(t=0.0, p_W=np.array([est.body.p_W, np.zeros(3), np.zeros(3)]))
    cmd = ctrl.update(0.0, est, ref)
    assert cmd.rotor_speeds.shape == (4,) and np.all(np.isfinite(cmd.rotor_speeds))
    assert cmd.thrust is not None and cmd.thrust > 0 and cmd.torque_B.shape == (3,)


@pytest.mark.parametrize("integral", [True, False])
def test_dfl_integral_removes_the_offset_of_a_mass_error(scenario, plans, integral):
    """A controller believing 5 % too much mass: the integral removes the steady error."""
    traj = plans["landing"]
    track = TrajectoryTrack(traj, 0.0, 500.0)
    flag = "true" if integral else "false"  # TOML booleans (strict types)
    believed = load_scenario(
        "slope50", [*CENTRED, "vehicle.mass=1.05", f"controller.tethered.dfl_integral={flag}"]
    )
    ctrl = DflController(believed)
    run = simulate_tethered(scenario, ctrl, track.reference, start_state(traj), traj.duration + 6.0)
    e_phi, e_theta, _ = tracking_errors(scenario, run, track)
    final = max(abs(e_phi[-1]), abs(e_theta[-1]))
    if integral:
        assert final < 0.02
    else:
        assert final > 1.0  # the law without it keeps an offset (13 deg here)


def test_dfl_restarts_from_motors_off_at_the_nominal_thrust(scenario, plans):
    """Motors off -> tethered: the extension starts at the plan's thrust, not at zero
    (where the decoupling matrix is singular)."""
    traj = plans["takeoff"]
    geo = LandingGeometry.from_scenario(scenario)
    est = estimate_of(start_state(traj), 0.0, geo, geo.link_length)
    ctrl = SwitchingController(scenario, "dfl")
    off = ctrl.update(0.0, est, Reference(t=0.0, mode=ControlMode.MOTORS_OFF))
    assert off.thrust == 0.0
    ref = TrajectoryTrack(traj, 0.002, 500.0).reference(0.002)
    on = ctrl.update(0.002, est, ref)
    assert on.diagnostics["singular"] == 0.0
    assert on.thrust == pytest.approx(traj.nominal(0.0).f_R, rel=0.02)



def test_tethered_to_free_flight_continues_the_commanded_force(scenario, plans):
    """Tethered -> free flight (the release, an abort): the free-flight integral starts at
    the force the tethered law was commanding minus the free-flight law's own, so the first
    free-flight command is the last tethered force (bumpless); a plain reset would drop
    what the tethered law held (here the plan's 2 N start tension)."""
    traj = plans["landing"]
    geo = LandingGeometry.from_scenario(scenario)
    est = estimate_of(start_state(traj), 0.0, geo, geo.link_length)
    # a clamp of 0.5 m g per axis holds the start tension's 2.3 N along x_W
    wide = load_scenario("slope50", [*CENTRED, "controller.free_flight.integral_force_max=0.5"])
    ctrl = SwitchingController(wide)
    last = ctrl.update(0.0, est, TrajectoryTrack(traj, 0.0, 500.0).reference(0.0))
    F_last = last.thrust * quat_to_rotmat(est.body.q_WB)[:, 2]
    hold = Reference(t=0.002, p_W=np.array([est.body.p_W, np.zeros(3), np.zeros(3)]))
    first = ctrl.update(0.002, est, hold)
    pos = ctrl.free_flight.position
    bound = pos.integral_max
    assert np.all(np.abs(pos.integral_force) < bound)  # not clamped: the premise
    assert first.thrust == pytest.approx(last.thrust, rel=1e-3)
    # the desired force is the last one: integral + m (g z_W - k_v v), v from the estimate
    m = scenario.vehicle.mass
    F_0 = m * (GRAVITY * np.array([0.0, 0.0, 1.0]) - pos.k_v * est.body.v_W)
    np.testing.assert_allclose(pos.integral_force + F_0, F_last, atol=1e-9)
    # a plain reset (from motors off) would start at F_0: off by the cable's pull, the
    # plan's start tension (the plan starts at rest in inclined hovering: F - m g z_W = T d)
    assert np.linalg.norm(F_last - F_0) == pytest.approx(scenario.planner.start_tension, rel=1e-9)
    ctrl.free_flight.reset()
    np.testing.assert_array_equal(pos.integral_force, 0.0)


def _tethered_force_W(ctrl: HierarchicalController, est) -> np.ndarray:
    """The desired force F_d of the tethered law's last update [N, F_W]: its direction is
    the desired attitude's z axis and its projection on the estimated z_B the thrust (the
    law's state, :mod:`tetherland.control.kernels.hierarchical`)."""
    from tetherland.control.kernels import hierarchical as kernel

    R_d = ctrl._state[kernel.STATE_R_D].reshape(3, 3)
    z_B = quat_to_rotmat(est.body.q_WB)[:, 2]
    return ctrl._state[kernel.STATE_THRUST] / float(R_d[:, 2] @ z_B) * R_d[:, 2]


@pytest.mark.parametrize("hand_over", [True, False])
def test_free_flight_to_tethered_continues_the_commanded_force(scenario, plans, hand_over):
    """Free flight -> tethered (the stretch's end), ``integral_hand_over`` on: the link
    integral starts where the first tethered command continues the last free-flight
    force across the link (its y_L and z_L components; along x_L the cable takes the
    rest). The free-flight integral here holds a model error B (a believed mass 4 % heavy
    and a sideways push); off (the default), a plain reset starts at the plan's nominal
    force f_n z_B (the law reproduces its own plan at the start, the cable at the centre
    of mass), so it drops (F_last . z_B - f_n) z_B across the link, to be integrated
    again on the way down."""
    from tetherland.geometry import link_frame

    traj = plans["landing"]
    geo = LandingGeometry.from_scenario(scenario)
    est = estimate_of(start_state(traj), 0.0, geo, geo.link_length)
    m = scenario.vehicle.mass
    B = m * GRAVITY * np.array([0.0, 0.03, -0.04])
    flag = f"controller.tethered.integral_hand_over={str(hand_over).lower()}"
    ctrl = SwitchingController(load_scenario("slope50", [*CENTRED, flag]))
    ctrl.free_flight.position.seed_integral(B)
    hold = Reference(t=0.0, p_W=np.array([est.body.p_W, np.zeros(3), np.zeros(3)]))
    last = ctrl.update(0.0, est, hold)
    F_last = last.thrust * quat_to_rotmat(est.body.q_WB)[:, 2]
    tethered = ctrl.tethered
    assert isinstance(tethered, HierarchicalController)
    ctrl.update(0.002, est, TrajectoryTrack(traj, 0.002, 500.0).reference(0.002))
    F_d = _tethered_force_W(tethered, est)
    L_W = geo.R_WA @ link_frame(est.link.phi, est.link.delta)  # columns x_L, y_L, z_L
    across = L_W[:, 1:].T
    if hand_over:
        np.testing.assert_allclose(across @ F_d, across @ F_last, atol=1e-9)
    else:  # the reset start misses the model error's part across the link
        z_B = quat_to_rotmat(est.body.q_WB)[:, 2]
        dropped = (last.thrust - traj.nominal(0.0).f_R) * (across @ z_B)
        np.testing.assert_allclose(across @ (F_last - F_d), dropped, atol=1e-6)
        assert np.linalg.norm(dropped) > 0.2


def test_lateral_free_leaves_the_link_azimuth_to_gravity(scenario, plans):
    """Reference.lateral_free: at rest 3 deg off the plumb plane (delta = 0.05 rad,
    delta' = 0) and with a delta integral built up, the desired thrust axis lies in the
    link plane (u_y = m l k_d delta' = 0), whatever the reference's delta; tracked, the
    same state asks for the sideways force m g sin(phi) sin(delta) - m l v_delta, a
    tilt of its ratio to the thrust out of the plane."""
    from dataclasses import replace

    from tetherland.geometry import link_frame

    traj = plans["landing"]
    geo = LandingGeometry.from_scenario(scenario)
    x0 = start_state(traj)
    x0[1] = 0.05  # delta [rad]
    est = estimate_of(x0, 0.0, geo, geo.link_length)
    out = np.zeros((5, 4))
    theta = theta_A_from_z_B(geo.R_WA.T @ quat_to_rotmat(x0[4:8])[:, 2], x0[0], 0.0)
    out[0] = [x0[0], 0.0, theta, 0.0]  # the reference at the plumb plane, delta_d = 0
    ff = Feedforward(np.zeros(3), np.zeros(3), 9.81)
    ref = Reference(t=0.0, mode=ControlMode.TETHERED, output=out, feedforward=ff)

    def out_of_plane(lateral_free: bool) -> float:
        ctrl = HierarchicalController(scenario)
        ctrl._state[1] = 0.05  # a delta integral [rad s]
        ctrl._state[2] = 0.0
        ctrl.update(0.0, est, replace(ref, lateral_free=lateral_free))
        R_d = ctrl._state[5:14].reshape(3, 3)
        y_L = link_frame(x0[0], x0[1])[:, 1]
        return float((geo.R_WA.T @ R_d[:, 2]) @ y_L)

    assert abs(out_of_plane(True)) < 1e-9
    v = scenario.vehicle
    k_p = scenario.controller.tethered.link_frequency**2
    k_i = scenario.controller.tethered.link_integral
    u_y = v.mass * GRAVITY * math.sin(x0[0]) * math.sin(0.05) - v.mass * geo.link_length * (
        k_p * (0.0 - 0.05) + k_i * 0.05
    )
    assert abs(out_of_plane(False)) > 0.5 * abs(u_y) / (v.mass * GRAVITY)


def test_lateral_free_keeps_a_fraction_of_the_link_damping(scenario, plans):
    """Left to gravity, the only sideways force is the damping c m l k_d delta' with c =
    ``controller.tethered.lateral_damping``: the out-of-plane tilt of the desired thrust
    axis scales with c (half the damping, half the tilt; none without it)."""
    from tetherland.config import with_overrides
    from tetherland.geometry import link_frame

    traj = plans["landing"]
    geo = LandingGeometry.from_scenario(scenario)
    x0 = start_state(traj)
    x0[1], x0[3] = 0.05, 0.1  # delta [rad], delta' [rad/s]
    est = estimate_of(x0, 0.0, geo, geo.link_length)
    out = np.zeros((5, 4))
    theta = theta_A_from_z_B(geo.R_WA.T @ quat_to_rotmat(x0[4:8])[:, 2], x0[0], 0.0)
    out[0] = [x0[0], 0.0, theta, 0.0]
    ref = Reference(t=0.0, mode=ControlMode.TETHERED, output=out, lateral_free=True,
                    feedforward=Feedforward(np.zeros(3), np.zeros(3), 9.81))  # fmt: skip

    def out_of_plane(c: float) -> float:
        sc = with_overrides(scenario, [f"controller.tethered.lateral_damping={c}"])
        ctrl = HierarchicalController(sc)
        ctrl.update(0.0, est, ref)
        R_d = ctrl._state[5:14].reshape(3, 3)
        return float((geo.R_WA.T @ R_d[:, 2]) @ link_frame(x0[0], x0[1])[:, 1])

    full, half = out_of_plane(1.0), out_of_plane(0.5)
    assert abs(full) > 1e-3  # the premise: damping 0.1 rad/s tilts the axis
    assert half == pytest.approx(0.5 * full, rel=0.02)
    assert abs(out_of_plane(0.0)) < 1e-9


def test_taking_the_azimuth_back_adds_no_sideways_step(scenario, plans):
    """The lateral lock hands the azimuth back to the law (lateral_free True, then False):
    at rest in the plumb plane (delta = delta' = 0) with a delta integral I built up before
    the release, the free tick asks for no sideways force (the free rows cancel k_i I), and
    so does the first held tick at delta_d = delta: the integral the free rows cancelled is
    dropped, not returned in one tick as the sideways force m l k_i I (a tilt of about
    l k_i I / g out of the link plane, which a controller never released still asks for).
    The phi integral is kept."""
    from dataclasses import replace

    from tetherland.control.kernels import hierarchical as kernel
    from tetherland.geometry import link_frame

    traj = plans["landing"]
    geo = LandingGeometry.from_scenario(scenario)
    x0 = start_state(traj)
    x0[1], x0[3] = 0.0, 0.0  # in the plumb plane, at rest sideways
    est = estimate_of(x0, 0.0, geo, geo.link_length)
    out = np.zeros((5, 4))
    theta = theta_A_from_z_B(geo.R_WA.T @ quat_to_rotmat(x0[4:8])[:, 2], x0[0], 0.0)
    out[0] = [x0[0], 0.0, theta, 0.0]
    ref = Reference(t=0.0, mode=ControlMode.TETHERED, output=out,
                    feedforward=Feedforward(np.zeros(3), np.zeros(3), 9.81))  # fmt: skip
    integral = np.array([0.02, 0.05])  # [rad s]
    y_L = link_frame(x0[0], x0[1])[:, 1]

    def out_of_plane(ctrl: HierarchicalController) -> float:
        R_d = ctrl._state[kernel.STATE_R_D].reshape(3, 3)
        return float((geo.R_WA.T @ R_d[:, 2]) @ y_L)

    def built_up() -> HierarchicalController:
        ctrl = HierarchicalController(scenario)
        ctrl._state[kernel.STATE_INTEGRAL] = integral
        ctrl._state[kernel.STATE_T_LAST] = 0.0
        return ctrl

    never_free = built_up()
    never_free.update(0.002, est, replace(ref, t=0.002))
    k_i = scenario.controller.tethered.link_integral
    tilt = geo.link_length * k_i * integral[1] / GRAVITY
    assert abs(out_of_plane(never_free)) > 0.5 * tilt  # the premise: the integral's step
    locked = built_up()
    locked.update(0.002, est, replace(ref, t=0.002, lateral_free=True))
    assert abs(out_of_plane(locked)) < 1e-9  # free: nothing sideways
    locked.update(0.004, est, replace(ref, t=0.004))  # the lock: delta_d = delta
    assert abs(out_of_plane(locked)) < 1e-9  # held: still nothing sideways
    assert locked._state[kernel.STATE_INTEGRAL][1] == 0.0
    assert locked._state[kernel.STATE_INTEGRAL][0] != 0.0  # phi's integral kept
