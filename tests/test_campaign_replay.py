"""Replay and explain any campaign run: kept run directories, failures with time, phase and
numbers, `tetherland replay`, `tetherland campaign report`, and `mission --perturb`."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

from tetherland.campaign import CampaignSpec, Sweep, open_store, run_campaign
from tetherland.campaign.executors import InlineExecutor
from tetherland.campaign.jobs import draw_run, keep_run, keeps
from tetherland.campaign.perturb import apply_perturbation, sample_perturbation
from tetherland.campaign.replay import differences, replay
from tetherland.campaign.store import ResultsStore
from tetherland.cli import main
from tetherland.config import load_scenario
from tetherland.errors import ConfigError
from tetherland.randomness import RandomSource
from tetherland.runs import load_run
from tetherland.runs.explain import explain
from tetherland.sim.log import Column, SimLog
from tetherland.sim.mjcf import FRAME_PARTS
from tetherland.verdict import RunRecord
from tetherland.verdict.record import Expectations, PhaseSpan

STEEP = ["surface.slope_deg=65"]
"""Contact-free perching at 65 deg: it touches down sliding and its frame hits the
surface in most runs (the campaign's crash to replay)."""


@pytest.fixture(scope="module")
def crashed(tmp_path_factory) -> Path:
    """Two contact-free campaign runs at 65 deg in one worker (its planners reused from
    the first run to the second, as a campaign worker does), failed runs kept."""
    directory = tmp_path_factory.mktemp("crash") / "campaign"
    spec = CampaignSpec(
        scenario=load_scenario("slope50", STEEP).model_dump(mode="json"), runs=2,
        methods=("free-flight",), seed=24,
    )  # fmt: skip
    with open_store(spec, directory) as store:
        run_campaign(spec, store, InlineExecutor(), keep="failures")
    return directory


def _records(directory: Path) -> list[dict]:
    return ResultsStore(directory).load()


# --- the records: failures with time, phase, part and force -----------------------------------


@pytest.mark.slow
def test_a_crash_in_results_jsonl_carries_time_phase_part_and_force(crashed):
    records = _records(crashed)
    crashes = [r for r in records if r["verdict"]["outcome"] == "crashed"]
    assert crashes, [r["verdict"]["reason"] for r in records]
    limit = load_scenario("slope50").verdict.crash_force
    for r in crashes:
        first = r["verdict"]["failures"][0]
        assert first["outcome"] == "crashed"
        phases = [p["name"] for p in r["verdict"]["phases"]]
        assert first["phase"] in phases
        assert first["force_N"] > limit and first["limit"] == limit
        assert first["part"] in FRAME_PARTS  # the part that hit, from the plant's contacts
        # the kept log (plant truth) shows the frame force above the limit at that time
        log, _ = load_run(crashed / r["run_dir"])
        period = 1.0 / load_scenario("slope50").controller.rate_hz
        near = np.abs(log["t"] - first["t"]) <= period + 1e-9
        assert np.nan_to_num(log["frame_force"][near]).max() > limit
        # ... and never before it (the first touch)
        assert np.nan_to_num(log["frame_force"][log["t"] < first["t"] - period]).max() <= limit
        span = next(p for p in r["verdict"]["phases"] if p["name"] == first["phase"])
        assert span["start"] <= first["t"] <= span["end"]
        # every failed landing condition names its measured value above its limit
        for f in r["verdict"]["failures"][1:]:
            if f["outcome"] == "landing_conditions" and "value" in f:
                assert f["value"] > f["limit"]


@pytest.mark.slow
def test_failed_runs_keep_their_run_directories_with_the_perturbation(crashed, capsys):
    records = _records(crashed)
    assert all(not r["verdict"]["success"] for r in records)
    summary = json.loads((crashed / "summary.json").read_text())
    assert summary["kept_runs"] == sorted(r["run_id"] for r in records)
    for r in records:
        assert r["run_dir"] == f"runs/{r['run_id']}"
        _, record = load_run(crashed / r["run_dir"])
        drawn = record.provenance["perturbation"]
        assert drawn["seed"] == r["seed"]
        assert {k: drawn[k] for k in r["perturbation"]} == r["perturbation"]
        assert record.provenance["campaign_run"] == r["run_id"]
        # the kept run re-judges to its own summary.json (exit 1: the run failed)
        assert main(["judge", str(crashed / r["run_dir"])]) == 1
        assert "same as summary.json: yes" in capsys.readouterr().out
    assert not [p for p in (crashed / "runs").iterdir() if p.name.startswith(".")]


# --- replay ---------------------------------------------------------------------------------


@pytest.mark.slow
def test_replay_of_a_crashed_run_gives_the_identical_record(crashed, tmp_path, capsys):
    """The second run of the worker, flown again in a fresh process state: the same
    record bit for bit (wall times aside), verdict, failures and crash record included."""
    recorded = _records(crashed)[-1]
    out = tmp_path / "replay"
    code = main(["replay", str(crashed), recorded["run_id"], "--out", str(out), "--json"])
    doc = json.loads(capsys.readouterr().out)
    assert code == 0 and doc["identical"] is True and doc["differences"] == []
    assert doc["record"]["verdict"]["failures"] == recorded["verdict"]["failures"]
    assert doc["record"]["verdict"]["outcome"] == "crashed"
    assert doc["record"]["perturbation"] == recorded["perturbation"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["outcome"] == "crashed"
    assert summary["provenance"]["perturbation"]["seed"] == recorded["seed"]
    crash, first = summary["crash"], recorded["verdict"]["failures"][0]
    assert crash["part"] == first["part"] and crash["part"] in FRAME_PARTS
    assert crash["phase"] == first["phase"] and crash["t"] == first["t"]
    assert crash["force_N"] == pytest.approx(first["force_N"])


@pytest.mark.slow
def test_a_run_flown_again_replaces_its_kept_directory_as_a_whole(crashed, tmp_path):
    """A resumed campaign flies again a run whose directory was written but whose record
    was not (interrupted in between): the new directory replaces the old one whole."""
    run_id = _records(crashed)[0]["run_id"]
    copy = tmp_path / run_id
    shutil.copytree(crashed / "runs" / run_id, copy)
    (copy / "stale.txt").write_text("from an earlier attempt")
    again = replay(crashed, run_id)
    assert again.identical and again.result is not None
    keep_run(again.result, copy)
    assert not (copy / "stale.txt").exists()
    assert json.loads((copy / "summary.json").read_text())["outcome"] == "crashed"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_replay_of_an_analysis_run_and_a_changed_record(tmp_path, capsys):
    spec = CampaignSpec(scenario=load_scenario("slope50").model_dump(mode="json"), runs=2,
                        sweep=Sweep.parse("surface.slope_deg=50,80"), seed=3,
                        job="analysis")  # fmt: skip
    with open_store(spec, tmp_path) as store:
        run_campaign(spec, store, InlineExecutor())
    assert not (tmp_path / "runs").exists()  # nothing flown, nothing kept
    run_id = "tethered-80-00001"
    assert main(["replay", str(tmp_path), run_id, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["identical"] is True
    # a record that no longer matches (another tetherland, an edited file): exit 1
    lines = (tmp_path / "results.jsonl").read_text().splitlines()
    edited = []
    for line in lines:
        r = json.loads(line)
        if r["run_id"] == run_id:
            r["verdict"]["max_slope_rad"] += 1e-12
        edited.append(json.dumps(r))
    (tmp_path / "results.jsonl").write_text("\n".join(edited) + "\n")
    assert main(["replay", str(tmp_path), run_id]) == 1
    out = capsys.readouterr().out
    assert "differs from results.jsonl" in out and "verdict.max_slope_rad" in out


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["replay", "{dir}", "tethered-base-99999"], "RUN_ID 'tethered-base-99999' is no run"),
        (["replay", "{empty}", "x"], "not a campaign directory"),
        (["campaign", "report", "{empty}"], "not a campaign directory"),
        (["campaign", "slope50", "--keep", "some", "--job", "analysis"], "--keep must be one of"),
    ],
)
def test_bad_replay_and_report_input_is_one_line(tmp_path, capsys, argv, needle):
    spec = CampaignSpec(scenario=load_scenario("slope50").model_dump(mode="json"), runs=1,
                        seed=3, job="analysis")  # fmt: skip
    with open_store(spec, tmp_path / "c") as store:
        run_campaign(spec, store, InlineExecutor())
    (tmp_path / "empty").mkdir()
    args = [a.format(dir=tmp_path / "c", empty=tmp_path / "empty") for a in argv]
    code = main([*args, "--out", str(tmp_path / "o")] if argv[0] == "campaign" and
                "slope50" in argv else args)  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and needle in err
    assert not (tmp_path / "o").exists()


def test_differences_compare_every_recorded_field_exactly():
    recorded = {"verdict": {"success": False, "t": 1.0, "failures": [{"t": 2.0}]}, "seed": 1}
    same = json.loads(json.dumps(recorded))
    assert list(differences(recorded, same)) == []
    newer = {**same, "verdict": {**same["verdict"], "added_later": 1}}
    assert list(differences(recorded, newer)) == []  # a field an older campaign lacks
    changed = json.loads(json.dumps(recorded))
    changed["verdict"]["failures"][0]["t"] = 2.0 + 2**-40
    assert list(differences(recorded, changed)) == [
        f"verdict.failures[0].t: recorded 2.0, replayed {2.0 + 2**-40!r}"]  # fmt: skip
    assert list(differences({"a": 1}, {"a": True})) and list(differences({"a": 1}, {}))


# --- keeping, staging, specification ---------------------------------------------------------


def test_keep_policies():
    failed, ok = {"verdict": {"success": False}}, {"verdict": {"success": True}}
    assert keeps("failures", failed) and not keeps("failures", ok)
    assert keeps("all", ok) and keeps("all", failed)
    assert not keeps("none", failed)
    with pytest.raises(ConfigError, match="--keep"):
        keeps("most", failed)


def test_half_written_run_directories_are_removed_when_the_campaign_is_opened(tmp_path):
    spec = CampaignSpec(scenario=load_scenario("slope50").model_dump(mode="json"), runs=1,
                        seed=3, job="analysis")  # fmt: skip
    with open_store(spec, tmp_path) as store:
        run_campaign(spec, store, InlineExecutor())
    stale = tmp_path / "runs" / ".tethered-base-00000.staging-abc123"
    stale.mkdir(parents=True)
    (stale / "log.npz").write_bytes(b"half")
    whole = tmp_path / "runs" / "tethered-base-00000"
    whole.mkdir()
    with open_store(spec, tmp_path, resume=True):
        assert not stale.exists() and whole.exists()


@pytest.mark.parametrize(
    "extra",
    [{"sweep": Sweep.parse("surface.slope_deg=20:80:30")}, {"faults": ("rotor", "snap"),
                                                          "fault_window": (2.0, 40.0)}],
)  # fmt: skip
def test_a_manifest_gives_back_the_same_campaign(extra):
    spec = CampaignSpec(scenario=load_scenario("slope50").model_dump(mode="json"), runs=3,
                        seed=11, **extra)  # fmt: skip
    again = CampaignSpec.from_dict(json.loads(json.dumps(spec.to_dict())))
    assert again.fingerprint() == spec.fingerprint()
    assert again.expand() == spec.expand()


# --- the report ------------------------------------------------------------------------------


@pytest.mark.slow
def test_campaign_report_prints_success_with_intervals_and_failures_by_kind_and_phase(
    crashed, capsys
):
    for png in ("success_rate.png", "errors.png"):
        (crashed / png).unlink(missing_ok=True)  # the library draws none, the CLI does
    assert main(["campaign", "report", str(crashed), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    records = _records(crashed)
    (rate,) = doc["rates"]
    assert rate["n"] == 2 and rate["successes"] == 0 and rate["ci_low"] == 0.0
    z2 = 1.959963984540054**2  # Wilson's upper bound at 0 of n: z^2 / (n + z^2)
    assert rate["ci_high"] == pytest.approx(z2 / (2 + z2), rel=1e-12)
    by_group = {(g["kind"], g["phase"]): g["run_ids"] for g in doc["failures"]}
    expected: dict[tuple[str, str], list[str]] = {}
    for r in records:
        first = r["verdict"]["failures"][0]
        expected.setdefault((first["outcome"], first["phase"]), []).append(r["run_id"])
    assert by_group == expected
    assert (crashed / "success_rate.png").exists() and (crashed / "errors.png").exists()
    # while another process holds the campaign, the figures are left alone
    (crashed / "success_rate.png").unlink()
    holder = ResultsStore(crashed)
    holder.lock()
    try:
        assert main(["campaign", "report", str(crashed)]) == 0
    finally:
        holder.close()
    out = capsys.readouterr().out
    assert "figures not redrawn" in out and "Failures by kind and phase" in out
    assert not (crashed / "success_rate.png").exists()


# --- mission --perturb -----------------------------------------------------------------------


@pytest.mark.slow
def test_mission_perturb_flies_the_campaigns_draw_for_that_seed(crashed, tmp_path, capsys):
    """`mission --perturb --seed S` draws, records and flies exactly what the campaign's run
    with seed S did: the same perturbation and belief, the same verdict."""
    r = _records(crashed)[0]
    out = tmp_path / "m"
    argv = ["mission", "slope50", "--set", *STEEP, "--method", "free-flight", "--perturb",
            "--seed", str(r["seed"]), "--out", str(out), "--json"]  # fmt: skip
    assert main(argv) == 1  # it crashes, as in the campaign
    summary = json.loads(capsys.readouterr().out)
    _, record = load_run(out)
    truth = load_scenario("slope50", STEEP)
    p = sample_perturbation(truth, RandomSource(r["seed"]))
    assert p.to_dict() == r["perturbation"]
    assert {k: record.provenance["perturbation"][k] for k in r["perturbation"]} == p.to_dict()
    _, belief = apply_perturbation(truth, p)
    assert record.belief_scenario().model_dump() == belief.model_dump()
    assert draw_run(truth, r["seed"]).belief.model_dump() == belief.model_dump()
    for key in ("outcome", "reason", "sim_time_s", "crashed"):
        assert summary[key] == r["verdict"][key]
    assert summary["failures"] == r["verdict"]["failures"]


@pytest.mark.slow
def test_a_plain_mission_believes_the_scenario_exactly(crashed, tmp_path, capsys):
    """Without --perturb the seed varies only the sensor noise: the belief is the truth, no
    perturbation is recorded; the campaign's draw of the same seed is another belief."""
    seed = _records(crashed)[0]["seed"]
    argv = ["mission", "slope50", "--set", *STEEP, "--method", "free-flight", "--seed",
            str(seed), "--out", str(tmp_path / "m"), "--json"]  # fmt: skip
    main(argv)
    capsys.readouterr()
    _, record = load_run(tmp_path / "m")
    truth = load_scenario("slope50", STEEP)
    assert record.belief_scenario().model_dump() == truth.model_dump()
    assert "perturbation" not in record.provenance
    assert draw_run(truth, seed).belief.model_dump() != truth.model_dump()


# --- explaining a verdict (constructed logs) -------------------------------------------------

_COLUMNS = (Column("t", 1, "s", ""), Column("phase", 1, "-", "", True),
            Column("frame_force", 1, "N", ""), Column("tension", 1, "N", ""))  # fmt: skip


def _record(expects: Expectations | None = None) -> RunRecord:
    sc = load_scenario("slope50").model_dump(mode="json")
    return RunRecord(method="tethered", seed=0, truth=sc, belief=sc,
                     expects=expects or Expectations(), phase_codes={"approach": 0, "landing": 1},
                     tension_phases=("landing",),
                     phases=(PhaseSpan("approach", 0.0, 1.0, "done"),
                             PhaseSpan("landing", 1.0, 2.0, "done")))  # fmt: skip


def _summary(**kw) -> dict:
    base = {"success": False, "outcome": "crashed", "reason": "r", "status": "completed",
            "crashed": False, "landing": {"reached": False}, "takeoff": {"required": False},
            "return": {"required": False}, "sim_time_s": 2.0, "abort_reason": None,
            "safe_stop": {"reached": False},
            "phases": [{"name": "approach", "start": 0.0, "end": 1.0, "exit_reason": "done"},
                       {"name": "landing", "start": 1.0, "end": 2.0, "exit_reason": "done"}]}
    return base | kw  # fmt: skip


def _log(force: list[float], tension: list[float] | None = None) -> SimLog:
    n = len(force)
    t = np.linspace(0.0, 2.0, n)
    m = np.column_stack([t, (t >= 1.0).astype(float), force, tension or [1.0] * n])
    return SimLog(_COLUMNS, m)


def test_a_crash_without_the_judges_record_is_found_in_the_log():
    force = [0.0] * 10 + [3.0, 9.0, 0.0] + [0.0] * 8
    (f, *_rest) = explain(_summary(crashed=True), _log(force), _record())
    assert f.outcome == "crashed" and f.part is None
    assert f.t == pytest.approx(2.0 * 10 / 20) and f.phase == "landing" and f.force_N == 3.0


def test_the_judges_crash_record_is_used_as_it_is():
    crash = {"t": 0.5, "phase": "approach", "part": "rotor guard 2", "force_N": 4.5}
    (f, *_rest) = explain(_summary(crashed=True, crash=crash), _log([5.0] * 21), _record())
    assert (f.t, f.phase, f.part, f.force_N) == (0.5, "approach", "rotor guard 2", 4.5)
    assert "rotor guard 2" in f.message


def test_a_failed_condition_at_a_bounce_names_the_bounce():
    tol = load_scenario("slope50").verdict
    landing = {"reached": True, "t_L": 1.2, "position_error_m": 0.001,
               "touchdown_speed_mps": 0.01, "touchdown_angular_rate_rps": 0.0,
               "bounces": [{"t": 1.5, "touchdown_speed_mps": 2 * tol.touchdown_speed,
                            "touchdown_angular_rate_rps": 0.0}],
               "conditions": {"1": True, "2": True, "3": False, "4": True, "5": True},
               "required_conditions": ["1", "2", "3", "4", "5"],
               "all_conditions": False}  # fmt: skip
    (f,) = explain(_summary(outcome="landing_conditions", landing=landing), _log([0.0] * 21),
                   _record())  # fmt: skip
    assert (f.condition, f.measure, f.t, f.phase) == ("3", "touchdown_speed_mps", 1.5, "landing")
    assert f.value == 2 * tol.touchdown_speed and f.limit == tol.touchdown_speed


def test_a_slack_cable_is_placed_at_its_least_tension():
    tension = [2.0] * 21
    tension[15] = -0.0
    landing = {"reached": True, "t_L": 1.9, "conditions": {}, "required_conditions": [],
               "all_conditions": True, "min_tension_N": -0.0}  # fmt: skip
    rec = _record(Expectations(tension=True))
    (f,) = explain(_summary(outcome="slack_cable", landing=landing), _log([0.0] * 21, tension),
                   rec)  # fmt: skip
    assert f.outcome == "slack_cable" and f.t == pytest.approx(1.5) and f.phase == "landing"
    assert f.value == 0.0 and f.limit == 0.0 and not math.isnan(f.t)


def test_the_first_failure_is_the_one_that_decided_the_outcome():
    """A safe stop after three missed hooks never touched down: the judge's outcome is
    the safe stop (it comes first), placed where the supervisor left its phase."""
    phases = [{"name": "approach", "start": 0.0, "end": 1.0, "exit_reason": "abort: missed"},
              {"name": "safe_hover", "start": 1.0, "end": 2.0, "exit_reason": "run ended"}]
    summary = _summary(outcome="safe_stop", abort_reason="missed", phases=phases,
                       safe_stop={"reached": True})  # fmt: skip
    failures = explain(summary, _log([0.0] * 21), _record())
    assert [f.outcome for f in failures] == ["safe_stop", "no_touchdown"]
    assert (failures[0].t, failures[0].phase) == (1.0, "approach")
    assert failures[1].phase == "safe_hover" and failures[1].t == 2.0
