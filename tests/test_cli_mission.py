"""`tetherland mission` and `tetherland campaign` from the command line (headless)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tetherland.cli import main

EXE = str(Path(sys.executable).with_name("tetherland"))


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (
            ["mission", "slope50", "--method", "hover"],
            "--method must be one of tethered, free-flight",
        ),
        (["mission", "slope50", "--controller", "pid"], "--controller must be one of"),
        (["mission", "slope50", "--seed", "-1"], "--seed must be >= 0"),
        (["mission", "slope50", "--set", "mission.deploy_time=-1"], "mission.deploy_time"),
        (["campaign", "slope50", "--engine", "mpi", "--job", "analysis"], "unknown engine"),
        (["campaign", "slope50", "--runs", "0"], "--runs must be >= 1"),
    ],
)
def test_bad_mission_and_campaign_input(capsys, tmp_path, argv, needle):
    code = main([*argv, "--out", str(tmp_path / "o")])
    _, err = capsys.readouterr()
    assert code == 2 and err.count("\n") == 1 and needle in err


@pytest.mark.slow
def test_mission_json_files_and_exit_code(tmp_path: Path):
    out = tmp_path / "m"
    proc = subprocess.run(
        [EXE, "mission", "pipe60", "--seed", "3", "--out", str(out), "--json"],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    doc = json.loads(proc.stdout)
    for key in ("success", "phases", "landing", "takeoff", "return", "sim_time_s", "wall_time_s",
                "real_time_factor"):  # fmt: skip
        assert key in doc
    for key in ("position_error_m", "attitude_error_rad", "touchdown_speed_mps",
                "touchdown_angular_rate_rps", "touchdown_accel_mps2", "slip_m", "min_tension_N",
                "conditions"):  # fmt: skip
        assert key in doc["landing"]
    assert doc["success"] is True
    for name in (
        "log.npz",
        "summary.json",
        "figure_6_5.png",
        "path_3d.png",
        "landing_trajectory.csv",
    ):
        assert (out / name).stat().st_size > 1000
    assert json.loads((out / "summary.json").read_text())["provenance"]["scenario_name"] == "pipe60"


@pytest.mark.slow
def test_free_flight_method_slides_on_slope50(tmp_path: Path):
    """Contact-free perching on 50 deg (tan 50 > mu): the verdict is failure, exit code 1."""
    proc = subprocess.run(
        [EXE, "mission", "slope50", "--method", "free-flight", "--out", str(tmp_path), "--json"],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    assert proc.returncode == 1, proc.stderr[-2000:]
    doc = json.loads(proc.stdout)
    assert doc["method"] == "free-flight" and doc["success"] is False
    assert doc["landing"]["conditions"]["5"] is False and doc["landing"]["slip_m"] > 0.05
