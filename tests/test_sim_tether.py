"""Cable, contacts and friction of the plant against the models of docs/theory.md sections 4-5."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tetherland import GRAVITY
from tetherland.analysis.statics import contact_forces, tethered_rest_tension
from tetherland.config import load_scenario
from tetherland.models.tethered import (
    link_dynamics,
    link_position_velocity,
    tethered_rhs,
    thrust_in_link_frame,
)
from tetherland.rotations import quat_to_rotmat, rotvec_to_quat
from tetherland.sim.plant import Plant
from tetherland.state import RigidBodyState

IDEAL = 'tether.material="ideal"'
"""The chapter's inextensible cable, which these tests compare with its models."""
SWING_ANGLE_TOL = 2e-3
"""|phi - phi_model|, |delta - delta_model| over 2 s [rad]; measured 7e-4 / 1.3e-4 at
dt = 1 ms, halving at dt = 0.5 ms (first-order integrator error)."""
SWING_RATE_TOL = 2e-3
"""Angular-rate error [rad/s]; measured 6e-4."""
SWING_TENSION_TOL = 0.15
"""Tension error [N] (2-3 % of the 4.4-8 N swing tension); measured 0.06 N, from the
cable compliance (``sim.cable_time_constant`` = 4 ms)."""


def test_tethered_swing_matches_the_3d_link_model():
    """Cable engaged at the CoM (r_att = 0), constant tilted thrust: (phi, delta) follow
    models/tethered.py integrated by scipy with the same thrust vector."""
    # the link model has a constant thrust: no rotor drag, no ground effect of the swing
    # near the ground (the aero effects are tested in test_sim_aero.py)
    sc = load_scenario(
        "flat",
        [
            "vehicle.cable_attachment=[0,0,0]",
            IDEAL,
            "aero.rotor_drag=[0, 0]",
            "aero.ground_effect=false",
        ],
    )
    plant = Plant(sc)
    geo = plant.layout.geometry
    m, l = sc.vehicle.mass, sc.tether.length
    x0 = np.array([math.radians(70.0), 0.3, 0.0, -0.2])
    q_WB = rotvec_to_quat([0.15, -0.1, 0.0])  # tilted: thrust has x_A and y_A components
    f_R = 1.5 * m * GRAVITY
    w = math.sqrt(f_R / 4 / sc.vehicle.thrust_coefficient)
    r_A, v_A = link_position_velocity(x0, l)
    start = RigidBodyState(geo.p_A + geo.R_WA @ r_A, geo.R_WA @ v_A, q_WB, np.zeros(3))
    plant.reset(start, rotor_speeds=np.full(4, w), cable_engaged=True)
    thrust_A = geo.R_WA.T @ (f_R * quat_to_rotmat(q_WB)[:, 2])
    T = 2.0
    sol = solve_ivp(
        lambda t, x: tethered_rhs(x, thrust_A, m, l),
        (0.0, T),
        x0,
        method="DOP853",
        rtol=1e-11,
        atol=1e-12,
        dense_output=True,
    )
    worst = np.zeros(5)
    for _ in range(200):
        plant.step(10)
        y = sol.sol(plant.time)
        link = plant.link_state()
        # the tension sensor refers to the start of the last step
        ys = sol.sol(plant.time - plant.dt)
        f_L = link_dynamics(*ys, thrust_in_link_frame(thrust_A, ys[0], ys[1]), m, l).tension
        assert f_L > 1.0  # the model's cable stays taut: the comparison is meaningful
        err = np.abs(
            [
                link.phi - y[0],
                link.delta - y[1],
                link.phi_dot - y[2],
                link.delta_dot - y[3],
                plant.tension - f_L,
            ]
        )
        worst = np.maximum(worst, err)
    assert np.ptp(sol.sol(np.linspace(0, T, 50))[0]) > 1.0  # a real swing (> 57 deg)
    assert worst[0] < SWING_ANGLE_TOL and worst[1] < SWING_ANGLE_TOL, worst
    assert worst[2] < SWING_RATE_TOL and worst[3] < SWING_RATE_TOL, worst
    assert worst[4] < SWING_TENSION_TOL, worst
    assert plant.frame_contact_force == 0.0 and not np.any(plant.lander_forces)


def test_rest_tension_on_a_50_degree_slope_equals_the_force_balance():
    """Landed at p*_L, motors off, cable holding: f_L = -m g (x_S.z_W)/(x_S.d~) (6.14),
    = m g sin(beta)/cos(gamma) since x_S.d~ = cos(gamma). Soft static friction creeps to
    zero, so the cable ends up carrying the whole downhill load (the inextensible cable:
    an elastic one stops where friction holds it, tests/test_tether.py)."""
    sc = load_scenario("slope50", [IDEAL])
    plant = Plant(sc)
    geo = plant.layout.geometry
    expected = tethered_rest_tension(geo.surface, geo.d_tilde, sc.vehicle.mass)
    beta, gamma = math.radians(50.0), geo.gamma
    assert expected == pytest.approx(sc.vehicle.mass * GRAVITY * math.sin(beta) / math.cos(gamma))
    assert expected == pytest.approx(7.5334, abs=1e-4)  # h_att = 0.07 m: gamma = 4.01 deg
    land = plant.landed_state()
    plant.reset(land, cable_engaged=True)
    plant.step(4000)
    assert plant.tension == pytest.approx(expected, rel=1e-3)
    assert np.linalg.norm(plant.state().p_W - land.p_W) < 1e-3
    assert np.all(plant.lander_forces > 0.5)
    # The contact carries the rest: normal force of (6.5) with this tension, no friction.
    balance = contact_forces(
        geo.surface, sc.vehicle.mass, 0.0, geo.surface.z_S, expected, geo.d_tilde
    )
    assert balance.holds and np.linalg.norm(balance.f_S) < 1e-9
    assert plant.lander_forces.sum() == pytest.approx(balance.f_N, rel=2e-3)


@pytest.mark.parametrize(
    ("slope_deg", "mu", "slides"),
    [(50.0, 0.6, True), (35.0, 0.6, True), (30.0, 0.6, False), (50.0, 1.5, False)],
)
def test_without_cable_slides_iff_tan_beta_exceeds_mu(slope_deg, mu, slides):
    """Motors off, cable disengaged: sliding when tan(beta) > mu with
    a = g (sin(beta) - mu cos(beta)) (within 5 %); at rest otherwise (< 1 mm in 2 s)."""
    sc = load_scenario("slope50", [f"surface.slope_deg={slope_deg}", f"surface.friction={mu}"])
    plant = Plant(sc)
    x_S = plant.layout.geometry.surface.x_S
    land = plant.landed_state()
    plant.reset(land)
    plant.step(200)  # settle into contact
    s0, v0 = x_S @ (plant.state().p_W - land.p_W), x_S @ plant.state().v_W
    plant.step(800)
    s1 = x_S @ (plant.state().p_W - land.p_W)
    beta = math.radians(slope_deg)
    if slides:
        a = GRAVITY * (math.sin(beta) - mu * math.cos(beta))
        assert s1 - s0 == pytest.approx(v0 * 0.8 + 0.5 * a * 0.8**2, rel=0.05)
    else:
        plant.step(1000)
        assert abs(x_S @ (plant.state().p_W - land.p_W)) < 1e-3


def test_vehicle_rests_on_the_pipe_on_its_four_landers():
    """pipe60: landed astride the top line, motors off, cable holding: all four landers
    carry load, no slip after settling, tension as (6.14) (pipe normals have no x_S part)."""
    sc = load_scenario("pipe60", [IDEAL])
    plant = Plant(sc)
    geo = plant.layout.geometry
    land = plant.landed_state()
    plant.reset(land, cable_engaged=True)
    plant.step(1000)
    p1 = plant.state().p_W
    plant.step(2000)
    p3 = plant.state().p_W
    forces = plant.lander_forces
    assert np.all(forces > 0.5), forces
    assert plant.frame_contact_force == 0.0
    assert np.linalg.norm(p3 - p1) < 1e-4  # no slip once settled
    assert np.linalg.norm(p3 - land.p_W) < 5e-3  # settling into the contacts only
    expected = tethered_rest_tension(geo.surface, geo.d_tilde, sc.vehicle.mass)
    assert plant.tension == pytest.approx(expected, rel=2e-3)
