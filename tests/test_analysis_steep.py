"""Analysis on walls and overhangs (slopes 90-180 deg): known answers by force balance and
the binding reason of each infeasible case (docs/theory.md sections 5 and 13)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland import GRAVITY as g
from tetherland.analysis import (
    Infeasibility,
    VehicleLimits,
    analyze,
    analyze_free_flight,
    landed_hover,
    tethered_slope_limit,
)
from tetherland.config import load_scenario
from tetherland.surface import Surface, surface_frame_from_slope

# Cable at the CoM, inextensible: the closed forms below are the rigid link's.
CENTRED = (
    "vehicle.cable_attachment=[0, 0, 0]",
    "tether.hook_drop=0.1",
    'tether.material="ideal"',
)


def _scenario(slope_deg: float, length: float, *extra: str):
    return load_scenario(
        "slope50", [f"surface.slope_deg={slope_deg}", f"tether.length={length}", *CENTRED, *extra]
    )


def _balance(beta: float, gamma: float, mass: float) -> tuple[float, float]:
    """f_R, f_L of the landed hover from 0 = f_R z_S - f_L d~ - m g z_W (in F_A), solved as
    a linear system: z_S = [sin b, 0, cos b], d~ = [cos(gamma - b), 0, sin(gamma - b)]."""
    z_S = np.array([math.sin(beta), math.cos(beta)])
    d = np.array([math.cos(gamma - beta), math.sin(gamma - beta)])
    f_R, f_L = np.linalg.solve(np.column_stack((z_S, -d)), [0.0, mass * g])
    return float(f_R), float(f_L)


@pytest.mark.parametrize("slope_deg", [90.0, 100.0])
@pytest.mark.parametrize("length", [0.25, 0.4])
def test_landed_hover_on_a_wall_and_an_overhang_is_the_force_balance(slope_deg, length):
    """Cable at the CoM: sin(gamma) = (h_att - h_A)/l = 0.1/l; the hover and the motors-off
    rest both balance, f_N = f_R (same number), no shear (y_S.d~ = 0 and (6.14))."""
    a = analyze(_scenario(slope_deg, length))
    t, beta = a.tethered, math.radians(slope_deg)
    gamma = math.asin(0.1 / length)
    f_R, f_L = _balance(beta, gamma, 1.0)
    assert t.gamma == pytest.approx(gamma, abs=1e-12)
    assert t.hover_thrust == pytest.approx(f_R, rel=1e-9)
    assert t.hover_tension == pytest.approx(f_L, rel=1e-9)
    assert t.hover_thrust == pytest.approx(g * math.cos(beta - gamma) / math.cos(gamma), rel=1e-12)
    assert t.hover_tension == pytest.approx(g * math.sin(beta) / math.cos(gamma), rel=1e-12)
    assert t.rest_tension == pytest.approx(f_L, rel=1e-9)
    assert t.rest_normal_force == pytest.approx(f_R, rel=1e-9)
    np.testing.assert_allclose(t.hover_rotor_thrusts, f_R / 4, rtol=1e-12)  # no torque
    assert t.phi_star == pytest.approx(gamma - beta, abs=1e-12)
    assert t.theta_A_star == pytest.approx(beta, abs=1e-12)
    # feasible iff every rotor keeps f_min + control_margin = 0.45 N (f_R < 23.0 N always)
    assert t.feasible is (f_R / 4 >= 0.45)


def test_known_numbers_at_90_and_100_degrees():
    """l = 0.4 m: gamma = 14.48 deg; at 90 deg f_R = m g tan(gamma) = 2.533 N (0.633 N per
    rotor: feasible), at 100 deg 0.791 N (0.198 N per rotor: the rotor floor binds);
    l = 0.25 m holds 100 deg with 2.513 N (0.628 N per rotor)."""
    wall = analyze(_scenario(90.0, 0.4)).tethered
    assert math.degrees(wall.gamma) == pytest.approx(14.4775, abs=1e-4)
    assert wall.hover_thrust == pytest.approx(g * math.tan(math.asin(0.25)), rel=1e-12)
    assert wall.hover_thrust == pytest.approx(2.533, abs=5e-4)
    assert wall.hover_tension == pytest.approx(g / math.cos(math.asin(0.25)), rel=1e-12)
    assert wall.feasible and wall.binding is None
    over = analyze(_scenario(100.0, 0.4)).tethered
    assert over.hover_thrust == pytest.approx(0.791, abs=5e-4)
    assert not over.feasible and over.binding is Infeasibility.ROTOR_FLOOR
    assert [c.reason for c in over.findings] == [Infeasibility.ROTOR_FLOOR]  # no torque here
    short = analyze(_scenario(100.0, 0.25)).tethered
    assert short.hover_thrust == pytest.approx(2.513, abs=5e-4) and short.feasible


@pytest.mark.parametrize("length", [0.25, 0.4, 0.5, 1.0])
def test_steepest_slope_past_vertical_is_the_closed_form(length):
    """No offset torque: f_R(beta) = n (f_min + margin) gives
    beta_max = gamma + acos(n (f_min + margin) cos(gamma) / (m g)), beyond 90 deg for
    short cables; the rotor floor binds beyond it."""
    t = analyze(_scenario(60.0, length)).tethered
    gamma = math.asin(0.1 / length)
    expected = gamma + math.acos(4 * 0.45 * math.cos(gamma) / g)
    assert t.max_slope_rad == pytest.approx(expected, abs=1e-8)
    assert t.max_slope_binding is Infeasibility.ROTOR_FLOOR
    assert (expected > math.pi / 2) is (length <= 0.5)


def test_without_rotor_floor_the_limit_is_ninety_degrees_plus_gamma():
    """f_min = 0 and no control margin: the hover exists exactly while beta < 90 deg + gamma."""
    sc = _scenario(60.0, 0.4, "vehicle.f_min=0", "vehicle.control_margin=0")
    t = analyze(sc).tethered
    gamma = math.asin(0.25)
    assert t.max_slope_rad == pytest.approx(math.pi / 2 + gamma, abs=1e-8)
    assert t.max_slope_binding is Infeasibility.NO_INCLINED_HOVER


def test_binding_reason_no_inclined_hover():
    """110 deg > 90 deg + 14.5 deg: f_R = m g cos(beta - gamma)/cos(gamma) < 0. The rest with
    the motors off fails too (f_N = f_R < 0), but the hover is what binds."""
    t = analyze(_scenario(110.0, 0.4)).tethered
    assert t.hover_thrust < 0
    assert t.binding is Infeasibility.NO_INCLINED_HOVER
    failed = [c.reason for c in t.findings]
    assert Infeasibility.ROTOR_FLOOR in failed and Infeasibility.NORMAL_FORCE in failed
    assert not t.condition4_possible and not t.condition5_holds
    assert "90 deg + gamma" in t.reasons[0]


def test_adhesive_pad_holds_the_rest_but_no_hover_exists():
    t = analyze(_scenario(110.0, 0.4, "surface.f_N_min=-5")).tethered
    assert t.rest_normal_force == pytest.approx(t.hover_thrust, rel=1e-9)
    assert -5 < t.rest_normal_force < 0
    assert t.condition5_holds
    assert t.binding is Infeasibility.NO_INCLINED_HOVER


def test_binding_reason_rotor_ceiling():
    """The landed hover needs more than the free hover's m g where 0 < beta < 2 gamma
    (cos(beta - gamma)/cos(gamma) > 1), most at beta = gamma: m g / cos(gamma). Rotors whose
    ceiling f_max - margin lies halfway between m g/4 and m g/(4 cos(gamma)) hover in free
    flight but not landed there."""
    gamma = analyze(_scenario(50.0, 0.25)).tethered.gamma
    m_g = 1.0 * g
    ceiling = 0.5 * (m_g / 4 + m_g / (4 * math.cos(gamma)))
    sc = _scenario(math.degrees(gamma), 0.25, f"vehicle.f_max={ceiling + 0.25}")
    result = analyze(sc)
    t = result.tethered
    assert result.hover.ok and t.binding is Infeasibility.ROTOR_CEILING
    assert t.hover_thrust == pytest.approx(m_g / math.cos(gamma), rel=1e-9)
    assert t.hover_thrust / 4 > ceiling > m_g / 4


def test_binding_reason_offset_torque():
    """slope50's cable 3 cm below the CoM at 80 deg: f_R/4 = 0.595 N clears the 0.45 N floor,
    but cancelling r_att x (f_L d~) = f_L r_z cos(gamma) about y_B takes a rotor below it."""
    t = analyze(load_scenario("slope50", ["surface.slope_deg=80"])).tethered
    assert t.hover_thrust / 4 > 0.45
    assert t.hover_rotor_thrusts.min() < 0.45
    assert t.binding is Infeasibility.OFFSET_TORQUE
    # the torque the rotors add: tau_y = f_L |r_z| cos(gamma), shared by the x-layout pairs
    tau = t.hover_tension * 0.03 * math.cos(t.gamma)
    arm = 0.23 / math.sqrt(2)
    spread = t.hover_rotor_thrusts.max() - t.hover_rotor_thrusts.min()
    assert spread == pytest.approx(tau / arm / 2, rel=1e-9)


def test_binding_reason_friction_motors_off_is_contact_free_only():
    """Frictionless 60 deg plane: the contact-free rest slides, the tethered rest has no
    shear at all (y_S.d~ = 0, (6.14)) and stays feasible."""
    a = analyze(_scenario(60.0, 0.4, "surface.friction=0"))
    assert a.free_flight.binding is Infeasibility.FRICTION_MOTORS_OFF
    assert a.tethered.feasible
    friction = next(c for c in a.tethered.checks if c.reason is Infeasibility.FRICTION_MOTORS_OFF)
    assert friction.margin == pytest.approx(0.0, abs=1e-9)


def test_contact_free_binding_reasons():
    limits = VehicleLimits(1.0, 0.2, 6.0, 0.25)

    def free(beta_deg: float, mu: float = 0.6):
        R = surface_frame_from_slope(math.radians(beta_deg))
        return analyze_free_flight(Surface(origin=np.zeros(3), R_WS=R, friction=mu), limits)

    assert free(20.0).feasible and free(20.0).binding is None
    # 28 deg: tan(28) = 0.53 < mu holds with the motors off, but condition (5) needs
    # f_R(t_L+) <= m g (cos b - sin b / mu) = 0.98 N < 1.8 N
    assert free(28.0).condition5_holds_motors_off
    assert free(28.0).binding is Infeasibility.TOUCHDOWN_THRUST
    assert free(40.0).binding is Infeasibility.FRICTION_MOTORS_OFF
    assert free(100.0).binding is Infeasibility.NORMAL_FORCE


def test_feasibility_is_reported_for_every_slope():
    """Every slope in [0, 180] deg gives a verdict; feasible exactly on [0, beta_max]."""
    sc = _scenario(0.0, 0.4)
    limits = VehicleLimits.from_scenario(sc)
    surface = Surface(origin=np.zeros(3), R_WS=np.eye(3))
    limit = tethered_slope_limit(surface, 0.25, limits)
    for slope_deg in range(0, 181, 5):
        beta = math.radians(slope_deg)
        hover = landed_hover(Surface(np.zeros(3), surface_frame_from_slope(beta)), 0.25, limits)
        assert hover.feasible is (beta <= limit.max_slope_rad)
        assert (hover.binding is None) is hover.feasible
        if slope_deg >= 105:
            assert hover.binding is Infeasibility.NO_INCLINED_HOVER


def test_analysis_json_names_the_binding_reason():
    doc = analyze(_scenario(100.0, 0.4)).to_dict()
    assert doc["tethered"]["binding"] is Infeasibility.ROTOR_FLOOR
    assert doc["tethered"]["max_slope_binding"] is Infeasibility.ROTOR_FLOOR
    checks = {c["reason"]: c for c in doc["tethered"]["checks"]}
    assert checks[Infeasibility.ROTOR_FLOOR]["margin_N"] == pytest.approx(
        analyze(_scenario(100.0, 0.4)).tethered.hover_thrust / 4 - 0.45
    )
