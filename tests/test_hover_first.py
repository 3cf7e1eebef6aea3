"""Hover first: `analyze` and `design` check that the vehicle can hover in free flight with
the control margin before anything else, and name ``cannot_hover`` as the binding reason.

The rule (:func:`tetherland.analysis.free_hover`): hovering needs the thrust m g with no
torque, m g / 4 per rotor of the symmetric quadrotor, and every rotor must stay in
[f_min + control_margin, f_max - control_margin]. So a vehicle hovers only if
m g <= 4 (f_max - control_margin) (the thrust-to-weight ratio 4 f_max / (m g) is at least
f_max / (f_max - control_margin)) and m g >= 4 (f_min + control_margin).
"""

from __future__ import annotations

import json
import math

import pytest

from tetherland import GRAVITY as g
from tetherland.analysis import Infeasibility, VehicleLimits, analyze, free_hover
from tetherland.cli import main
from tetherland.config import load_scenario
from tetherland.design import DesignLimit, search_designs

HEAVY = ("vehicle.mass=3", "vehicle.f_max=6", "vehicle.control_margin=0.25")
"""The new user's vehicle: 3 kg on 4 x 6 N rotors."""


def test_the_3_kg_vehicle_on_four_6_N_rotors_cannot_hover():
    """Before: "feasible" contact-free up to 29 deg and tethered up to 92 deg. m g = 29.4 N
    but 4 (f_max - margin) = 23 N: no slope is feasible for either method."""
    for slope in (0.0, 20.0, 50.0, 90.0):
        result = analyze(load_scenario("slope50", [*HEAVY, f"surface.slope_deg={slope}"]))
        assert not result.hover.ok
        assert result.hover.margin == pytest.approx((6.0 - 0.25) - 3.0 * g / 4, abs=1e-12)
        for method in (result.tethered, result.free_flight):
            assert not method.feasible
            assert method.binding is Infeasibility.CANNOT_HOVER
            assert method.max_slope_rad is None
        assert result.tethered.checks[0].reason is Infeasibility.CANNOT_HOVER
        assert result.free_flight.findings[0].reason is Infeasibility.CANNOT_HOVER


def test_the_threshold_is_m_g_equal_to_four_times_f_max_minus_the_margin():
    """Derived here: the heaviest vehicle that hovers is m* = 4 (f_max - margin) / g; the
    thrust-to-weight ratio it needs is f_max / (f_max - margin)."""
    f_max, margin = 6.0, 0.25
    m_star = 4 * (f_max - margin) / g
    below = load_scenario("slope50", [f"vehicle.mass={m_star * (1 - 1e-6)}"])
    above = load_scenario("slope50", [f"vehicle.mass={m_star * (1 + 1e-6)}"])
    ok, too_heavy = (free_hover(VehicleLimits.from_scenario(s)) for s in (below, above))
    assert ok.ok and not too_heavy.ok
    assert ok.margin == pytest.approx(f_max - margin - m_star * (1 - 1e-6) * g / 4, rel=1e-9)
    limits = VehicleLimits.from_scenario(above)
    assert limits.hover_thrust_to_weight == pytest.approx(f_max / (f_max - margin))
    assert limits.thrust_to_weight() < limits.hover_thrust_to_weight
    # just below the threshold the hover no longer binds (something else may)
    assert analyze(below).tethered.binding is not Infeasibility.CANNOT_HOVER
    assert f"{4 * (f_max - margin) / g:.3g} kg" in too_heavy.message
    # a vehicle that hovers is not told it cannot (analyze --json prints the message)
    per_rotor = m_star * (1 - 1e-6) * g / 4
    assert ok.message.startswith("the vehicle hovers") and f"{per_rotor:.3f}" in ok.message
    assert "cannot" not in ok.message


def test_rotors_that_cannot_throttle_down_to_the_weight_cannot_hover():
    """0.2 kg on rotors of at least 0.5 N with a 0.25 N margin: m g / 4 = 0.49 N is below
    f_min + margin = 0.75 N, the vehicle climbs at its least controllable thrust."""
    sc = load_scenario("slope50", ["vehicle.mass=0.2", "vehicle.f_min=0.5"])
    hover = free_hover(VehicleLimits.from_scenario(sc))
    assert not hover.ok
    assert hover.margin == pytest.approx(0.2 * g / 4 - (0.5 + 0.25), abs=1e-12)
    assert "f_min" in hover.message
    assert analyze(sc).tethered.binding is Infeasibility.CANNOT_HOVER


def test_analyze_cli_names_cannot_hover_as_the_binding_reason(capsys):
    code = main(["analyze", "slope50", *(a for o in HEAVY for a in ("--set", o)), "--json"])
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert code == 1
    assert doc["hover"]["ok"] is False
    assert doc["hover"]["thrust_to_weight"] == pytest.approx(4 * 6.0 / (3.0 * g))
    assert doc["tethered"]["binding"] == doc["free_flight"]["binding"] == "cannot_hover"
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "(binding: cannot_hover)" in lines[0]


def test_design_checks_the_hover_before_any_candidate(capsys):
    code = main(["design", "slope50", *(a for o in HEAVY for a in ("--set", o)), "--json"])
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert code == 1
    assert doc["binding"] == "cannot_hover" and not doc["feasible"]
    assert doc["candidates"] == 0 and doc["planned"] == 0
    assert "cannot hover" in err


def test_design_of_a_1_kg_vehicle_on_2_5_N_rotors_cannot_hover():
    """m g / 4 = 2.45 N > f_max - margin = 2.25 N: the search stops before its grid."""
    r = search_designs(load_scenario("slope50", ["vehicle.f_max=2.5"]), 10.0)
    assert r.limit is DesignLimit.CANNOT_HOVER and r.binding == "cannot_hover"
    assert r.candidates == 0 and not r.feasible
    assert math.isclose(free_hover(VehicleLimits.from_scenario(
        load_scenario("slope50", ["vehicle.f_max=2.5"]))).margin, 2.25 - g / 4)  # fmt: skip
