"""Scenario loading, overrides and validation (issue 2, items 2 and 6)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from pydantic import ValidationError

from tetherland.config import (
    Scenario,
    apply_overrides,
    builtin_scenarios,
    load_scenario,
    parse_override,
    scenario_to_toml,
)
from tetherland.errors import ConfigError

BUILTINS = {"flat", "slope50", "pipe60", "steep70"}


def test_builtins_are_listed_and_load():
    names = {info.name for info in builtin_scenarios()}
    assert BUILTINS <= names
    for name in names:
        scenario = load_scenario(name)
        assert scenario.name == name
        assert scenario.description


def test_slope50_matches_design_defaults(slope50: Scenario):
    v = slope50.vehicle
    assert (v.mass, v.f_min, v.f_max, v.h_R, v.arm_length) == (1.0, 0.2, 6.0, 0.10, 0.23)
    assert v.inertia == (0.015, 0.015, 0.025)
    assert slope50.surface.slope_deg == 50.0
    assert slope50.surface.friction == 0.6
    assert slope50.tether.length == 1.0
    assert slope50.sensors.imu.rate_hz == 1000.0
    assert slope50.sensors.mocap.rate_hz == 120.0


def test_override_changes_value_and_keeps_rest(slope50: Scenario):
    s = load_scenario("slope50", ["surface.slope_deg=70", "vehicle.inertia=[0.02, 0.02, 0.03]"])
    assert s.surface.slope_deg == 70.0
    assert s.vehicle.inertia == (0.02, 0.02, 0.03)
    assert s.vehicle.mass == slope50.vehicle.mass


def test_override_plain_string_and_nested_section():
    s = load_scenario("slope50", ["surface.kind=pipe", "sensors.imu.gyro_noise=0.01"])
    assert s.surface.kind == "pipe"
    assert s.sensors.imu.gyro_noise == 0.01


def test_parse_override_parses_toml_values():
    assert parse_override("a.b=1") == (["a", "b"], 1)
    assert parse_override("a.b = [1, 2.5]") == (["a", "b"], [1, 2.5])
    assert parse_override('a.b="x=y"') == (["a", "b"], "x=y")
    assert parse_override("a.b=true") == (["a", "b"], True)


def test_apply_overrides_does_not_mutate_input():
    data = {"surface": {"slope_deg": 10}}
    out = apply_overrides(data, ["surface.slope_deg=20"])
    assert data["surface"]["slope_deg"] == 10
    assert out["surface"]["slope_deg"] == 20


def test_scenarios_are_frozen(slope50: Scenario):
    with pytest.raises(ValidationError):
        slope50.vehicle.mass = 2.0  # type: ignore[misc]


def test_toml_round_trip(tmp_path: Path):
    s = load_scenario("pipe60", ["vehicle.mass=1.2", "surface.friction=0.45"])
    path = tmp_path / "round.toml"
    path.write_text(scenario_to_toml(s))
    again = load_scenario(path)
    assert again == s


def test_scenario_file_path_and_name_from_stem(tmp_path: Path):
    path = tmp_path / "my_ramp.toml"
    path.write_text("[surface]\nslope_deg = 30.0\n")
    s = load_scenario(str(path))
    assert s.name == "my_ramp"
    assert s.surface.slope_deg == 30.0


def test_normal_instead_of_slope(tmp_path: Path):
    beta = math.radians(35.0)
    path = tmp_path / "normal.toml"
    path.write_text(f"[surface]\nnormal = [{math.sin(beta)}, 0.0, {math.cos(beta)}]\n")
    s = load_scenario(path)
    from tetherland.geometry import surface_from_config

    assert surface_from_config(s).slope == pytest.approx(beta, abs=1e-12)


# --- bad input: one line naming the field and the allowed range ----------------------------

BAD_OVERRIDES = [
    (["vehicle.mas=1"], r"vehicle\.mas: unknown key \(allowed keys: .*mass"),
    (["vehicle.mass=-1"], r"vehicle\.mass: .*greater than 0.*allowed range \(0, 100\]"),
    (["vehicle.mass=nan"], r"vehicle\.mass: .*finite.*allowed range"),
    (["vehicle.mass=inf"], r"vehicle\.mass: .*finite"),
    (["surface.slope_deg=185"], r"surface\.slope_deg: .*allowed range \[0, 180\]"),
    (["surface.slope_deg=-1"], r"surface\.slope_deg: .*allowed range \[0, 180\]"),
    (["surface.slope_deg=nan"], r"surface\.slope_deg: .*finite.*allowed range \[0, 180\]"),
    (["surface.slope_deg=inf"], r"surface\.slope_deg: .*finite.*allowed range \[0, 180\]"),
    (
        ["vehicle.h_R=0.9", "tether.length=0.8"],
        r"tether\.length = 0\.8 m must be > \|h_att - anchor\.h_A\|",
    ),
    (["tether.length=0.4"], r"tether\.hook_drop \+ capture_radius = 0\.6 m must be < length"),
    (["anchor.h_A=1.2"], r"tether\.length = 1\.0 m must be >"),
    (["vehicle.f_min=7"], r"vehicle\.f_min = 7\.0 N must be < f_max = 6\.0 N"),
    (["anchor.landing_point=[0, 0, 1]"], r"anchor\.landing_point must lie on the surface"),
    (["anchor.position=[0, 0, 0]"], r"anchor\.position and landing_point are mutually exclusive"),
    (["surface.kind=tube"], r"surface\.kind: .*'plane' or 'pipe'"),
    (["vehicle.inertia=[0.01, -1, 0.01]"], r"vehicle\.inertia\[1\]: .*greater than 0"),
    (["vehicle.inertia=[0.01, 0.01, 0.05]"], r"vehicle\.inertia: .*triangle"),
    (["surface.kind=pipe", "surface.pipe_radius=0.1"], r"surface\.pipe_radius = 0\.1 m must be >"),
    (["planner.nodes=3"], r"planner\.nodes: .*allowed range \[10, 2000\]"),
    (["nosuchsection.x=1"], r"nosuchsection: unknown key"),
    (["vehicle=3"], r"vehicle: "),
    (["surface.slope_deg"], r"expected section\.key=value"),
]


@pytest.mark.parametrize(("overrides", "pattern"), BAD_OVERRIDES)
def test_bad_overrides_give_one_line_errors(overrides: list[str], pattern: str):
    with pytest.raises(ConfigError) as info:
        load_scenario("slope50", overrides)
    message = str(info.value)
    assert "\n" not in message
    assert re.search(pattern, message), message


def test_anchor_not_on_surface_is_rejected(tmp_path: Path):
    path = tmp_path / "floating_anchor.toml"
    path.write_text("[anchor]\nposition = [0.0, 0.0, 0.5]\n")
    with pytest.raises(
        ConfigError, match=r"anchor\.position must lie at height anchor\.h_A = 0\.0 m"
    ):
        load_scenario(path)


def test_anchor_on_surface_is_accepted():
    from tetherland.config import scenario_from_dict
    from tetherland.geometry import LandingGeometry

    s = scenario_from_dict({"anchor": {"position": [-0.5, 0.0, 0.5 * math.tan(math.radians(50))]}})
    assert LandingGeometry.from_scenario(s).surface.height(s.anchor.position) == pytest.approx(
        0.0, abs=1e-12
    )


def test_missing_file_and_unknown_name():
    with pytest.raises(ConfigError, match="does not exist"):
        load_scenario("/nonexistent/dir/x.toml")
    with pytest.raises(
        ConfigError, match=r"neither a built-in \(.*slope50.*\) nor an existing file"
    ):
        load_scenario("nosuchscenario")


def test_invalid_toml(tmp_path: Path):
    path = tmp_path / "broken.toml"
    path.write_text("[vehicle\nmass = 1\n")
    with pytest.raises(ConfigError, match=r"is not valid TOML"):
        load_scenario(path)
