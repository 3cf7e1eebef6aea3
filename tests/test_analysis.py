"""Landing analysis (issue 2, item 4): statics by force balance, corrected chapter
formulas, slope limits, conditions (1)-(5) and Table 6.1."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherland import GRAVITY as g
from tetherland.analysis import (
    LandingTolerances,
    VehicleLimits,
    analyze,
    analyze_free_flight,
    condition_1,
    condition_2,
    condition_3,
    condition_4,
    condition_5_observed,
    condition_5_static,
    contact_forces,
    evaluate_landing,
    free_flight_max_touchdown_thrust,
    hover_tilt_for_tension,
    inclined_hover,
    landing_hover,
    tethered_max_touchdown_thrust,
    tethered_rest_tension,
    touchdown_index,
)
from tetherland.config import load_scenario
from tetherland.errors import SingularityError
from tetherland.geometry import inclined_hover_direction, link_direction
from tetherland.surface import Surface, normal_from_slope, surface_frame


def plane(beta_deg: float, mu: float = 0.6, f_N_min: float = 0.0) -> Surface:
    R = surface_frame(normal_from_slope(math.radians(beta_deg)))
    return Surface(origin=np.zeros(3), R_WS=R, friction=mu, f_N_min=f_N_min)


# --- inclined hovering ---------------------------------------------------------------------


def test_worked_example_hover_thrust_and_tension():
    f_R, f_L = landing_hover(math.radians(50), 0.1, 1.0)
    assert f_R == pytest.approx(7.061, abs=5e-4)
    assert f_L == pytest.approx(7.553, abs=5e-4)


@settings(max_examples=200, deadline=None)
@given(st.floats(-1.4, 1.4), st.floats(-1.2, 1.2), st.floats(0.1, 5.0))
def test_inclined_hover_is_a_force_balance(phi: float, theta: float, mass: float):
    if abs(math.cos(phi + theta)) < 0.05:
        return
    f_R, f_L = inclined_hover(phi, theta, mass)
    z_B = np.array([math.sin(theta), 0.0, math.cos(theta)])  # in F_A
    d = link_direction(phi, 0.0)
    residual = f_R * z_B - f_L * d - mass * g * np.array([0.0, 0.0, 1.0])
    np.testing.assert_allclose(residual, 0.0, atol=1e-9 * (1 + abs(f_R) + abs(f_L)))


@settings(max_examples=100, deadline=None)
@given(st.floats(-1.3, 1.3), st.floats(0.01, 20.0))
def test_hover_tilt_for_tension_inverts_inclined_hover(phi: float, tension: float):
    theta = hover_tilt_for_tension(phi, tension, 1.0)
    _, f_L = inclined_hover(phi, theta, 1.0)
    assert f_L == pytest.approx(tension, rel=1e-9)


def test_inclined_hover_singularity_is_reported():
    with pytest.raises(SingularityError, match="parallel to the link"):
        inclined_hover(0.3, math.pi / 2 - 0.3, 1.0)


def test_landing_hover_matches_planar_formula_at_phi_star():
    beta, c = math.radians(63.0), 0.12
    gamma = math.asin(c)
    assert landing_hover(beta, c, 1.3) == pytest.approx(inclined_hover(gamma - beta, beta, 1.3))


# --- contact: corrected (6.6), (6.7), (6.14)-(6.16) ------------------------------------------


@pytest.mark.parametrize("f_R", [0.0, 1.0, 3.0])
def test_contact_free_normal_force_has_the_corrected_sign(f_R: float):
    s = plane(20.0)
    contact = contact_forces(s, 1.0, f_R, s.z_S)
    assert contact.f_N == pytest.approx(g * math.cos(math.radians(20)) - f_R)  # (6.6) corrected
    # the friction needed is the downhill pull of gravity, m g |x_S.z_W|
    assert np.linalg.norm(contact.f_S) == pytest.approx(g * math.sin(math.radians(20)))


@pytest.mark.parametrize("mu", [0.3, 0.6, 1.2])
def test_motors_off_without_cable_holds_iff_tan_beta_below_mu(mu: float):
    limit = math.degrees(math.atan(mu))
    for beta, expected in ((limit - 0.5, True), (limit + 0.5, False)):
        s = plane(beta, mu)
        assert contact_forces(s, 1.0, 0.0, s.z_S).holds is expected
        assert (
            analyze_free_flight(s, VehicleLimits(1.0, 0.2, 6.0, 0.25)).condition5_holds_motors_off
            is expected
        )


def _max_thrust_by_bisection(surface: Surface, d: np.ndarray | None, mass: float) -> float:
    f_L = 0.0 if d is None else tethered_rest_tension(surface, d, mass)
    lo, hi = -1000.0, 1000.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if contact_forces(surface, mass, mid, surface.z_S, f_L, d).holds:
            lo = mid
        else:
            hi = mid
    return lo


@settings(max_examples=60, deadline=None)
@given(
    st.floats(1.0, 89.0),
    st.floats(0.05, 1.5),
    st.floats(-3.0, 0.0),
    st.floats(0.02, 0.9),
    st.floats(-0.5, 0.5),
)
def test_tethered_max_touchdown_thrust_equals_force_balance_threshold(beta, mu, f_N_min, c, y_part):
    """(6.15) corrected equals the largest thrust for which (6.5) has admissible contact
    forces, for landing spots below the anchor (also off the inclined-hover point)."""
    s = plane(beta, mu, f_N_min)
    d = math.sqrt(1 - c * c) * (math.sqrt(1 - y_part**2) * s.x_S + y_part * s.y_S) + c * s.z_S
    bound = tethered_max_touchdown_thrust(s, d, 1.0)
    by_balance = _max_thrust_by_bisection(s, d, 1.0)
    f_L = tethered_rest_tension(s, d, 1.0)
    # the friction (6.16) may bind before the normal force for y_part != 0; the closed form
    # is the normal-force bound, so it is an upper bound, exact when friction does not bind
    assert by_balance <= bound + 1e-6
    contact_at_bound = contact_forces(s, 1.0, bound, s.z_S, f_L, d)
    if np.linalg.norm(contact_at_bound.f_S) <= contact_at_bound.f_S_max + 1e-9:
        assert by_balance == pytest.approx(bound, abs=1e-6)


@settings(max_examples=60, deadline=None)
@given(st.floats(0.0, 89.0), st.floats(0.05, 1.5), st.floats(-3.0, 0.0))
def test_free_flight_max_touchdown_thrust_equals_force_balance_threshold(beta, mu, f_N_min):
    s = plane(beta, mu, f_N_min)
    assert free_flight_max_touchdown_thrust(s, 1.0) == pytest.approx(
        _max_thrust_by_bisection(s, None, 1.0), abs=1e-6
    )


@settings(max_examples=60, deadline=None)
@given(st.floats(0.5, 90.0), st.floats(0.0, 1.5), st.floats(-0.9, 0.9))
def test_inclined_hover_touchdown_leaves_zero_normal_force(beta, mu, c):
    """At the inclined-hover point the hover thrust is exactly fbar_R (with f_N_min = 0):
    touching down in inclined hovering needs no normal force, (6.16) holds for any mu."""
    s = plane(beta, mu)
    d = inclined_hover_direction(s.R_WS, c)
    f_R, f_L = landing_hover(s.slope, c, 1.0)
    assert tethered_rest_tension(s, d, 1.0) == pytest.approx(f_L, rel=1e-9)
    assert tethered_max_touchdown_thrust(s, d, 1.0) == pytest.approx(f_R, rel=1e-9)
    rest = contact_forces(s, 1.0, 0.0, s.z_S, f_L, d)
    assert abs(s.y_S @ rest.f_S) < 1e-9 and abs(s.x_S @ rest.f_S) < 1e-9  # (6.14), (6.16)


def test_frictionless_slope_is_reported_not_divided():
    s = plane(30.0, mu=0.0)
    assert free_flight_max_touchdown_thrust(s, 1.0) is None
    result = analyze_free_flight(s, VehicleLimits(1.0, 0.2, 6.0, 0.25))
    assert result.feasible is False
    assert any("frictionless" in r for r in result.reasons)


# --- feasibility and slope limits -----------------------------------------------------------


def test_slope50_tethered_feasible_contact_free_not(slope50):
    a = analyze(slope50)
    assert a.tethered.feasible and not a.free_flight.feasible
    assert a.tethered.condition4_possible and not a.free_flight.condition4_possible
    assert a.tethered.condition5_holds and not a.free_flight.condition5_holds_motors_off


def test_flat_ground_both_methods_feasible():
    a = analyze(load_scenario("flat"))
    assert a.tethered.feasible and a.free_flight.feasible
    assert a.free_flight.condition4_possible
    assert a.tethered.hover_tension == pytest.approx(0.0, abs=1e-12)


def test_tethered_slope_limit_with_the_cable_at_the_centre_of_mass():
    centred = ["vehicle.cable_attachment=[0, 0, 0]"]
    a = analyze(load_scenario("slope50", [*centred, 'tether.material="ideal"']))
    lim = a.limits
    gamma = a.geometry.gamma
    # no cable torque: equal rotor thrusts, f_R(beta) = m g cos(beta - gamma)/cos(gamma)
    # = n (f_min + margin) solved for beta
    expected = gamma + math.acos(lim.min_controllable_thrust * math.cos(gamma) / (lim.mass * g))
    assert a.tethered.max_slope_rad == pytest.approx(expected, abs=1e-8)
    np.testing.assert_allclose(a.tethered.hover_rotor_thrusts, a.tethered.hover_thrust / 4)
    # An elastic cable's gamma is that of l + s at the limit slope's own f_L: the limit is
    # the fixed point beta = gamma'(beta) + acos(n f cos(gamma'(beta))/(m g)). The stretch
    # lowers gamma, and f_R = m g (cos(beta) + sin(beta) tan(gamma)) with it, so the rotor
    # floor binds at a lower slope than for the rigid cable.
    for material in ("dyneema", "nylon"):
        e = analyze(load_scenario("slope50", [*centred, f'tether.material="{material}"']))
        beta = e.tethered.max_slope_rad
        gamma_e = math.asin(e.geometry.cosine_at(beta, lim.mass))
        assert gamma_e < gamma
        fixed = gamma_e + math.acos(
            lim.min_controllable_thrust * math.cos(gamma_e) / (lim.mass * g)
        )
        assert beta == pytest.approx(fixed, abs=1e-8)
        assert beta < expected


def test_cable_offset_torque_lowers_the_slope_limit(slope50):
    """With the 3 cm attachment offset the rotors must cancel r_att x f_L d (6.6.5): at the
    limit the smallest rotor thrust of the landed hover is exactly f_min + margin."""
    a = analyze(slope50)
    limit = a.tethered.max_slope_rad
    centred = analyze(load_scenario("slope50", ["vehicle.cable_attachment=[0, 0, 0]"]))
    assert limit < centred.tethered.max_slope_rad - math.radians(5)
    at = analyze(load_scenario("slope50", [f"surface.slope_deg={math.degrees(limit)}"]))
    lim = at.limits
    assert at.tethered.hover_rotor_thrusts.min() == pytest.approx(lim.f_min + lim.margin, abs=1e-6)
    # the allocated thrusts produce the hover thrust and cancel the cable torque
    from tetherland.models.quadrotor import RotorLayout

    wrench = RotorLayout.from_config(slope50.vehicle).wrench(at.tethered.hover_rotor_thrusts)
    assert wrench[0] == pytest.approx(at.tethered.hover_thrust)
    c = at.geometry.c
    d_B = np.array([math.sqrt(1 - c * c), 0.0, c])
    tau_L = np.cross(np.array(slope50.vehicle.cable_attachment), -at.tethered.hover_tension * d_B)
    np.testing.assert_allclose(wrench[1:] + tau_L, 0.0, atol=1e-9)
    below = analyze(load_scenario("slope50", [f"surface.slope_deg={math.degrees(limit) - 0.2}"]))
    above = analyze(load_scenario("slope50", [f"surface.slope_deg={math.degrees(limit) + 0.2}"]))
    assert below.tethered.feasible and not above.tethered.feasible
    assert any("too steep" in r for r in above.tethered.reasons)


def test_contact_free_slope_limit_is_friction_with_controllable_thrust(slope50):
    a = analyze(slope50)
    mu, k = 0.6, a.limits.min_controllable_thrust / (a.limits.mass * g)
    # cos(b) - sin(b)/mu = k  <=>  R cos(b + psi) = k
    R, psi = math.hypot(1.0, 1.0 / mu), math.atan(1.0 / mu)
    assert a.free_flight.max_slope_rad == pytest.approx(math.acos(k / R) - psi, abs=1e-8)
    assert a.free_flight.max_slope_rad < math.atan(mu)  # stricter than motors-off sliding


def test_weak_rotors_are_reported():
    a = analyze(load_scenario("slope50", ["surface.slope_deg=10", "vehicle.f_max=2.5"]))
    assert not a.tethered.feasible
    assert any("f_max too low" in r for r in a.tethered.reasons)


def test_steep70_is_feasible_and_near_the_limit():
    a = analyze(load_scenario("steep70"))
    assert a.tethered.feasible
    assert math.radians(70) < a.tethered.max_slope_rad < math.radians(75)


def test_table_is_generated_from_the_numbers(slope50):
    t50 = {r.label: r for r in analyze(slope50).table()}
    t30 = {r.label: r for r in analyze(load_scenario("slope50", ["surface.slope_deg=30"])).table()}
    assert t50["Surface slope"].tethered == "50.0 deg"
    assert t30["Max f_R at t_L+"].tethered != t50["Max f_R at t_L+"].tethered
    assert t50["Feasible here"].free_flight == "no" and t50["Feasible here"].tethered == "yes"


# --- conditions (1)-(5) as predicates ---------------------------------------------------------


def test_condition_predicates_thresholds():
    tol = LandingTolerances()
    z = np.array([0.0, 0.0, 1.0])
    assert condition_1([0.02, 0, 0], [0, 0, 0], tol).holds
    assert not condition_1([0.04, 0, 0], [0, 0, 0], tol).holds
    tilt = math.radians(2.0)
    assert condition_2([math.sin(tilt), 0, math.cos(tilt)], z, tol).holds
    assert not condition_2([math.sin(2 * tilt), 0, math.cos(2 * tilt)], z, tol).holds
    assert condition_3([0.05, 0, 0], [0, 0.2, 0], tol).holds
    assert not condition_3([0.05, 0, 0], [0, 0.4, 0], tol).holds
    assert not condition_4([0, 0, 2.0], [0, 0, 0], tol).holds


def test_condition_5_observed_detects_slip():
    tol = LandingTolerances()
    still = np.zeros((50, 3))
    sliding = np.column_stack((np.linspace(0, 0.05, 50), np.zeros(50), np.zeros(50)))
    assert condition_5_observed(still, np.zeros((50, 3)), tol).holds
    assert not condition_5_observed(sliding, np.full((50, 3), 0.01), tol).holds


def test_condition_5_counts_sliding_along_the_surface_not_settling_onto_the_landers():
    """A vehicle pivoting flat onto all landers when the thrust goes moves p_RL mostly
    along the normal: with z_S that is settle, not slip; sliding along the surface is."""
    tol = LandingTolerances()
    beta = math.radians(70.0)
    z_S = np.array([-math.sin(beta), 0.0, math.cos(beta)])
    x_S = np.array([math.cos(beta), 0.0, math.sin(beta)])  # along the fall line
    s = np.linspace(0.0, 1.0, 50)[:, None]
    settling = -0.015 * s * z_S + 0.004 * s * x_S  # 15 mm down the normal, 4 mm along
    c = condition_5_observed(settling, np.zeros((50, 3)), tol, z_S)
    got = {m.name: m.value for m in c.measures}
    assert c.holds
    assert got["slip"] == pytest.approx(0.004, abs=1e-12)
    assert got["settle"] == pytest.approx(0.015, abs=1e-12)
    assert not condition_5_observed(settling, np.zeros((50, 3)), tol).holds  # no normal given
    sliding = 0.012 * s * x_S  # 12 mm down the fall line
    assert not condition_5_observed(sliding, np.zeros((50, 3)), tol, z_S).holds


def test_condition_5_static_uses_force_balance():
    s = plane(50.0)
    free = contact_forces(s, 1.0, 0.0, s.z_S)
    d = inclined_hover_direction(s.R_WS, 0.1)
    tethered = contact_forces(s, 1.0, 0.0, s.z_S, tethered_rest_tension(s, d, 1.0), d)
    assert not condition_5_static(free).holds
    assert condition_5_static(tethered).holds


def test_evaluate_landing_and_touchdown_index():
    verdict = evaluate_landing(
        p_RL=[0.01, 0, 0],
        z_B=[0, 0, 1],
        v_W=[0, 0, -0.02],
        omega_B=[0, 0, 0],
        a_W=[0, 0, 0.1],
        omega_dot_B=[0, 0, 0],
        p_L_star=[0, 0, 0],
        z_S=[0, 0, 1],
        rest_p_RL=np.zeros((10, 3)),
        rest_v_W=np.zeros((10, 3)),
    )
    assert verdict.all_hold and verdict.to_dict() == {str(i): True for i in range(1, 6)}
    assert touchdown_index([0.3, 0.2, 0.1, 0.004, 0.0], 0.005) == 3
    assert touchdown_index([0.3, 0.2], 0.005) is None
