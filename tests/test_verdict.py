"""The one judge: it re-judges saved runs exactly, serves every method, and its rules."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tetherland.cli import main
from tetherland.config import load_scenario, with_overrides
from tetherland.methods import METHODS, Planners
from tetherland.runs import closed_loop, jsonable_summary, rejudge, run_mission, save_run
from tetherland.verdict import RunRecord, RunRecordError, judge

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def planners() -> Planners:
    return Planners()


@pytest.fixture(scope="module")
def short_tethered(planners):
    """A tethered run aborted by the operator while stretching the cable: short, judged."""
    sc = with_overrides(load_scenario("slope50"), ["mission.abort_time=24"])
    return run_mission(sc, seed=0, planners=planners)


@pytest.fixture(scope="module")
def perched(planners):
    sc = load_scenario("slope50", ["surface.slope_deg=20"])
    return run_mission(sc, method="free-flight", seed=0, planners=planners)


@pytest.mark.parametrize("which", ["short_tethered", "perched"])
def test_judge_reproduces_summary_json_from_the_files_alone(which, request, tmp_path):
    result = request.getfixturevalue(which)
    files = save_run(result, tmp_path)
    stored = json.loads(files["summary"].read_text())
    assert stored.pop("files")
    again = jsonable_summary(rejudge(tmp_path))
    assert again == stored
    # the command line says so too
    assert main(["judge", str(tmp_path), "--json"]) == (0 if result.success else 1)


def test_both_methods_are_judged_by_the_same_function(planners, monkeypatch):
    calls = []

    def spy(log, record):
        calls.append(record.method)
        return judge(log, record)

    monkeypatch.setattr(closed_loop, "judge", spy)
    sc = with_overrides(load_scenario("slope50"), ["mission.abort_time=5"])
    run_mission(sc, seed=0, planners=planners)
    run_mission(load_scenario("flat"), method="free-flight", seed=0, planners=planners)
    assert calls == ["tethered", "free-flight"] == list(METHODS)


def test_an_aborted_run_is_judged_aborted_not_crashed(short_tethered):
    s = short_tethered.summary
    assert not s["success"] and s["outcome"] == "aborted" and not s["crashed"]
    assert s["abort_reason"] == "operator abort at t = 24 s"


def test_the_judge_measures_touchdown_at_the_first_contact_force(perched):
    """t_L is the first tick at which the landing surface presses a lander above
    verdict.touchdown_force (peak over the tick's physics steps); the speed of condition (3)
    is the true speed of the tick before."""
    log, s = perched.log, perched.summary
    force = log["lander_surface_forces"].max(axis=1)
    limit = perched.plant_scenario.verdict.touchdown_force
    k = int(np.flatnonzero(force > limit)[0])
    assert s["landing"]["t_L"] == pytest.approx(log["t"][k])
    assert s["landing"]["touchdown_speed_mps"] == pytest.approx(
        float(np.linalg.norm(log["v_W"][k - 1]))
    )


def test_a_tighter_tolerance_in_the_truth_changes_the_verdict(perched):
    """The judge reads the tolerances from the record's truth scenario: re-judging with a
    position tolerance below the measured error fails condition (1)."""
    err = perched.summary["landing"]["position_error_m"]
    truth = dict(perched.record.truth)
    truth["verdict"] = {**truth["verdict"], "position_error": 0.5 * err}
    from dataclasses import replace

    strict = judge(perched.log, replace(perched.record, truth=truth))
    assert strict.summary["landing"]["conditions"]["1"] is False
    assert not strict.success and strict.outcome.value == "landing_conditions"


def test_runs_without_a_record_get_one_line(tmp_path, capsys):
    (tmp_path / "log.npz").write_bytes(b"")
    assert main(["judge", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "no run.json" in err
    with pytest.raises(RunRecordError, match="not a tetherland run record"):
        RunRecord.from_dict({"method": "tethered"})
