"""`tetherland design`: the JSON document, exit codes, the feasibility map files."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tetherland.cli import main


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_json_document_and_overrides_that_plan(capsys, tmp_path):
    code, out, err = run(capsys, "design", "slope50", "--slope-deg", "70", "--json")
    assert code == 0 and err == ""
    doc = json.loads(out)
    assert doc["slope_deg"] == 70.0 and doc["feasible"] is True and doc["reason"] == "ok"
    assert isinstance(doc["designs"], list) and doc["designs"]
    for d in doc["designs"]:
        assert set(d) >= {"overrides", "min_rotor_margin_N", "min_clearance_m"}
        assert all(isinstance(o, str) and "=" in o for o in d["overrides"])
        assert isinstance(d["min_rotor_margin_N"], float)
        assert isinstance(d["min_clearance_m"], float)
    assert doc["provenance"]["scenario_name"] == "slope50"
    assert doc["wall_time_s"] > 0
    # the overrides of the best design, as `--set` values, plan with the other commands
    best = doc["designs"][0]
    args = [a for o in best["overrides"] for a in ("--set", o)]
    for maneuver in ("landing", "takeoff"):
        code, out, _ = run(capsys, "plan", "slope50", *args, "--maneuver", maneuver, "--json",
                           "--out", str(tmp_path / maneuver))  # fmt: skip
        assert code == 0
        summary = json.loads(out)
        assert summary["status"] == "solved" and summary["min_tension_N"] > 0
    code, out, _ = run(capsys, "analyze", "slope50", *args, "--json")
    assert code == 0 and json.loads(out)["tethered"]["feasible"] is True


def test_infeasible_request_is_one_line_exit_1(capsys):
    code, out, err = run(capsys, "design", "slope50", "--slope-deg", "140")
    lines = err.strip().splitlines()
    assert code == 1 and len(lines) == 1
    assert lines[0].startswith("error: no design lands on 140 deg") and "no_inclined_hover" in err
    code, out, err = run(capsys, "design", "slope50", "--slope-deg", "100", "--json")
    assert code == 1
    doc = json.loads(out)
    assert (
        doc["feasible"] is False and doc["designs"] == [] and doc["binding"] == "hooking_clearance"
    )
    assert len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--slope-deg", "nan"], "surface.slope_deg"),
        (["--slope-deg", "inf"], "surface.slope_deg"),
        (["--slope-deg", "181"], "allowed range [0, 180]"),
        (["--set", "tether.approach_direction=[0,0,0]"], "approach_direction must be a non-zero"),
        (["--set", "surface.normal=[1,0,1]"], "surface.normal"),
        (["--slope-deg", "abc"], "--slope-deg"),
    ],
)
def test_bad_input_exit_2_one_line_nothing_written(capsys, tmp_path, argv, needle):
    out_dir = tmp_path / "map"
    code, out, err = run(capsys, "design", "slope50", *argv, "--out", str(out_dir))
    lines = err.strip().splitlines()
    assert code == 2 and out == "" and len(lines) == 1 and needle in lines[0]
    assert "Traceback" not in err
    assert not out_dir.exists()


def test_out_writes_the_map_with_provenance(capsys, tmp_path, monkeypatch):
    import sys

    cli_design = sys.modules["tetherland.cli.design"]  # the package exports the function
    monkeypatch.setattr(cli_design, "MAP_SLOPES_DEG", (60.0, 90.0))
    monkeypatch.setattr(cli_design, "MAP_LENGTHS", (0.4, 1.0))
    code, out, err = run(capsys, "design", "slope50", "--slope-deg", "60", "--json",
                         "--out", str(tmp_path))  # fmt: skip
    assert code == 0, err
    doc = json.loads(out)
    files = {k: Path(v) for k, v in doc["files"].items()}
    assert set(files) == {"map", "map_data", "map_csv", "design"}
    assert files["map"].stat().st_size < 200_000
    data = json.loads(files["map_data"].read_text())
    assert data["provenance"]["scenario_name"] == "slope50" and data["provenance"]["git_commit"]
    assert data["chosen"]["overrides"] == doc["designs"][0]["overrides"]
    assert len(data["cells"]) == 4 and len(data["steepest"]) == 2
    rows = files["map_csv"].read_text().splitlines()
    assert rows[0].startswith("# tetherland") and len(rows) == 2 + 4
    assert json.loads(files["design"].read_text())["designs"] == doc["designs"]
