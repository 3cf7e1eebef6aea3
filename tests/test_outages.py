"""Bad output directories and unreachable or failing clusters: one line, exit 2, no work
lost or recorded twice."""

from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import pytest

from tetherland.campaign import CampaignSpec, ResultsStore, Sweep, open_store, run_campaign
from tetherland.campaign.executors import DaskExecutor, check_reachable
from tetherland.cli import main
from tetherland.config import load_scenario
from tetherland.errors import ConfigError


def _one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.mark.parametrize(
    "argv",
    [
        ["mission", "slope50", "--out", "/proc/x"],
        ["plan", "slope50", "--out", "/proc/x"],
        ["campaign", "slope50", "--job", "analysis", "--runs", "1", "--out", "/proc/x"],
    ],
)
def test_an_unwritable_output_directory_fails_before_any_work(argv, capsys):
    t0 = time.perf_counter()
    assert main(argv) == 2
    err = _one_line(capsys)
    assert "--out" in err and "/proc/x" in err
    assert time.perf_counter() - t0 < 10.0  # refused before planning or flying


def test_an_output_path_that_is_a_file_is_refused(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    assert main(["mission", "slope50", "--out", str(blocker / "run")]) == 2
    assert "--out" in _one_line(capsys)
    assert blocker.read_text() == "not a directory"


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]  # closed again: nothing listens there


@pytest.mark.parametrize("engine", ["dask", "ray"])
def test_an_unreachable_cluster_address_fails_within_seconds(engine, capsys, tmp_path):
    address = f"127.0.0.1:{_free_port()}"
    t0 = time.perf_counter()
    code = main(["campaign", "slope50", "--job", "analysis", "--runs", "1", "--engine", engine,
                 "--address", address, "--out", str(tmp_path / "c")])  # fmt: skip
    elapsed = time.perf_counter() - t0
    assert code == 2
    err = _one_line(capsys)
    assert "--address" in err and address in err
    assert elapsed < 30.0


def test_address_syntax_is_checked():
    with pytest.raises(ConfigError, match="expected host:port"):
        check_reachable("dask", "tcp://:80")
    with pytest.raises(ConfigError, match="no dask scheduler reachable"):
        check_reachable("dask", f"tcp://127.0.0.1:{_free_port()}", timeout=2.0)


@pytest.mark.slow
def test_a_dask_worker_killed_mid_campaign_loses_and_repeats_no_run(tmp_path: Path):
    """SIGKILL one of two Dask worker processes after the first result: Dask reruns its
    tasks on the other worker (its nanny restarts it), and every run is recorded once."""
    spec = CampaignSpec(
        scenario=load_scenario("slope50").model_dump(mode="json"),
        runs=8,
        sweep=Sweep.parse("surface.slope_deg=20:70:25"),
        seed=3,
        job="analysis",
    )
    store = open_store(spec, tmp_path / "c")
    executor = DaskExecutor(2)
    pids = executor._client.run(os.getpid)
    killed: list[int] = []

    def on_result(record: dict) -> None:
        if not killed:
            pid = next(iter(pids.values()))
            os.kill(pid, signal.SIGKILL)
            killed.append(pid)

    result = run_campaign(spec, store, executor, on_result=on_result)
    records = ResultsStore(tmp_path / "c").load()
    ids = [r["run_id"] for r in records]
    assert killed and result.total == len(spec.expand()) == 2 * 3 * 8
    assert len(ids) == len(set(ids)) == result.total  # each run exactly once
    assert all(r["status"] == "ok" for r in records)
    # the killed process is gone
    assert subprocess.run(["kill", "-0", str(killed[0])], capture_output=True).returncode != 0


def test_a_campaign_directory_keeps_each_run_once_when_an_engine_repeats_one(tmp_path):
    """An engine may deliver a rerun of a lost worker's job twice: the store keeps one."""
    spec = CampaignSpec(
        scenario=load_scenario("slope50").model_dump(mode="json"), runs=2, seed=1,
        job="analysis",
    )  # fmt: skip
    class Repeating:
        def map_unordered(self, fn, jobs, lost=None):
            for job in jobs:
                record = fn(job)
                yield record
                yield dict(record)

        def close(self):
            pass

    store = open_store(spec, tmp_path / "r")
    run_campaign(spec, store, Repeating())
    ids = [r["run_id"] for r in ResultsStore(tmp_path / "r").load()]
    assert len(ids) == len(set(ids)) == len(spec.expand())

