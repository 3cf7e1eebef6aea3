"""Scenario field names follow one rule in every section, and old names fail with the new one.

The rule (``tetherland.config.schema``): fields in SI units carry no unit suffix; fields in
degrees end in ``_deg``, in degrees per second in ``_deg_s``, in hertz in ``_hz``; no other
unit suffix. Every numeric field states its unit in brackets at the end of its
description. Time constants are spelled ``*_time_constant``. A name used in two places
means the same thing in both.
"""

from __future__ import annotations

import re
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

from tetherland.cli import main
from tetherland.config import RENAMES, Scenario, load_scenario, scenario_to_toml
from tetherland.config.schema import FieldDoc, fields, sections, split_unit
from tetherland.errors import ConfigError

FIELDS: list[FieldDoc] = list(fields(Scenario))
KEYS = {f.key for f in FIELDS}

SUFFIX_UNITS = {"_deg_s": "deg/s", "_deg": "deg", "_hz": "Hz"}
"""The only unit suffixes, and the unit each one stands for."""
OTHER_UNIT_SUFFIXES = (
    "_m", "_mm", "_cm", "_km", "_s", "_ms", "_sec", "_h", "_mps", "_mps2", "_ms2",
    "_rps", "_rps2", "_rad", "_rad_s", "_rads", "_radps", "_n", "_nm", "_kg", "_g", "_pa",
    "_degps", "_dps", "_deg_per_s", "_khz", "_pct", "_percent",
)  # fmt: skip
"""Unit suffixes the rule forbids (SI fields carry none; the others have one spelling)."""

SHARED_NAMES = {
    "rate_hz": "the rate of a periodic output: a sensor's samples, the controller's commands",
    "nodes": "shooting intervals of an optimal control problem (tethered or perching)",
    "integrator_step": "largest RK4 step of a shooting integrator",
    "k_thrust_accel": "cost weight of the rotor thrust accelerations",
    "attitude_frequency": "natural frequency of an inner roll/pitch attitude loop",
    "attitude_damping": "damping ratio of an inner roll/pitch attitude loop",
    "yaw_frequency": "natural frequency of an inner yaw loop",
    "yaw_damping": "damping ratio of an inner yaw loop",
    "kind": "which variant of the section applies",
    "speed": "peak speed of the section's pass (hooking, stretching)",
    "approach_speed": "speed towards the surface at touchdown (planned or allowed)",
    "rotor_drag": "rotor drag (d_x, d_y) at the hover rotor speed: the plant's in [aero], "
    "the robot's belief in [controller]",
}
"""Names used in more than one section, each with its one meaning."""


def test_the_schema_walk_sees_every_section_and_field():
    sections = {f.section for f in FIELDS}
    assert {"vehicle", "tether", "surface", "anchor", "sensors.imu", "sensors.mocap", "planner",
            "planner.weights", "controller.free_flight", "controller.tethered", "mission",
            "mission.flight", "mission.hooking", "mission.stretch", "mission.touchdown",
            "mission.contact", "mission.detection", "sim", "perturbation", "perching",
            "perching.weights", "verdict", "faults"} <= sections  # fmt: skip
    # every key is one a TOML file can give: it round-trips through scenario_to_toml
    toml = scenario_to_toml(load_scenario("slope50"))
    for f in FIELDS:
        if f.default is not None:
            assert re.search(rf"^{re.escape(f.name)} = ", toml, re.M), f.key


@pytest.mark.parametrize("field", [f for f in FIELDS if f.numeric], ids=lambda f: f.key)
def test_every_numeric_field_states_its_unit_and_meaning(field: FieldDoc):
    assert field.unit, f"{field.key}: the description must end with its unit in brackets"
    assert len(field.meaning.split()) >= 3, f"{field.key}: the description must say what it is"


@pytest.mark.parametrize("field", FIELDS, ids=lambda f: f.key)
def test_unit_suffixes_follow_one_rule(field: FieldDoc):
    name = field.name
    suffix = next((s for s in SUFFIX_UNITS if name.endswith(s)), None)
    if suffix is not None:
        assert field.unit == SUFFIX_UNITS[suffix], f"{field.key} is in [{field.unit}]"
    else:
        assert field.unit not in SUFFIX_UNITS.values(), (
            f"{field.key} is in [{field.unit}]: its name must end in the unit's suffix"
        )
        bad = [s for s in OTHER_UNIT_SUFFIXES if name.lower().endswith(s)]
        assert not bad, f"{field.key}: SI fields carry no unit suffix ({bad[0]})"


@pytest.mark.parametrize("field", FIELDS, ids=lambda f: f.key)
def test_time_constants_have_one_spelling(field: FieldDoc):
    name = field.name
    assert not re.search(r"timeconst|time_const(?!ant)|_tau\b|filter_time|dampratio", name)
    if "time constant" in field.meaning.lower() and not name.endswith("_rel"):
        assert name.endswith("_time_constant"), field.key


def test_a_name_in_two_places_has_one_meaning():
    counts = Counter(f.name for f in FIELDS)
    shared = {name for name, n in counts.items() if n > 1}
    assert shared == set(SHARED_NAMES), (
        "names used in several sections must mean the same thing in each; say what in "
        f"SHARED_NAMES or rename: {sorted(shared ^ set(SHARED_NAMES))}"
    )


def test_the_two_contact_forces_have_distinct_names():
    """The robot's estimated surface push and the judge's true touchdown force."""
    assert "mission.contact.surface_force" in KEYS and "verdict.touchdown_force" in KEYS
    assert not any(f.name == "contact_force" for f in FIELDS)


def test_split_unit_reads_the_trailing_brackets():
    assert split_unit("Time [s].") == ("Time.", "s")
    assert split_unit("Tension in (0, 10] [N m].") == ("Tension in (0, 10].", "N m")
    assert split_unit("Moved this far\n    [m].") == ("Moved this far.", "m")
    assert split_unit("No unit here.") == ("No unit here.", None)


# --- renames ---------------------------------------------------------------------------------


def test_the_rename_table_maps_old_names_to_fields_that_exist():
    assert len(set(RENAMES.values())) == len(RENAMES)  # no two old names onto one field
    for old, new in RENAMES.items():
        assert new in KEYS, f"{old} -> {new}: no such field"
        assert old not in KEYS, f"{old} is still a field"
        assert old.split(".")[0] == new.split(".")[0], "renames stay in their section"


@pytest.mark.parametrize(("old", "new"), sorted(RENAMES.items()))
def test_an_old_name_in_an_override_names_the_new_field(old: str, new: str):
    with pytest.raises(ConfigError) as info:
        load_scenario("slope50", [f"{old}=1"])
    assert str(info.value) == f"{old} was renamed: use {new}"


def test_old_names_in_a_file_are_all_named_on_one_line(tmp_path: Path):
    path = tmp_path / "old.toml"
    path.write_text(
        "[mission]\ntouchdown_hold_rate = 0.2\ncontact_force = 0.1\n\n"
        "[verdict]\nspeed_mps = 0.2\n"
    )
    with pytest.raises(ConfigError) as info:
        load_scenario(path)
    message = str(info.value)
    assert "\n" not in message
    for old, new in (("mission.touchdown_hold_rate", "mission.touchdown.hold_rate"),
                     ("mission.contact_force", "mission.contact.surface_force"),
                     ("verdict.speed_mps", "verdict.touchdown_speed")):  # fmt: skip
        assert f"{old} was renamed: use {new}" in message


def test_the_new_names_load_with_their_values(tmp_path: Path):
    path = tmp_path / "new.toml"
    path.write_text(
        "[mission.touchdown]\nhold_rate = 0.2\n\n[mission.contact]\nsurface_force = 0.1\n"
    )
    s = load_scenario(path, ["verdict.touchdown_speed=0.2"])
    assert s.mission.touchdown.hold_rate == 0.2 and s.mission.contact.surface_force == 0.1
    assert s.verdict.touchdown_speed == 0.2


def test_cli_old_name_exit_2_one_line(capsys, tmp_path: Path):
    path = tmp_path / "old.toml"
    path.write_text("[mission]\ntouchdown_hold_rate = 0.2\n")
    for argv in (["show", str(path)],
                 ["analyze", "slope50", "--set", "sim.contact_timeconst=0.01"]):  # fmt: skip
        code = main(argv)
        out, err = capsys.readouterr()
        assert code == 2 and out == "" and "Traceback" not in err
        lines = err.strip().splitlines()
        assert len(lines) == 1
    assert lines[0] == "error: sim.contact_timeconst was renamed: use sim.contact_time_constant"
    exe = Path(sys.executable).with_name("tetherland")
    proc = subprocess.run([str(exe), "show", str(path)], capture_output=True, text=True)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.strip() == (
        "error: mission.touchdown_hold_rate was renamed: use mission.touchdown.hold_rate"
    )


# --- the docs use the current names -----------------------------------------------------------

ROOT = Path(__file__).resolve().parents[1]
SECTIONS = {name for name, _ in sections(Scenario)}
NOT_FIELDS = {"sim.render", "surface.py", "tether.cable_model", "mission.hooking.hook_offset",
              "sim.start.plan_start_state", "planner.py", "sensors.py", "estimator.py",
              "verdict.failures"}  # fmt: skip
"""Dotted names in the docs that are modules, functions, properties or record fields (a
campaign record's ``verdict.failures``), not TOML keys."""


def _doc_files() -> list[Path]:
    roots = [ROOT / "README.md", *(ROOT / d for d in ("docs", "examples", "benchmarks"))]
    roots.append(ROOT / "src" / "tetherland" / "scenarios")
    files = []
    for root in roots:
        files += [root] if root.is_file() else sorted(root.rglob("*"))
    generated = ROOT / "docs" / "reference"  # lists the old names on purpose
    return [p for p in files if p.suffix in (".md", ".py", ".toml", ".sh")
            and generated not in p.parents]  # fmt: skip


def test_command_lines_and_names_in_the_docs_are_current_fields():
    tops = "|".join(sorted({k.split(".")[0] for k in KEYS if "." in k}))
    option = re.compile(rf"--(?:set|sweep)[ =]+[\"']?((?:{tops})\.[A-Za-z0-9_.]+)=")
    quoted = re.compile(rf"`((?:{tops})\.[a-z0-9_]+(?:\.[a-z0-9_]+)*)`")
    stale = []
    for path in _doc_files():
        text = path.read_text(encoding="utf-8")
        for match in option.finditer(text):
            if match.group(1) not in KEYS:
                stale.append((path.name, match.group(1)))
        for match in quoted.finditer(text):
            name = match.group(1)
            if name not in KEYS and name not in SECTIONS and name not in NOT_FIELDS:
                stale.append((path.name, name))
    assert not stale, stale
