"""`tetherland show --all`: every field, unset ones included, with its unit and range as a
TOML comment (from the schema, :mod:`tetherland.config.schema`), loadable again."""

from __future__ import annotations

import re
import tomllib

import pytest

from tetherland.cli import main
from tetherland.config import Scenario, load_scenario, scenario_from_dict
from tetherland.config.schema import fields


def _show(capsys, *argv: str) -> str:
    code = main(["show", *argv])
    out, err = capsys.readouterr()
    assert code == 0 and err == ""
    return out


def _lines_by_section(text: str) -> dict[str, list[str]]:
    """The lines of each TOML table (comments included)."""
    out: dict[str, list[str]] = {"": []}
    section = ""
    for line in text.splitlines():
        header = re.fullmatch(r"\[([\w.]+)\]", line)
        if header:
            section = header.group(1)
            out[section] = []
        else:
            out[section].append(line)
    return out


@pytest.mark.parametrize("name", ["slope50", "wall90", "pipe60"])
def test_every_field_is_printed_with_its_unit_and_range(capsys, name):
    text = _show(capsys, name, "--all")
    sc = load_scenario(name)
    dumped = sc.model_dump(mode="json")
    tables = _lines_by_section(text)
    docs = list(fields(Scenario))
    assert len(docs) > 200
    for doc in docs:
        value = dumped
        for part in doc.key.split("."):
            value = value[part]
        lines = tables[doc.section]
        if value is None:  # unset: commented out, said so
            line = next(x for x in lines if x.startswith(f"# {doc.name} =  # unset"))
        else:
            line = next(x for x in lines if x.startswith(f"{doc.name} = "))
        if doc.unit is not None:
            assert f"[{doc.unit}]" in line, line
        if doc.range is not None:
            assert f"range {doc.range}" in line, line


def test_the_new_users_unset_fields_are_listed(capsys):
    text = _show(capsys, "slope50", "--all")
    for section, name, unit in [
        ("mission", "abort_time", "s"),
        ("faults", "cable_snap_time", "s"),
        ("tether", "axial_stiffness", "N"),
        ("anchor", "position", "m"),
    ]:
        lines = _lines_by_section(text)[section]
        assert any(x.startswith(f"# {name} =  # unset; [{unit}]") for x in lines), name
    # the plain `show` omits them (TOML has no null)
    plain = _show(capsys, "slope50")
    assert "abort_time" not in plain and "cable_snap_time" not in plain


def test_the_output_loads_back_to_the_same_scenario(capsys, tmp_path):
    path = tmp_path / "anchored.toml"
    path.write_text("[anchor]\nposition = [-0.5, 0.2, 0.595876796297]\n")  # on the 50 deg plane
    overrides = ["faults.cable_snap_time=31.5", 'description="a \\"quoted\\" name"']
    sc = load_scenario(path, overrides)
    text = _show(capsys, str(path), *(a for o in overrides for a in ("--set", o)), "--all")
    again = scenario_from_dict(tomllib.loads(text))
    assert again.model_dump() == sc.model_dump()
    tables = _lines_by_section(text)
    line = "position = [-0.5, 0.2, 0.595876796297]  # [m], [float, float, float] or none"
    assert line in tables["anchor"]
    assert any(x.startswith("cable_snap_time = 31.5  # [s]") for x in tables["faults"])


def test_a_partial_file_is_completed_from_the_defaults(capsys, tmp_path):
    """A file names only what it changes; every other field takes the schema's default,
    which `show --all` prints."""
    path = tmp_path / "mine.toml"
    path.write_text("[vehicle]\nmass = 1.4\n")
    text = _show(capsys, str(path), "--all")
    data = tomllib.loads(text)
    assert data["vehicle"]["mass"] == 1.4
    defaults = Scenario.model_fields["surface"].annotation.model_fields
    assert data["surface"]["slope_deg"] == defaults["slope_deg"].default
    assert data["name"] == "mine"
