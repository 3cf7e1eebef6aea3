"""The planner on steep walls and overhangs (80, 90, 100 deg) where the analysis says the
tethered landing is feasible: solved, re-simulated within the rotor bounds, taut cable."""

from __future__ import annotations

import math

import numpy as np
import pytest

from test_planning_landing import check_plan
from tetherland import GRAVITY as g
from tetherland.analysis import Infeasibility, analyze
from tetherland.config import load_scenario
from tetherland.planning import Planner, PlanStatus

# cable at the CoM (no offset torque), length per slope: 0.4 m reaches 94 deg, 0.25 m 104 deg
CASES = [(80.0, 0.4), (90.0, 0.4), (100.0, 0.25)]


def _gamma(length: float, beta: float, EA: float, mass: float = 1.0) -> float:
    """gamma of the landed link of the elastic cable at the CoM: sin(gamma) = 0.1/(l + s),
    s = f_L l/EA with f_L = m g sin(beta)/cos(gamma) (6.10), by plain iteration."""
    s = 0.0
    for _ in range(100):
        s = mass * g * math.sin(beta) / math.cos(math.asin(0.1 / (length + s))) * length / EA
    return math.asin(0.1 / (length + s))


def _scenario(slope_deg: float, length: float, *extra: str):
    return load_scenario(
        "slope50",
        [
            f"surface.slope_deg={slope_deg}",
            f"tether.length={length}",
            "vehicle.cable_attachment=[0, 0, 0]",
            "tether.hook_drop=0.1",
            *extra,
        ],
    )


@pytest.fixture(scope="module")
def planner() -> Planner:
    return Planner()


@pytest.mark.parametrize(("slope_deg", "length"), CASES)
@pytest.mark.parametrize("maneuver", ["landing", "takeoff"])
def test_plans_on_walls_and_overhangs(planner, slope_deg, length, maneuver):
    # a short cable swings fast (sqrt(g/l) = 5 rad/s at 0.4 m): with one RK4 step per
    # 80 ms interval the independent re-simulation ends with phi'' = 1.1e-3 rad/s^2 on the
    # wall, just over check_plan's 1e-3; two steps per interval bring it to 6e-5
    scenario = _scenario(slope_deg, length, "planner.integrator_step=0.04")
    analysis = analyze(scenario).tethered
    assert analysis.feasible
    result = planner.plan(scenario, maneuver)
    check_plan(result)  # re-simulated with DOP853: final state, rotor bounds, f_L > 0
    spec, beta = result.spec, math.radians(slope_deg)
    gamma = _gamma(length, beta, scenario.tether.effective_axial_stiffness)
    landed = (
        (spec.phi_final, spec.theta_final)
        if maneuver == "landing"
        else (spec.phi_start, spec.theta_start)
    )
    assert landed == pytest.approx((gamma - beta, beta), abs=1e-12)
    # the landed end of the plan holds the analysis' inclined hover
    s = result.trajectory.sample([spec.duration if maneuver == "landing" else 0.0])
    assert s.f_R[0] == pytest.approx(analysis.hover_thrust, rel=1e-4)
    assert s.tension[0] == pytest.approx(analysis.hover_tension, rel=1e-4)
    assert analysis.hover_thrust == pytest.approx(
        g * math.cos(beta - gamma) / math.cos(gamma), rel=1e-12
    )
    # the link never swings past the surface beyond the anchor: phi <= pi - gamma - beta
    phi = result.trajectory.sample(np.linspace(0, spec.duration, 201)).phi[:, 0]
    assert phi.max() <= math.pi - gamma - beta + 1e-6


def test_overhang_beyond_the_rotor_floor_is_refused_like_the_analysis(planner):
    scenario = _scenario(100.0, 0.4)
    assert analyze(scenario).tethered.binding is Infeasibility.ROTOR_FLOOR
    result = planner.plan(scenario, "landing")
    assert result.status is PlanStatus.INFEASIBLE
    assert "f_min" in result.message
