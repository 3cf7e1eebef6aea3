"""Robust margins of a design, the ranking by verified success, and the new-user wall
vehicle's verified first design (issue 24)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from tetherland.campaign.executors import make_executor
from tetherland.config import load_scenario
from tetherland.design import (
    BeliefBounds,
    Design,
    DesignPoint,
    DesignSpace,
    Verification,
    rank_verified,
    robust_pass_clearance,
    robust_rotor_margin,
    search_designs,
    verify_designs,
)
from tetherland.design.robust import scenario_pass, true_surfaces
from tetherland.mission.hooking import pass_clearance
from tetherland.surface import Surface, surface_frame_from_slope

WALL_VEHICLE = ["vehicle.mass=0.5", "vehicle.arm_length=0.15", "vehicle.f_min=0.05",
                "vehicle.f_max=3", "vehicle.control_margin=0.2"]  # fmt: skip
"""The new user's 0.5 kg wall vehicle of issue 24."""


def test_a_surface_offset_error_shrinks_the_clearance_by_exactly_that_offset():
    # a plane moved by o along its normal is o closer to every point of the pass; with no
    # other error the robust clearance is the nominal one less o
    sc = load_scenario("wall90")
    geo, hooking = scenario_pass(sc)
    nominal = pass_clearance(sc, geo, hooking)
    bounds = BeliefBounds(surface_offset_error=0.013)
    assert robust_pass_clearance(sc, bounds) == pytest.approx(nominal - 0.013, abs=1e-12)
    assert robust_pass_clearance(sc, BeliefBounds()) == pytest.approx(nominal, abs=1e-12)


@pytest.mark.parametrize(("x", "z"), [(0.4, 0.1), (-0.25, 0.3)])
def test_a_slope_error_moves_the_surface_at_a_point_by_the_hand_derived_worst_case(x, z):
    # believed plane at 30 deg; a point x along x_S and z above it. The true plane tilted
    # by -/+ d about y_S through the origin has normal n' with n'.x_S = +/- sin d and
    # n'.z_S = cos d: the point's true height is +/- x sin d + z cos d, so the surface comes
    # closer by at most z (1 - cos d) + |x| sin d.
    d = math.radians(2.0)
    R = surface_frame_from_slope(math.radians(30.0), 0.0)
    believed = Surface(np.zeros(3), R)
    p = x * R[:, 0] + z * R[:, 2]
    closer = max(z - s.height(p) for s in true_surfaces(believed, BeliefBounds(slope_error_deg=2)))
    assert closer == pytest.approx(z * (1 - math.cos(d)) + abs(x) * math.sin(d), abs=1e-12)


def test_robust_rotor_margin_scales_the_commands_by_the_mass_and_thrust_coefficient_errors():
    # commands (1 +/- 0.05)(1 +/- 0.1) of thrusts in [1, 5] N, limits [0.2, 6] N:
    # min(0.95 * 0.9 * 1 - 0.2, 6 - 1.05 * 1.1 * 5) = min(0.655, 0.225)
    bounds = BeliefBounds(mass_rel=0.05, thrust_coefficient_rel=0.1)
    assert robust_rotor_margin(1.0, 5.0, 0.2, 6.0, bounds) == pytest.approx(0.225, abs=1e-12)
    assert robust_rotor_margin(1.0, 2.0, 0.5, 6.0, bounds) == pytest.approx(0.355, abs=1e-12)


def _synthetic(length: float, margin: float, clearance: float, verified=None) -> Design:
    point = DesignPoint(90.0, length, (0.0, 0.0, 0.0), 0.0, (-1.0, 0.0, 0.0), 0.2)
    return Design(point, margin, margin, clearance, None, None, margin, clearance, verified)  # type: ignore[arg-type]


def test_verified_designs_rank_by_the_wilson_lower_bound_then_by_robust_margins():
    sc = load_scenario(
        "wall90", ["vehicle.control_margin=0.2", "mission.hooking.min_clearance=0.02"]
    )
    space = DesignSpace()
    v = lambda k, n: Verification.of(k, n, seed=1)  # noqa: E731
    designs = [
        _synthetic(0.30, 0.40, 0.05, v(9, 10)),
        _synthetic(0.32, 0.30, 0.05, v(10, 10)),
        _synthetic(0.34, 0.45, 0.05, None),  # not flown: after every flown design
        _synthetic(0.36, 0.35, 0.05, v(10, 10)),  # ties 0.32 on the bound: larger margin first
        _synthetic(0.38, 0.50, 0.01, v(7, 10)),
    ]
    ranked = [d.point.length for d in rank_verified(designs, sc, space)]
    assert ranked == [0.36, 0.32, 0.30, 0.38, 0.34]
    # without flights: robust designs first (0.38 keeps 1 cm < 2 cm when the belief is off)
    bare = [replace(d, verified=None) for d in designs]
    assert [d.point.length for d in rank_verified(bare, sc, space)] == [
        0.34,
        0.30,
        0.36,
        0.32,
        0.38,
    ]
    assert v(10, 10).ci_low == pytest.approx(10 / (10 + 1.959963984540054**2), rel=1e-12)


def test_the_search_ranks_designs_that_keep_their_margins_under_the_belief_errors_first():
    sc = load_scenario("wall90", WALL_VEHICLE)
    result = search_designs(sc)
    first = result.chosen
    assert first is not None
    floor, least = sc.vehicle.control_margin, sc.mission.hooking.min_clearance
    assert first.robust_rotor_margin >= floor and first.robust_clearance >= least
    # the robust margins are below the nominal ones, and the first design (2.4 cm
    # nominal clearance) no longer comes first
    for d in result.designs:
        assert d.robust_rotor_margin < d.min_rotor_margin
        assert d.robust_clearance < d.min_clearance
    assert first.min_clearance > 0.03


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason="issue 24 regression, not met yet: the first design (l = 0.32 m) landed 7 of 10 "
    "perturbed runs at seed 9090 before the hook mechanism's design search is merged",
)
def test_the_wall_vehicle_first_verified_design_lands_9_of_10_perturbed_runs():
    # issue 24's new user: 0.5 kg, 0.15 m arm, rotors 0.05-3 N, control margin 0.2 N
    sc = load_scenario("wall90", WALL_VEHICLE)
    result = search_designs(sc)
    executor = make_executor("local", 2)
    try:
        ranked = verify_designs(sc, result.designs, 10, 9090, executor, candidates=1)
    finally:
        executor.close()
    first = ranked[0]
    assert first.verified is not None and first.verified.runs == 10
    assert first.verified.successes >= 9
