"""Bad input on walls and overhangs, for every command that takes a scenario: one line.

Invalid input (a zero-length approach direction, a non-finite slope) exits 2, a valid slope
the vehicle cannot reach exits 1 naming the binding reason; never a traceback, and nothing
is written for an invalid request or a mission that cannot be flown.
"""

from __future__ import annotations

import pytest

from tetherland.cli import main

COMMANDS = ("design", "analyze", "plan", "mission")
_WRITES = {"design", "plan", "mission"}  # commands with --out


def _run(capsys, tmp_path, command: str, *overrides: str) -> tuple[int, str, str, object]:
    out_dir = tmp_path / "o"
    argv = [command, "wall90", *(a for o in overrides for a in ("--set", o))]
    if command in _WRITES:
        argv += ["--out", str(out_dir)]
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err, out_dir


@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize(
    ("override", "needle"),
    [
        ("tether.approach_direction=[0,0,0]", "tether.approach_direction"),
        ("surface.slope_deg=nan", "surface.slope_deg"),
        ("surface.slope_deg=inf", "surface.slope_deg"),
        ("surface.slope_deg=-inf", "surface.slope_deg"),
    ],
)
def test_invalid_input_exits_2_with_one_line(capsys, tmp_path, command, override, needle):
    code, out, err, out_dir = _run(capsys, tmp_path, command, override)
    lines = err.strip().splitlines()
    assert code == 2 and out == ""
    assert len(lines) == 1 and lines[0].startswith(f"error: {needle}")
    assert "Traceback" not in err
    assert not out_dir.exists()


@pytest.mark.parametrize(
    ("command", "needle"),
    [
        ("analyze", "(binding: rotor_floor)"),
        ("plan", "rotor f_min too high"),
        ("mission", "rotor f_min too high"),
    ],
)
def test_unreachable_slope_exits_1_with_the_binding_reason(capsys, tmp_path, command, needle):
    code, _, err, out_dir = _run(capsys, tmp_path, command, "surface.slope_deg=100")
    lines = err.strip().splitlines()
    assert code == 1 and len(lines) == 1 and needle in lines[0]
    assert lines[0].startswith("error: ") and "Traceback" not in err
    if command == "mission":
        # a mission that cannot be planned is not flown and leaves no results behind
        assert not out_dir.exists()


def test_unreachable_slope_for_design_names_the_binding_limit(capsys):
    """`design` may shorten the cable (the rotor floor then holds up to about 103 deg): on
    100 deg the hooking clearance binds instead."""
    code = main(["design", "wall90", "--slope-deg", "100"])
    _, err = capsys.readouterr()
    lines = err.strip().splitlines()
    assert code == 1 and len(lines) == 1 and lines[0].startswith("error: no design lands on 100")
    assert "hooking pass comes too close to the surface" in lines[0]
