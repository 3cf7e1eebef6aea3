"""A design search that finds nothing names the field to change and a value that works
(issue 24, item 5): applying the hint gives a design."""

from __future__ import annotations

import json

import pytest

from tetherland import GRAVITY as g
from tetherland.cli import main
from tetherland.config import load_scenario, with_overrides
from tetherland.design import DesignLimit, search_designs
from tetherland.planning import Planner

WEAK = ["vehicle.f_max=2.5"]
"""1 kg on 4 x 2.5 N rotors: m g / 4 = 2.45 N > f_max - control_margin = 2.25 N."""
WALL_VEHICLE = ["vehicle.mass=0.5", "vehicle.arm_length=0.15", "vehicle.f_min=0.05",
                "vehicle.f_max=3", "vehicle.control_margin=0.2"]  # fmt: skip


@pytest.fixture(scope="module")
def planner() -> Planner:
    return Planner()


def test_a_vehicle_that_cannot_hover_gets_an_f_max_and_a_mass_that_give_a_design(planner):
    sc = load_scenario("slope50", WEAK)
    r = search_designs(sc, 10.0, planner=planner, fixes=True)
    assert r.limit is DesignLimit.CANNOT_HOVER and not r.feasible
    by_field = {f.field: f for f in r.fixes}
    assert set(by_field) == {"vehicle.f_max", "vehicle.mass"}
    v = sc.vehicle
    # hovering alone needs m g / 4 <= f_max - control_margin: the fixes reach at least that
    assert by_field["vehicle.f_max"].value >= v.mass * g / 4 + v.control_margin
    assert by_field["vehicle.mass"].value <= 4 * (v.f_max - v.control_margin) / g
    for fix in r.fixes:
        assert f"--set {fix.override}" in r.reason and "\n" not in r.reason
        fixed = search_designs(with_overrides(sc, [fix.override]), 10.0, planner=planner)
        assert fixed.feasible, fix


def test_a_slope_no_vehicle_value_reaches_gets_the_steepest_slope_that_works(planner):
    # at 120 deg the wall vehicle has no inclined hover at all: no rotor or mass helps
    sc = load_scenario("wall90", WALL_VEHICLE)
    r = search_designs(sc, 120.0, planner=planner, fixes=True)
    assert r.limit is DesignLimit.LANDED_HOVER and r.binding == "no_inclined_hover"
    (fix,) = r.fixes
    assert fix.field == "surface.slope_deg" and 90.0 <= fix.value < 120.0
    assert search_designs(sc, fix.value, planner=planner).feasible
    # the steepest within the rounding of 0.5 deg and the bisection (120 / 8 / 2^6 deg)
    assert not search_designs(sc, fix.value + 0.5 + 120 / 8 / 2**6, planner=planner).feasible


def test_the_fixes_are_asked_for_only(planner):
    r = search_designs(load_scenario("slope50", WEAK), 10.0, planner=planner)
    assert r.fixes == () and "a design exists" not in r.reason


def test_design_cli_prints_the_fix_and_lists_it_in_json(capsys):
    code = main(["design", "slope50", "--slope-deg", "10", "--set", WEAK[0], "--json"])
    out, err = capsys.readouterr()
    doc = json.loads(out)
    assert code == 1 and not doc["feasible"]
    fields = {f["field"]: f for f in doc["fixes"]}
    assert "vehicle.f_max" in fields and "--set vehicle.f_max=" in err
    assert (
        fields["vehicle.f_max"]["override"] == f"vehicle.f_max={fields['vehicle.f_max']['value']:g}"
    )
