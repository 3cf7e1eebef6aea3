"""`tetherland plan` run headless: files, JSON, exit codes."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tetherland.cli import main
from tetherland.planning import load_trajectory

KEYS = (
    "status", "solve_time_s", "iterations", "cost", "duration_s", "final_error",
    "min_tension_N", "min_rotor_thrust_N", "max_rotor_thrust_N", "provenance",
)  # fmt: skip


def run(capsys, *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_json_summary_and_files(capsys, tmp_path):
    code, out, err = run(capsys, "plan", "slope50", "--json", "--out", str(tmp_path))
    assert code == 0, err
    doc = json.loads(out)
    for key in KEYS:
        assert key in doc
    assert doc["status"] == "solved" and doc["solver"] == "fatrop"
    assert set(doc["final_error"]) == {"phi_rad", "theta_A_rad", "phi_rate", "theta_A_rate"}
    assert max(abs(v) for v in doc["final_error"].values()) < 1e-4
    assert (
        doc["min_tension_N"] > 0
        and 0.2 <= doc["min_rotor_thrust_N"] <= doc["max_rotor_thrust_N"] <= 6.0
    )
    assert doc["provenance"]["scenario_name"] == "slope50"
    assert doc["provenance"]["maneuver"] == "landing"
    for name in ("trajectory.csv", "trajectory.png", "plan.json"):
        assert (tmp_path / name).is_file()
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # atomic writes
    traj = load_trajectory(tmp_path / "trajectory.csv")
    assert traj.meta.maneuver == "landing" and traj.duration == pytest.approx(doc["duration_s"])
    saved = json.loads((tmp_path / "plan.json").read_text())
    assert saved["cost"] == pytest.approx(doc["cost"])


def test_takeoff_spline_with_overrides(capsys, tmp_path):
    code, out, err = run(
        capsys, "plan", "slope50", "--maneuver", "takeoff", "--method", "spline",
        "--set", "surface.slope_deg=60", "--json", "--out", str(tmp_path),
    )  # fmt: skip
    assert code == 0, err
    doc = json.loads(out)
    assert doc["maneuver"] == "takeoff" and doc["method"] == "spline" and doc["solver"] is None
    assert doc["boundary"]["theta_A_start_deg"] == pytest.approx(60.0)
    traj = load_trajectory(tmp_path / "trajectory.csv")
    assert traj.kind == "spline"
    np.testing.assert_allclose(np.degrees(traj.initial_output[2]), 60.0)


def test_human_output_and_default_directory(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, _ = run(capsys, "plan", "flat", "--solver", "ipopt")
    assert code == 0
    assert "solved" in out and "ipopt" in out
    assert (tmp_path / "out" / "flat" / "plan" / "trajectory.csv").is_file()


def test_infeasible_plan_exits_1_with_one_line(capsys, tmp_path):
    code, out, err = run(
        capsys, "plan", "slope50", "--set", "vehicle.f_max=2", "--out", str(tmp_path)
    )
    assert code == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: landing plan infeasible")
    assert "f_max too low" in lines[0] and "Traceback" not in err
    assert not (tmp_path / "trajectory.csv").exists()
    code, out, err = run(
        capsys, "plan", "slope50", "--set", "vehicle.f_max=2", "--json", "--out", str(tmp_path)
    )
    assert code == 1 and json.loads(out)["status"] == "infeasible"


@pytest.mark.parametrize(
    "args",
    [
        ["plan", "nosuch-scenario"],
        ["plan", "slope50", "--solver", "snopt"],
        ["plan", "slope50", "--maneuver", "sideways"],
        ["plan", "slope50", "--set", "planner.nodes=3"],
        ["plan", "slope50", "--set", "planner.weights.k_bogus=1"],
    ],
)
def test_bad_input_exits_2(capsys, args):
    code, _, err = run(capsys, *args)
    assert code == 2
    assert err.startswith("error:") and len(err.strip().splitlines()) == 1
    assert "Traceback" not in err
