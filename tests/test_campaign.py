"""Campaigns: expansion, statistics, durable results, kill-and-resume, engine equivalence."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from tetherland.campaign import (
    CampaignSpec,
    Perturbation,
    ResultsStore,
    Sweep,
    apply_perturbation,
    make_executor,
    open_store,
    run_campaign,
    sample_perturbation,
    summarize,
    wilson_interval,
)
from tetherland.campaign.executors import DaskExecutor, InlineExecutor, LocalPoolExecutor
from tetherland.campaign.run import campaign_job
from tetherland.config import load_scenario
from tetherland.errors import ConfigError
from tetherland.geometry import LandingGeometry
from tetherland.randomness import RandomSource

EXE = str(Path(sys.executable).with_name("tetherland"))


def analysis_spec(runs: int = 4, sweep: str | None = "surface.slope_deg=20:80:30") -> CampaignSpec:
    return CampaignSpec(
        scenario=load_scenario("slope50").model_dump(mode="json"),
        runs=runs,
        sweep=Sweep.parse(sweep) if sweep else None,
        seed=7,
        job="analysis",
    )


def comparable(records: list[dict]) -> list[dict]:
    return sorted(
        ({k: v for k, v in r.items() if k not in ("wall_time_s", "cpu_time_s")} for r in records),
        key=lambda r: r["run_id"],
    )


# --- specification and statistics ------------------------------------------------------------


def test_sweep_parsing():
    assert Sweep.parse("surface.slope_deg=30:80:10").values == (30, 40, 50, 60, 70, 80)
    assert Sweep.parse("surface.slope_deg=30,45").values == (30.0, 45.0)
    for bad in ("slope=1:2:1", "surface.slope_deg=80:30:10", "surface.slope_deg=1:2:0", "x.y=a"):
        with pytest.raises(ConfigError, match="--sweep"):
            Sweep.parse(bad)


def test_expansion_is_deterministic_and_paired():
    spec = analysis_spec(runs=3)
    runs = spec.expand()
    assert len(runs) == 3 * 2 * 3 and len({r.run_id for r in runs}) == len(runs)
    assert [r.seed for r in runs] == [r.seed for r in analysis_spec(runs=3).expand()]
    by_key = {}
    for r in runs:
        by_key.setdefault((r.sweep_value, r.index), set()).add(r.seed)
    assert all(len(seeds) == 1 for seeds in by_key.values())  # both methods share a seed
    assert len({r.seed for r in runs}) == 9  # distinct across points and indices


def test_unknown_method_and_bad_counts_are_rejected():
    with pytest.raises(ConfigError, match="unknown method"):
        CampaignSpec(scenario={}, runs=1, methods=("hover",))
    with pytest.raises(ConfigError, match="--runs must be >= 1"):
        CampaignSpec(scenario={}, runs=0)
    with pytest.raises(ConfigError, match="--workers must be >= 1"):
        make_executor("local", 0)
    with pytest.raises(ConfigError, match="unknown engine"):
        make_executor("mpi", 2)


def test_firmware_campaigns_are_checked_and_reach_every_job(tmp_path: Path):
    with pytest.raises(ConfigError, match="--firmware must be one of betaflight"):
        CampaignSpec(scenario={}, runs=1, firmware="px4")
    with pytest.raises(ConfigError, match="--firmware flies missions"):
        CampaignSpec(scenario={}, runs=1, firmware="betaflight", job="analysis")
    own = CampaignSpec(scenario={}, runs=2, methods=("tethered",))
    fw = CampaignSpec(scenario={}, runs=2, methods=("tethered",), firmware="betaflight")
    assert "firmware" not in own.to_dict()  # campaigns without firmware keep their fingerprint
    assert fw.fingerprint() != own.fingerprint()  # --resume never mixes the two
    assert [r.seed for r in fw.expand()] == [r.seed for r in own.expand()]  # the same runs
    from tetherland.campaign.run import pending_jobs

    jobs, total = pending_jobs(fw, open_store(fw, tmp_path / "fw"))
    assert total == 2 and {job.firmware for job in jobs} == {"betaflight"}


@pytest.mark.parametrize(
    ("k", "n", "lo", "hi"),
    [
        (0, 10, 0.0, 0.2775),
        (5, 10, 0.2366, 0.7634),
        (10, 10, 0.7225, 1.0),
        (81, 100, 0.7222, 0.8749),
    ],
)
def test_wilson_interval_known_values(k, n, lo, hi):
    a, b = wilson_interval(k, n)
    assert a == pytest.approx(lo, abs=1e-4) and b == pytest.approx(hi, abs=1e-4)


def test_summary_counts_each_run_once_and_errors_as_failures():
    records = [
        {
            "run_id": "a",
            "method": "tethered",
            "sweep_value": 1.0,
            "status": "ok",
            "verdict": {"success": True},
        },
        {
            "run_id": "a",
            "method": "tethered",
            "sweep_value": 1.0,
            "status": "ok",
            "verdict": {"success": True},
        },
        {
            "run_id": "b",
            "method": "tethered",
            "sweep_value": 1.0,
            "status": "error",
            "verdict": {"success": False},
        },
        {
            "run_id": "c",
            "method": "tethered",
            "sweep_value": 1.0,
            "status": "ok",
            "verdict": {"success": False},
        },
    ]
    (s,) = summarize(records)
    assert (s.n, s.successes, s.errors) == (3, 1, 1) and s.rate == pytest.approx(1 / 3)


# --- perturbations ---------------------------------------------------------------------------


def test_perturbations_are_seeded_and_within_ranges(slope50):
    p1 = sample_perturbation(slope50, RandomSource(3))
    assert p1 == sample_perturbation(slope50, RandomSource(3))
    assert p1 != sample_perturbation(slope50, RandomSource(4))
    c = slope50.perturbation
    assert abs(p1.mass_factor - 1) <= c.mass_rel and abs(p1.slope_error_deg) <= c.slope_error_deg
    assert c.noise_scale_min <= p1.noise_scale <= c.noise_scale_max


def test_belief_differs_from_truth_and_stays_consistent(slope50):
    p = sample_perturbation(slope50, RandomSource(11))
    plant, belief = apply_perturbation(slope50, p)
    assert plant.vehicle == slope50.vehicle  # the plant keeps the true model
    assert belief.vehicle.mass == pytest.approx(slope50.vehicle.mass * p.mass_factor)
    assert plant.sensors.noise_scale == pytest.approx(p.noise_scale)
    g_true, g_belief = LandingGeometry.from_scenario(plant), LandingGeometry.from_scenario(belief)
    assert math.degrees(g_belief.surface.slope - g_true.surface.slope) == pytest.approx(
        p.slope_error_deg
    )
    assert g_belief.surface.height(g_belief.p_A) == pytest.approx(slope50.anchor.h_A, abs=1e-9)
    assert 0 < np.linalg.norm(g_belief.p_A - g_true.p_A) < 0.1


@pytest.mark.parametrize("name", ["slope50", "pipe60"])
def test_belief_errors_are_drawn_in_every_direction_within_their_bounds(name):
    """Over 400 seeds: the anchor error along x_S, y_S and z_S (h_A), the surface offset
    along its normal and a pipe's radius error stay within their half-widths (defaults
    1 cm, 5 mm, 2 mm), take both signs and fill the range (uniform draws: the largest of
    400 is within 1 % of the bound with probability 1 - 0.99^400 > 0.98; the seeds are
    fixed, so the check is exact)."""
    truth = load_scenario(name)
    c = truth.perturbation
    assert (c.anchor_error, c.surface_offset_error, c.pipe_radius_error) == (0.01, 0.005, 0.002)
    draws = [sample_perturbation(truth, RandomSource(seed)) for seed in range(400)]
    columns = {
        "anchor_x": ([p.anchor_error_S[0] for p in draws], c.anchor_error),
        "anchor_y": ([p.anchor_error_S[1] for p in draws], c.anchor_error),
        "anchor_h": ([p.anchor_error_S[2] for p in draws], c.anchor_error),
        "surface": ([p.surface_offset for p in draws], c.surface_offset_error),
        "pipe": ([p.pipe_radius_error for p in draws], c.pipe_radius_error),
    }
    for what, (values, bound) in columns.items():
        v = np.asarray(values)
        if what == "pipe" and name != "pipe60":
            assert not np.any(v)  # a plane has no radius to get wrong
            continue
        assert np.all(np.abs(v) <= bound), what
        assert v.min() < -0.99 * bound and v.max() > 0.99 * bound, what
    # every draw is recorded with the run (results.jsonl keeps Perturbation.to_dict())
    record = draws[0].to_dict()
    assert {"anchor_error_x_S", "anchor_error_y_S", "anchor_error_z_S", "surface_offset",
            "pipe_radius_error"} <= set(record)  # fmt: skip
    assert record["anchor_error_z_S"] == draws[0].anchor_error_S[2]


def test_a_campaign_run_meets_gusts_until_its_time_limit():
    """A run's gusts start anywhere up to ``mission.time_limit`` (the bar's mission flies
    150 s, its return after 120 s), and the gusts of its first 120 s are those a 120 s
    horizon draws from the seed's wind stream: a longer horizon only adds later ones."""
    from tetherland.campaign.jobs import draw_run
    from tetherland.campaign.perturb import sample_gusts

    truth = load_scenario("slope50")
    limit = truth.mission.time_limit
    late = 0
    for seed in range(10):
        gusts = draw_run(truth, seed).perturbation.gusts
        first = sample_gusts(truth.perturbation, RandomSource(seed).stream("wind"), 120.0)
        assert first and gusts[: len(first)] == first
        assert all(g.t_start < limit for g in gusts)
        assert [g.t_start for g in gusts] == sorted(g.t_start for g in gusts)
        late += sum(g.t_start > 150.0 for g in gusts)
    # gusts come at wind_gust_rate: about rate x (limit - 150 s) per run after 150 s
    assert late > 0.5 * 10 * truth.perturbation.wind_gust_rate * (limit - 150.0)


@pytest.mark.parametrize("e_h", [0.004, -0.004])
def test_belief_differs_from_truth_as_drawn_and_the_plant_keeps_the_truth(e_h):
    """pipe60 (h_A = 0) with only position errors: the believed top line is 3 mm out along
    z_S, the radius 2 mm short, the anchor 6 mm down-slope, 5 mm sideways and e_h above the
    believed surface (a negative height is believed zero: never behind the surface)."""
    truth = load_scenario("pipe60")
    assert truth.anchor.h_A == 0.0
    p = Perturbation(anchor_error_S=(0.006, -0.005, e_h), surface_offset=0.003,
                     pipe_radius_error=-0.002)  # fmt: skip
    plant, belief = apply_perturbation(truth, p)
    g_true, g_belief = LandingGeometry.from_scenario(truth), LandingGeometry.from_scenario(belief)
    s_true, s_belief = g_true.surface, g_belief.surface
    np.testing.assert_allclose(s_belief.R_WS, s_true.R_WS, atol=1e-12)  # no tilt drawn
    assert s_belief.height(s_true.origin) == pytest.approx(-0.003, abs=1e-12)
    assert belief.surface.pipe_radius == pytest.approx(truth.surface.pipe_radius - 0.002)
    h_A = max(e_h, 0.0)
    assert belief.anchor.h_A == pytest.approx(h_A)
    assert s_belief.height(g_belief.p_A) == pytest.approx(h_A, abs=1e-12)
    d = g_belief.p_A - g_true.p_A
    np.testing.assert_allclose(
        [d @ s_true.x_S, d @ s_true.y_S, d @ s_true.z_S], [0.006, -0.005, 0.003 + h_A],
        atol=1e-12,
    )  # fmt: skip
    # the plant simulates the truth: surface, radius and anchor as given
    assert plant.surface == truth.surface and plant.anchor == truth.anchor
    from tetherland.sim import Plant

    model = Plant(plant).model
    assert model.geom("surface").size[0] == pytest.approx(truth.surface.pipe_radius)
    np.testing.assert_allclose(model.site("anchor").pos, g_true.p_A, atol=1e-12)


@pytest.mark.parametrize(
    ("name", "error_deg"), [("wall90", 0.8), ("overhang93", 0.9), ("wall90", -0.7)]
)
def test_believed_slope_is_not_clamped_at_vertical(name, error_deg):
    """Walls and overhangs: the believed slope is the true one plus the error on [0, 180]
    (a clamp at 90 deg would hide the error of a wall that leans out), and the believed
    anchor lies on the believed surface at the true h_A."""
    truth = load_scenario(name)
    plant, belief = apply_perturbation(truth, Perturbation(slope_error_deg=error_deg))
    g_true, g_belief = LandingGeometry.from_scenario(plant), LandingGeometry.from_scenario(belief)
    assert math.degrees(g_true.surface.slope) == pytest.approx(truth.surface.slope_deg)
    assert math.degrees(g_belief.surface.slope) == pytest.approx(
        truth.surface.slope_deg + error_deg, abs=1e-9
    )
    assert g_belief.surface.height(g_belief.p_A) == pytest.approx(truth.anchor.h_A, abs=1e-9)
    # the anchor stays put up to the tilt of the believed surface about its origin
    lever = float(np.linalg.norm(g_true.p_A - g_true.surface.origin))
    shift = float(np.linalg.norm(g_belief.p_A - g_true.p_A))
    assert shift == pytest.approx(lever * abs(math.sin(math.radians(error_deg))), rel=1e-6)


# --- durability, resume, engines -------------------------------------------------------------


def test_torn_last_line_is_discarded(tmp_path: Path):
    spec = analysis_spec(runs=1, sweep=None)
    with open_store(spec, tmp_path) as store:
        store.append({"run_id": "x", "method": "tethered"})
    with open(store.results_path, "a") as fh:
        fh.write('{"run_id": "torn", "meth')
    store = open_store(spec, tmp_path, resume=True)
    assert [r["run_id"] for r in store.load()] == ["x"]
    store.append({"run_id": "y", "method": "tethered"})
    assert [r["run_id"] for r in store.load()] == ["x", "y"]


def test_summary_matches_results_table(tmp_path: Path):
    spec = analysis_spec(runs=3)
    result = run_campaign(spec, open_store(spec, tmp_path), InlineExecutor())
    records = ResultsStore(tmp_path).load()
    assert result.done == result.total == len(records) == 18
    doc = json.loads((tmp_path / "summary.json").read_text())
    for rate in doc["rates"]:
        rows = [
            r
            for r in records
            if r["method"] == rate["method"] and r["sweep_value"] == rate["sweep_value"]
        ]
        assert rate["n"] == len(rows)
        assert rate["successes"] == sum(r["verdict"]["success"] for r in rows)
    # the physics of the fast job: at 50 deg only the tethered method is feasible, at 20 both,
    # at 80 neither (the cable-offset torque limits this vehicle to about 73 deg)
    rates = {(r["method"], r["sweep_value"]): r["rate"] for r in doc["rates"]}
    assert rates[("tethered", 50.0)] == 1.0 and rates[("free-flight", 50.0)] == 0.0
    assert rates[("tethered", 20.0)] == 1.0 and rates[("free-flight", 20.0)] == 1.0
    assert rates[("tethered", 80.0)] == 0.0
    assert (tmp_path / "results.csv").read_text().count("\n") == 19


def _count_lines(path: Path) -> int:
    try:
        return path.read_bytes().count(b"\n")
    except FileNotFoundError:
        return 0


def test_killed_campaign_resumes_with_every_run_exactly_once(tmp_path: Path):
    out = tmp_path / "camp"
    cmd = [EXE, "campaign", "slope50", "--job", "analysis", "--runs", "30", "--workers", "2",
           "--sweep", "surface.slope_deg=30,60", "--out", str(out)]  # fmt: skip
    proc = subprocess.Popen(
        cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )
    deadline = time.time() + 120
    while (
        _count_lines(out / "results.jsonl") < 15 and time.time() < deadline and proc.poll() is None
    ):
        time.sleep(0.01)
    os.killpg(proc.pid, signal.SIGKILL)  # a crash, not a polite stop
    proc.wait()
    partial = ResultsStore(out).load()
    assert 15 <= len(partial) < 120
    done = subprocess.run([*cmd, "--resume"], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    ids = [r["run_id"] for r in ResultsStore(out).load()]
    assert len(ids) == len(set(ids)) == 120
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] and sum(r["n"] for r in summary["rates"]) == 120


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_interrupt_stops_cleanly_with_exit_130(tmp_path: Path, sig):
    out = tmp_path / "camp"
    # enough analysis runs (about a minute) that a loaded machine cannot finish them all
    # between the fifth result and the signal
    cmd = [EXE, "campaign", "slope50", "--job", "analysis", "--runs", "4000", "--workers", "2",
           "--out", str(out)]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while _count_lines(out / "results.jsonl") < 5 and time.time() < deadline:
        time.sleep(0.01)
    children = Path(f"/proc/{proc.pid}/task/{proc.pid}/children")
    workers = [int(p) for p in children.read_text().split()] if children.exists() else []
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    assert "--resume" in stdout and "Traceback" not in stderr
    assert json.loads((out / "summary.json").read_text())["complete"] is False
    alive = workers
    for _ in range(100):  # reaped by init once they exit
        alive = [pid for pid in alive if Path(f"/proc/{pid}").exists()]
        if not alive:
            break
        time.sleep(0.05)
    alive = [(pid, Path(f"/proc/{pid}/cmdline").read_bytes()[:200]) for pid in alive]
    assert not alive, f"orphaned worker processes {alive}"


def test_local_pool_and_dask_give_the_same_results(tmp_path: Path):
    spec = analysis_spec(runs=2)
    inline = run_campaign(spec, open_store(spec, tmp_path / "a"), InlineExecutor())
    pool = run_campaign(spec, open_store(spec, tmp_path / "b"), LocalPoolExecutor(2))
    dask = run_campaign(spec, open_store(spec, tmp_path / "c"), DaskExecutor(2))
    a, b, c = (comparable(ResultsStore(tmp_path / d).load()) for d in "abc")
    assert a == b == c and len(a) == inline.total == pool.done == dask.done


@pytest.mark.slow
def test_ray_gives_the_same_results(tmp_path: Path):
    from tetherland.campaign.executors import RayExecutor

    spec = analysis_spec(runs=1)
    run_campaign(spec, open_store(spec, tmp_path / "a"), InlineExecutor())
    run_campaign(spec, open_store(spec, tmp_path / "r"), RayExecutor(2))
    assert comparable(ResultsStore(tmp_path / "a").load()) == comparable(
        ResultsStore(tmp_path / "r").load()
    )


@pytest.mark.slow
def test_contact_free_mission_job_flies_with_the_campaigns_tethered_controller_name():
    """The campaign's --controller names the tethered law; a contact-free run of the same
    campaign flies its own tracker (it used to be recorded as an error whenever its
    perching plan existed)."""
    from tetherland.campaign.jobs import Job, execute
    from tetherland.campaign.spec import RunSpec

    spec = RunSpec("free-flight-base-00000", "free-flight", 0, 5, None, None)
    scenario = load_scenario("flat").model_dump(mode="json")
    record = execute(Job(scenario, spec, kind="mission", controller="hierarchical"))
    assert record["status"] == "ok", record["error"]
    assert record["verdict"]["outcome"] != "no_run"  # planned and flown
    assert record["verdict"]["sim_time_s"] > load_scenario("flat").perching.hover_time


def test_a_record_keeps_the_cpu_time_of_its_run_alone(monkeypatch):
    """``cpu_time_s`` is the process CPU spent inside the run: a run whose analysis burns
    0.3 s of CPU records at least that; one that sleeps 0.3 s records (almost) none of it,
    while its wall time holds the sleep."""
    from tetherland.campaign import jobs

    spec = analysis_spec(runs=1, sweep=None)
    job = campaign_job(spec, spec.expand()[0])

    def busy(*args):
        end = time.process_time() + 0.3
        while time.process_time() < end:
            pass
        return {"success": True}

    def idle(*args):
        time.sleep(0.3)
        return {"success": True}

    monkeypatch.setattr(jobs, "_analysis_verdict", busy)
    record, _ = jobs.run_job(job)
    assert record["cpu_time_s"] >= 0.3
    monkeypatch.setattr(jobs, "_analysis_verdict", idle)
    record, _ = jobs.run_job(job)
    assert record["wall_time_s"] >= 0.3 > record["cpu_time_s"] + 0.2


@pytest.mark.parametrize("e_h", [0.008, -0.009])
def test_a_bar_anchor_height_error_moves_the_believed_bar_and_not_the_plants(e_h):
    """mechanism.kind = "bar": the anchor is the bar's axis, so a height error e_h puts the
    believed bar at standoff + e_h (0.15 m + e_h, well above bar_radius + 2 hook_radius);
    the plant keeps the true bar at 0.15 m."""
    from tetherland.config import scenario_from_dict

    data = load_scenario("slope50").model_dump(mode="python")
    data["mechanism"]["kind"], data["anchor"]["h_A"] = "bar", 0.0  # "on the surface"
    truth = scenario_from_dict(data, "slope50")
    standoff = truth.mechanism.standoff
    assert truth.anchor.h_A == standoff
    plant, belief = apply_perturbation(truth, Perturbation(anchor_error_S=(0.0, 0.0, e_h)))
    assert belief.mechanism.standoff == pytest.approx(standoff + e_h, abs=1e-15)
    assert belief.anchor.h_A == pytest.approx(standoff + e_h, abs=1e-15)
    g_belief = LandingGeometry.from_scenario(belief)
    assert g_belief.surface.height(g_belief.p_A) == pytest.approx(standoff + e_h, abs=1e-12)
    assert plant.mechanism == truth.mechanism and plant.anchor == truth.anchor


def test_hooking_counts_count_every_attempt_and_the_runs_lost_or_held():
    """Three tethered runs at one point (a bounce then a catch that came off under load;
    a catch never released; two misses) and a contact-free run without hooking."""
    from tetherland.campaign.report import hooking_counts

    def rec(method, value, hooking):
        return {"run_id": "x", "method": method, "sweep_value": value, "status": "ok",
                "verdict": {"success": False, "hooking": hooking}}  # fmt: skip

    records = [
        rec("tethered", 20.0, {"outcome": "caught", "release": "not_tried", "t_lost": 81.2,
                               "attempts": ["bounced", "caught"]}),
        rec("tethered", 20.0, {"outcome": "caught", "release": "not_released", "t_lost": None,
                               "attempts": ["caught"]}),
        rec("tethered", 20.0, {"outcome": "missed", "release": "not_tried", "t_lost": None,
                               "attempts": ["missed", "missed"]}),
        rec("free-flight", 20.0, None),
    ]  # fmt: skip
    (h,) = hooking_counts(records)
    assert (h.method, h.sweep_value, h.runs) == ("tethered", 20.0, 3)
    assert h.attempts == {"bounced": 1, "caught": 2, "missed": 2}
    assert (h.lost, h.not_released) == (1, 1)


@pytest.mark.parametrize("e_h", [0.008, -0.009])
def test_a_magnet_anchor_height_error_moves_the_believed_plate_and_not_the_plants(e_h):
    """mechanism.kind = "magnet": the anchor is the cable's eye on the held magnet,
    plate_thickness + magnet_thickness above the surface; a height error e_h is the
    plate's (the robot knows its magnet): the believed plate is max(0.005 + e_h, 1 mm)
    thick and the believed anchor that plus the magnet's 1.5 cm; the plant keeps the
    true plate."""
    truth = load_scenario("wall90", ["mechanism.kind=magnet"])
    m = truth.mechanism
    assert truth.anchor.h_A == pytest.approx(m.plate_thickness + m.magnet_thickness, abs=1e-15)
    plant, belief = apply_perturbation(truth, Perturbation(anchor_error_S=(0.0, 0.0, e_h)))
    plate = max(m.plate_thickness + e_h, 1e-3)
    assert belief.mechanism.plate_thickness == pytest.approx(plate, abs=1e-15)
    assert belief.mechanism.magnet_thickness == m.magnet_thickness
    assert belief.anchor.h_A == pytest.approx(plate + m.magnet_thickness, abs=1e-15)
    g_belief = LandingGeometry.from_scenario(belief)
    assert g_belief.surface.height(g_belief.p_A) == pytest.approx(
        plate + m.magnet_thickness, abs=1e-12
    )
    assert plant.mechanism == truth.mechanism and plant.anchor == truth.anchor


def test_a_magnet_believed_plate_at_its_floor_is_exactly_the_floor():
    """A 3 mm plate under a 1 cm magnet believed 1 cm lower: the believed plate is clamped
    to MAGNET_PLATE_MIN (1 mm) exactly, and the believed anchor is that plus the magnet, so
    the belief is a valid scenario (h_A - t rounded to 0.999... mm was refused)."""
    truth = load_scenario("overhang93", ["mechanism.kind=magnet", "mechanism.boom_length=0.3",
                                         "mechanism.boom_angle_deg=20", "tether.length=0.36",
                                         "mechanism.plate_thickness=0.003",
                                         "mechanism.magnet_thickness=0.01"])  # fmt: skip
    m = truth.mechanism
    _, belief = apply_perturbation(truth, Perturbation(anchor_error_S=(0.0, 0.0, -0.01)))
    assert belief.mechanism.plate_thickness == 1e-3
    assert belief.anchor.h_A == 1e-3 + m.magnet_thickness
