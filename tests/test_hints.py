"""Every "not flown" hint names the field to change and a value that works, or the design
command (issue 24, item 5): the value of each hint applied makes the mission plan."""

from __future__ import annotations

import re

import pytest

from tetherland.config import load_scenario
from tetherland.mission.plan import MissionError, plan_mission
from tetherland.sim import Plant


def _plan(sc):
    return plan_mission(sc, Plant(sc).start_state())


def _suggested(message: str) -> str:
    match = re.search(r"set ([a-z_.]+=[0-9.]+)", message)
    assert match is not None, message
    return match.group(1)


@pytest.mark.parametrize(
    ("scenario", "overrides", "field"),
    [
        # the "use hook_drop >= 1.21 m with hook_drop + capture_radius < length" case
        ("slope50", ["surface.slope_deg=70"], "tether.hook_drop"),
        ("wall90", ["tether.hook_drop=0.1"], "tether.hook_drop"),
        ("slope50", ["mission.time_limit=5"], "mission.time_limit"),
    ],
)
def test_applying_the_suggested_value_makes_the_mission_plan(scenario, overrides, field):
    sc = load_scenario(scenario, overrides)
    with pytest.raises(MissionError) as info:
        _plan(sc)
    fix = _suggested(str(info.value))
    assert fix.startswith(field + "=")
    plan = _plan(load_scenario(scenario, [*overrides, fix]))
    assert plan.clearance.ok


def test_a_hook_drop_that_cannot_fit_the_cable_points_at_the_design_command():
    # it needs a drop of about 0.84 m: none fits a 0.6 m cable
    sc = load_scenario(
        "slope50", ["surface.slope_deg=70", "tether.length=0.6", "tether.hook_drop=0.4"]
    )
    with pytest.raises(MissionError) as info:
        _plan(sc)
    message = str(info.value)
    assert "no hook drop fits inside tether.length = 0.6 m" in message
    assert "`tetherland design slope50`" in message and "tether.approach_direction" in message
