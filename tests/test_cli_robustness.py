"""Bad, odd and hostile input ends in one line and exit 2, nothing lands outside the output
root and no run is silently overwritten or mixed (issue 28); one vocabulary for results
and every validation error of a file at once (issue 24, items 7 and 8)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tetherland.cli import MESSAGE_CHARS, main
from tetherland.cli.common import conditions_text
from tetherland.config import load_scenario
from tetherland.errors import ConfigError
from tetherland.io import OutputDir
from tetherland.verdict import Outcome

EXE = str(Path(sys.executable).with_name("tetherland"))


def one_error(capsys, code: int) -> str:
    """The stderr of a command that must end with exit 2 and one ``error:`` line."""
    out, err = capsys.readouterr()
    assert code == 2, (code, err[-600:])
    assert "Traceback" not in err + out
    assert err.count("\n") == 1 and err.startswith("error: "), err[-600:]
    assert len(err.strip()) <= len("error: ") + MESSAGE_CHARS
    return err.strip()


# --- 1. a scenario name is a label: outputs stay under the output root ---------------------


@pytest.mark.parametrize("name", ["VICTIM", "../x", "a/b", "..", ".", "a\\b", "a\x00b", "a\nb"])
@pytest.mark.parametrize("command", ["mission", "plan", "campaign"])
def test_a_scenario_name_cannot_lead_outside_the_output_root(
    tmp_path, monkeypatch, capsys, name, command
):
    monkeypatch.chdir(tmp_path)
    victim = tmp_path / "some" / "dir"
    victim.mkdir(parents=True)
    name = str(victim) if name == "VICTIM" else name  # `name = "/some/dir"`, a real folder
    scenario = tmp_path / "s.toml"
    scenario.write_text(f"name = {json.dumps(name)}\n")  # JSON strings are TOML strings
    code = main([command, str(scenario), *(["--job", "analysis"] if command == "campaign" else [])])
    assert "name" in one_error(capsys, code)
    # nothing written anywhere: not in the victim, not next to the scenario, not in out/
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.toml", "some"]
    assert not any(victim.iterdir())


def test_a_scenario_name_with_nul_in_an_override_is_one_line(capsys):
    code = main(["show", "flat", "--set", 'name="a\\u0000"'])
    assert "control characters" in one_error(capsys, code)


# --- 2. an existing run is never silently overwritten or mixed -----------------------------


@pytest.mark.slow
def test_mission_refuses_an_existing_run_and_overwrite_replaces_it_whole(tmp_path, capsys):
    out = tmp_path / "R"
    first = ["mission", "slope50", "--set", "mission.abort_time=2", "--out", str(out)]
    assert main(first) == 1  # an operator abort is not a success
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    assert {"landing_trajectory.csv", "figure_6_5.png", "log.npz"} <= set(before)
    capsys.readouterr()
    # the same --out again: refused on one line before anything flies, the run untouched
    second = ["mission", "slope50", "--method", "free-flight", "--seed", "3", "--out", str(out)]
    err = one_error(capsys, main(second))
    assert "--overwrite" in err and str(out) in err
    assert {p.name: p.stat().st_mtime_ns for p in out.iterdir()} == before
    # --overwrite: the new run's files and nothing else (no plan, figure or CSV of the first)
    assert main([*second, "--overwrite", "--json"]) == 1  # it slides on 50 deg
    doc = json.loads(capsys.readouterr().out)
    listed = {Path(p).name for p in doc["files"].values()}
    assert {p.name for p in out.iterdir()} == listed == {
        "summary.json", "run.json", "log.npz", "perching_trajectory.csv"
    }  # fmt: skip
    assert json.loads((out / "summary.json").read_text())["method"] == "free-flight"
    assert json.loads((out / "run.json").read_text())["seed"] == 3
    assert all(Path(p).parent == out for p in doc["files"].values())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["R"]  # no staging left behind


def test_output_dir_replaces_whole_or_not_at_all(tmp_path):
    target = tmp_path / "run"
    target.mkdir()
    (target / "summary.json").write_text("{}")
    (target / "stale.csv").write_text("old")
    with pytest.raises(ConfigError, match="--overwrite"):
        OutputDir(target)
    # a failure while writing leaves the old output as it was, and no staging directory
    out = OutputDir(target, overwrite=True)
    with pytest.raises(RuntimeError), out.staging() as stage:
        (stage / "summary.json").write_text('{"new": 1}')
        raise RuntimeError("disk full")
    assert sorted(p.name for p in target.iterdir()) == ["stale.csv", "summary.json"]
    assert (target / "summary.json").read_text() == "{}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
    # success: exactly the new files
    with out.staging() as stage:
        (stage / "summary.json").write_text('{"new": 1}')
    assert sorted(p.name for p in target.iterdir()) == ["summary.json"]
    assert (target / "summary.json").read_text() == '{"new": 1}'
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
    # never replaces a directory that is no tetherland output, even with --overwrite
    home = tmp_path / "home"
    home.mkdir()
    (home / "thesis.tex").write_text("precious")
    with pytest.raises(ConfigError, match="no tetherland output"):
        OutputDir(home, overwrite=True)
    with pytest.raises(ConfigError, match="is a file"):
        OutputDir(home / "thesis.tex")


def test_output_dir_through_a_symbolic_link_replaces_the_folder_and_keeps_the_link(tmp_path):
    real = tmp_path / "disk" / "run"
    real.mkdir(parents=True)
    (real / "run.json").write_text("old")
    link = tmp_path / "run"
    link.symlink_to(real, target_is_directory=True)
    with OutputDir(link, overwrite=True).staging() as stage:
        (stage / "run.json").write_text("new")
    assert link.is_symlink() and (link / "run.json").read_text() == "new"
    assert sorted(p.name for p in (tmp_path / "disk").iterdir()) == ["run"]


# --- 5. judge: a changed run or bad values in run.json ---------------------------------------


@pytest.fixture(scope="module")
def saved_run(tmp_path_factory) -> Path:
    """A short contact-free run on flat ground, saved by the command line."""
    out = tmp_path_factory.mktemp("runs") / "ff"
    assert main(["mission", "flat", "--method", "free-flight", "--out", str(out)]) == 0
    return out


def _copy(run: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(run, tmp_path / "run"))


def _edit_json(path: Path, edit) -> None:
    doc = json.loads(path.read_text())
    edit(doc)
    path.write_text(json.dumps(doc))  # NaN and Infinity written as JSON allows them


@pytest.mark.slow
def test_judge_exits_1_when_summary_json_differs(saved_run, tmp_path, capsys):
    assert main(["judge", str(saved_run)]) == 0
    run = _copy(saved_run, tmp_path)
    _edit_json(
        run / "run.json", lambda d: d["times"].update(t_maneuver=d["times"]["t_maneuver"] + 1)
    )
    capsys.readouterr()
    assert main(["judge", str(run)]) == 1
    out, err = capsys.readouterr()
    assert "same as summary.json: NO" in out
    assert err.count("\n") == 1 and "differs" in err and "times" in err
    assert main(["judge", str(run), "--json"]) == 1
    assert json.loads(capsys.readouterr().out)["matches_summary"] is False


@pytest.mark.slow
@pytest.mark.parametrize(
    ("edit", "needle"),
    [
        (lambda d: d["times"].update(t_L=float("nan")), "times.t_L"),
        (lambda d: d.update(seed=float("inf")), "seed"),  # "seed": 1e400 reads as inf
        (lambda d: d.update(seed=-1), "seed"),
        (lambda d: d.update(wall_time_s=-3.0), "wall_time_s"),
        (lambda d: d.update(finished="yes"), "finished"),
        (lambda d: d.update(home_pad_W=[0.0, float("inf"), 0.0]), "home_pad_W"),
        (lambda d: d["truth"]["surface"].update(slope_deg=True), "truth"),
        (lambda d: d.update(truth=[1, 2]), "truth"),
    ],
)
def test_judge_checks_the_values_of_run_json(saved_run, tmp_path, capsys, edit, needle):
    run = _copy(saved_run, tmp_path)
    _edit_json(run / "run.json", edit)
    assert needle in one_error(capsys, main(["judge", str(run)]))


@pytest.mark.slow
def test_seed_1e400_literally_in_run_json_is_one_line(saved_run, tmp_path, capsys):
    run = _copy(saved_run, tmp_path)
    text = (run / "run.json").read_text()
    (run / "run.json").write_text(text.replace('"seed": 0', '"seed": 1e400', 1))
    assert "seed" in one_error(capsys, main(["judge", str(run)]))


# --- 6. every traceback case of the issue: one line, exit 2 ----------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("command", ["judge", "export"])
@pytest.mark.parametrize(
    ("file", "damage"),
    [
        ("log.npz", lambda b: b[: len(b) // 2]),  # truncated
        ("log.npz", lambda b: b""),  # zero bytes (was "aborted", exit 130)
        ("log.npz", lambda b: b[:30] + bytes(200) + b[230:]),  # a damaged member
        ("summary.json", lambda b: b[: len(b) // 2]),  # truncated
        ("run.json", lambda b: b[: len(b) // 3]),
        ("run.json", lambda b: b"\xff\xfe garbage"),
    ],
)
def test_damaged_run_files_give_one_line(saved_run, tmp_path, capsys, command, file, damage):
    run = _copy(saved_run, tmp_path)
    (run / file).write_bytes(damage((run / file).read_bytes()))
    argv = ["judge", str(run)] if command == "judge" else ["export", str(run), "--mcap"]
    err = one_error(capsys, main(argv))
    assert file.split(".")[0] in err or "summary" in err


@pytest.mark.slow
def test_export_into_an_unwritable_place_or_a_directory_is_one_line(saved_run, tmp_path, capsys):
    pytest.importorskip("foxglove")
    (tmp_path / "dir.mcap").mkdir()
    (tmp_path / "afile").write_text("")
    for target, needle in (
        (tmp_path / "dir.mcap", "is a directory"),
        (Path("/proc/tetherland.mcap"), "cannot write"),  # a folder no one may write into
        (tmp_path / "afile" / "x.mcap", "cannot write"),
    ):
        err = one_error(capsys, main(["export", str(saved_run), "--mcap", "--out", str(target)]))
        assert needle in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile", "dir.mcap"]


@pytest.mark.parametrize(
    ("override", "needle"),
    [
        ("sim.timestep=5e-324", "sim.timestep"),
        ("sim.timestep=1e-310", "sim.timestep"),
        ("sensors.imu.rate_hz=5e-324", "sensors.imu.rate_hz"),
        ("sensors.mocap.rate_hz=1e-300", "sensors.mocap.rate_hz"),
        ("controller.rate_hz=1e-320", "controller.rate_hz"),
        ("surface.slope_deg=" + "[" * 600 + "]" * 600, "nested too deeply"),
    ],
)
def test_extreme_values_are_one_line(capsys, override, needle):
    assert needle in one_error(capsys, main(["show", "slope50", "--set", override]))


def test_deeply_nested_toml_is_one_line(tmp_path, capsys):
    path = tmp_path / "deep.toml"
    path.write_text("a = " + "[" * 600 + "]" * 600 + "\n")
    assert "nested too deeply" in one_error(capsys, main(["show", str(path)]))
    path.write_text(f"[{'.'.join(['t'] * 300)}]\n")  # tables: parsed, too deep to validate
    assert "nested too deeply" in one_error(capsys, main(["show", str(path)]))


# --- 7. strict types --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("override", "needle"),
    [
        ("surface.slope_deg=true", "surface.slope_deg: Input should be a valid number"),
        ("sensors.imu.rate_hz=true", "sensors.imu.rate_hz: Input should be a valid number"),
        ("faults.hook_jam=1", "faults.hook_jam: Input should be a valid boolean"),
        ('faults.hook_jam="yes"', "faults.hook_jam: Input should be a valid boolean"),
        ("faults.hook_jam=yes", "faults.hook_jam: Input should be a valid boolean"),
        ('surface.slope_deg="50"', "surface.slope_deg: Input should be a valid number"),
        ("mission.hooking.max_attempts=2.0", "mission.hooking.max_attempts: Input should be"),
        ("vehicle.cable_attachment=[0, 0, true]", "vehicle.cable_attachment[2]"),
        ("name=5", "name: Input should be a valid string"),
        ("surface.slope_deg=1979-05-27", "surface.slope_deg"),  # a TOML date
    ],
)
def test_wrong_types_are_rejected_not_converted(capsys, override, needle):
    assert needle in one_error(capsys, main(["show", "slope50", "--set", override]))


def test_numbers_still_take_integers_and_arrays_fill_tuples():
    sc = load_scenario("slope50", ["surface.slope_deg=60", "vehicle.cable_attachment=[0, 0, 0]"])
    assert sc.surface.slope_deg == 60.0 and isinstance(sc.surface.slope_deg, float)
    assert sc.vehicle.cable_attachment == (0.0, 0.0, 0.0)
    assert load_scenario("slope50", ["faults.hook_jam=true"]).faults.hook_jam is True


# --- 8. settings that cannot work are refused before anything flies --------------------------


def test_deploy_time_that_cannot_fit_the_time_limit_is_bad_input(capsys):
    code = main(["mission", "slope50", "--set", "mission.deploy_time=299.5"])
    err = one_error(capsys, code)
    assert "mission.deploy_time" in err and "mission.time_limit" in err


@pytest.mark.slow
def test_deploy_time_that_cuts_the_return_off_is_not_flown(tmp_path, capsys):
    """The fixed holds fit (241 < 300 s), but with the flight legs and the plans the
    nominal slope50 mission (80 s at deploy_time 2 s) needs about 320 s: not flown."""
    out = tmp_path / "m"
    code = main(["mission", "slope50", "--set", "mission.deploy_time=240", "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 1 and err.count("\n") == 0
    assert "mission.time_limit = 300 s is too short" in err
    assert not out.exists()


def test_tension_threshold_above_what_the_pull_can_hold_is_bad_input(capsys):
    sc = load_scenario("slope50")
    from tetherland.config.checks import stretch_tension_limit

    limit = stretch_tension_limit(sc)
    # the pull's spring k_p pull, less the elastic cable's give (k_p pull / (1 + k_p/k)),
    # plus the integral clamp along any direction; k_p = m w_n^2
    ff, v, k = sc.controller.free_flight, sc.vehicle, sc.tether.stiffness
    assert k is not None  # slope50 flies a dyneema line
    k_p = v.mass * ff.position_frequency**2
    spring = (sc.planner.start_tension + k_p * sc.mission.stretch.pull_margin) / (1 + k_p / k)
    assert limit == pytest.approx(spring + 3**0.5 * ff.integral_force_max * v.mass * 9.81)
    key = "mission.stretch.tension_threshold"
    err = one_error(capsys, main(["mission", "slope50", "--set", f"{key}={limit * 1.01}"]))
    assert key in err
    load_scenario("slope50", [f"{key}={limit * 0.99}"])  # below: accepted


def test_rotor_tension_limit_along_the_cable():
    """The largest tension the rotors hold with the cable along d (anchor to vehicle):
    above the anchor the thrust is m g + T (T = 4 f_max - m g); hanging below it the
    thrust is m g - T and may not point down (T = m g); level, |f|^2 = (m g)^2 + T^2
    unless the tilt limit binds first."""
    import numpy as np

    from tetherland.mission.plan import rotor_tension_limit

    sc = load_scenario("slope50", ["controller.free_flight.max_tilt_deg=89"])
    w, f = sc.vehicle.mass * 9.81, 4 * sc.vehicle.f_max
    assert rotor_tension_limit(sc, np.array([0.0, 0.0, 1.0])) == pytest.approx(f - w)
    assert rotor_tension_limit(sc, np.array([0.0, 0.0, -1.0])) == pytest.approx(w)
    side = rotor_tension_limit(sc, np.array([1.0, 0.0, 0.0]))
    assert side == pytest.approx(min((f * f - w * w) ** 0.5, np.tan(np.radians(89)) * w))
    tilted = load_scenario("slope50", ["controller.free_flight.max_tilt_deg=30"])
    assert rotor_tension_limit(tilted, np.array([1.0, 0.0, 0.0])) == pytest.approx(
        np.tan(np.radians(30)) * w
    )


@pytest.mark.parametrize("command", ["show", "plan", "analyze"])
def test_one_set_of_rate_rules_for_every_command(capsys, tmp_path, command):
    """controller.rate_hz = 300 Hz does not divide 1000 Hz: mission rejected it at run
    time while plan accepted it; now every command does, before any work."""
    argv = [command, "slope50", "--set", "controller.rate_hz=300"]
    if command == "plan":
        argv += ["--out", str(tmp_path / "p")]
    assert "controller.rate_hz" in one_error(capsys, main(argv))


# --- 9. files that are no scenario, huge files ------------------------------------------------


def test_a_named_pipe_is_not_read(tmp_path):
    fifo = tmp_path / "s.toml"
    os.mkfifo(fifo)
    proc = subprocess.run([EXE, "show", str(fifo)], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "not a regular file" in proc.stderr
    assert proc.stderr.count("\n") == 1


def test_a_50_mb_scenario_file_is_refused_unread(tmp_path, capsys):
    path = tmp_path / "big.toml"
    with open(path, "wb") as fh:  # sparse: 50 MB long, nothing written
        fh.truncate(50 * 2**20)
    assert "at most 16 MiB" in one_error(capsys, main(["show", str(path)]))


def test_a_huge_value_is_cut_in_the_error_line(tmp_path, capsys):
    path = tmp_path / "big.toml"
    path.write_text("[surface]\nslope_deg = [" + ", ".join(["1.5"] * 400_000) + "]\n")
    err = one_error(capsys, main(["show", str(path)]))
    assert err.startswith("error: surface.slope_deg")


# --- issue 24, item 8: every validation error of a file -------------------------------------


def test_every_validation_error_of_a_file_is_listed(tmp_path, capsys):
    path = tmp_path / "two.toml"
    path.write_text(
        '[surface]\nslope_deg = 500\nfriction = "high"\ncolour = "red"\n[vehicle]\nmass = -1\n'
    )
    assert main(["show", str(path)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert all(line.startswith("error: ") for line in lines)
    fields = sorted(line.split(":")[1].strip() for line in lines)
    assert fields == ["surface.colour", "surface.friction", "surface.slope_deg", "vehicle.mass"]


# --- issue 24, item 7: one vocabulary ---------------------------------------------------------


def test_the_one_word_result_is_the_outcome():
    assert Outcome.SUCCESS.label == "success"
    assert Outcome.SAFE_STOP.label == "safe stop"
    assert Outcome.CRASHED.label == "crash"
    assert Outcome.NO_RUN.label == "not flown"
    others = set(Outcome) - {Outcome.SUCCESS, Outcome.SAFE_STOP, Outcome.CRASHED, Outcome.NO_RUN}
    assert {o.label for o in others} == {"failure"}


def test_only_the_required_conditions_are_listed():
    landing = {"conditions": {"1": True, "2": True, "3": True, "4": False, "5": True},
               "required_conditions": ["1", "2", "3", "5"]}  # fmt: skip
    assert conditions_text(landing) == "1:ok 2:ok 3:ok 5:ok (4 not required)"
    landing["conditions"]["2"] = False
    assert conditions_text(landing).startswith("1:ok 2:NO 3:ok 5:ok")


@pytest.mark.slow
def test_a_snap_fault_run_prints_safe_stop(tmp_path):
    """A cable snap while stretching ends in the hover-away safe stop: the one-line result
    says "safe stop" (it said "failure"), and the exit code is 1 (not a success)."""
    proc = subprocess.run(
        [EXE, "mission", "slope50", "--set", "faults.cable_snap_time=25",
         "--out", str(tmp_path / "m")],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    summary = json.loads((tmp_path / "m" / "summary.json").read_text())
    assert summary["outcome"] == "safe_stop"
    assert proc.returncode == 1
    first = next(line for line in proc.stdout.splitlines() if "(tethered):" in line)
    assert "safe stop" in first and "failure" not in first


@pytest.mark.slow
def test_the_contact_free_run_lists_only_its_required_conditions(saved_run, capsys):
    summary = json.loads((saved_run / "summary.json").read_text())
    assert summary["landing"]["required_conditions"] == ["1", "2", "3", "5"]
    assert main(["judge", str(saved_run)]) == 0
    out = capsys.readouterr().out
    assert "success" in out.splitlines()[0]
    from tetherland.cli.mission import _print_summary  # the table of `mission`

    _print_summary(summary, {"summary": saved_run / "summary.json"}, [])  # a success: none
    table = capsys.readouterr().out
    assert "conditions (required)" in table and "4:" not in table and "(4 not required)" in table
