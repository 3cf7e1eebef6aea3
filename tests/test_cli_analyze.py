"""The command line: `analyze`, `scenarios`, `show`, and bad input (exit 2, one line)."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from tetherland.cli import main

REQUIRED_KEYS = {
    "surface": ["slope_rad", "x_S", "y_S", "z_S"],
    "tethered": [
        "c",
        "d_tilde",
        "landing_point",
        "anchor_point",
        "phi_star",
        "theta_A_star",
        "hover_thrust",
        "hover_tension",
        "max_touchdown_thrust",
        "condition5_holds",
        "feasible",
        "max_slope_rad",
    ],
    "free_flight": [
        "condition4_possible",
        "condition5_holds_motors_off",
        "max_touchdown_thrust",
        "max_slope_rad",
        "feasible",
    ],
}


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_analyze_json_has_required_keys_and_values(capsys):
    code, out, _ = run(capsys, "analyze", "slope50", "--json")
    assert code == 0
    doc = json.loads(out)
    for section, keys in REQUIRED_KEYS.items():
        for key in keys:
            assert key in doc[section], f"{section}.{key}"
    assert doc["surface"]["slope_rad"] == pytest.approx(math.radians(50))
    assert doc["tethered"]["feasible"] is True and doc["free_flight"]["feasible"] is False
    assert doc["tethered"]["theta_A_star"] == pytest.approx(math.radians(50))
    assert doc["provenance"]["scenario_name"] == "slope50"
    assert doc["provenance"]["scenario"]["surface"]["slope_deg"] == 50.0
    assert doc["provenance"]["tetherland_version"]


def test_analyze_json_applies_overrides(capsys):
    _, out, _ = run(capsys, "analyze", "slope50", "--set", "surface.slope_deg=30", "--json")
    assert json.loads(out)["surface"]["slope_rad"] == pytest.approx(math.radians(30))


def test_analyze_table_output(capsys):
    code, out, _ = run(capsys, "analyze", "pipe60")
    assert code == 0
    assert "Table 6.1" in out and "tethered" in out and "60.0 deg" in out


def test_scenarios_lists_builtins(capsys):
    code, out, _ = run(capsys, "scenarios")
    assert code == 0
    for name in ("flat", "slope50", "pipe60", "steep70"):
        assert name in out


def test_show_prints_loadable_toml(capsys, tmp_path: Path):
    code, out, _ = run(capsys, "show", "slope50", "--set", "vehicle.mass=1.5")
    assert code == 0
    path = tmp_path / "resolved.toml"
    path.write_text(out)
    code, out, _ = run(capsys, "analyze", str(path), "--json")
    assert code == 0 and json.loads(out)["vehicle"]["mass"] == 1.5


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["analyze", "slope50", "--set", "vehicle.mas=1"], "vehicle.mas: unknown key"),
        (["analyze", "slope50", "--set", "vehicle.mass=-1"], "allowed range (0, 100]"),
        (["analyze", "slope50", "--set", "vehicle.mass=nan"], "vehicle.mass"),
        (["analyze", "slope50", "--set", "surface.slope_deg=181"], "allowed range [0, 180]"),
        (["analyze", "slope50", "--set", "surface.slope_deg=nan"], "allowed range [0, 180]"),
        (
            ["analyze", "slope50", "--set", "vehicle.h_R=0.9", "--set", "tether.length=0.8"],
            "tether.length = 0.8 m",
        ),
        (["analyze", "slope50", "--set", "vehicle.f_min=9"], "vehicle.f_min"),
        (["analyze", "slope50", "--set", "anchor.landing_point=[0,0,2]"], "anchor.landing_point"),
        (["analyze", "missing-file.toml"], "does not exist"),
        (["analyze", "slope50", "--bogus"], "No such option"),
        (["analyze"], "Missing argument"),
    ],
)
def test_bad_input_exit_2_one_line(capsys, argv: list[str], needle: str):
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ")
    assert needle in lines[0]


def test_invalid_toml_exit_2(capsys, tmp_path: Path):
    path = tmp_path / "bad.toml"
    path.write_text("mass = = 1")
    code, _, err = run(capsys, "analyze", str(path))
    assert code == 2 and "not valid TOML" in err and "Traceback" not in err


def test_console_script_reports_without_traceback():
    exe = Path(sys.executable).with_name("tetherland")
    proc = subprocess.run(
        [str(exe), "analyze", "slope50", "--set", "surface.slope_deg=190"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr
    assert proc.stderr.startswith("error: surface.slope_deg")
    ok = subprocess.run([str(exe), "--version"], capture_output=True, text=True, check=False)
    assert ok.returncode == 0 and ok.stdout.startswith("tetherland ")
