"""Campaigns that heal and cannot be corrupted (issue 28) and stop at once (issue 24, item 8):
one writer per directory, lost workers retried and counted once, --resume retries only
infrastructure errors, workers die with the main process, an interrupt stops without
waiting for the runs in flight and prints the exact resume command, and a cluster address
that answers TCP but no client fails within 30 s on one line."""

from __future__ import annotations

import importlib.util
import json
import os
import shlex
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from tetherland.campaign import (
    CampaignSpec,
    ResultsStore,
    Sweep,
    open_store,
    run_campaign,
)
from tetherland.campaign.executors import (
    CONNECT_TIMEOUT,
    HANDSHAKE_TIMEOUT,
    InlineExecutor,
    LocalPoolExecutor,
    check_handshake,
)
from tetherland.campaign.jobs import Job, lost_record
from tetherland.campaign.store import retryable
from tetherland.cli import main
from tetherland.config import load_scenario
from tetherland.errors import ConfigError

EXE = str(Path(sys.executable).with_name("tetherland"))


def spec_of(runs: int, sweep: str | None = None, seed: int = 0) -> CampaignSpec:
    """The spec `tetherland campaign slope50 --job analysis --runs R [--sweep S]` builds."""
    return CampaignSpec(
        scenario=load_scenario("slope50").model_dump(mode="json"),
        runs=runs,
        sweep=Sweep.parse(sweep) if sweep else None,
        seed=seed,
        job="analysis",
    )


def comparable(records: list[dict]) -> list[dict]:
    return sorted(
        ({k: v for k, v in r.items() if k not in ("wall_time_s", "cpu_time_s")} for r in records),
        key=lambda r: r["run_id"],
    )


def lines(path: Path) -> int:
    try:
        return path.read_bytes().count(b"\n")
    except FileNotFoundError:
        return 0


def children(pid: int) -> list[int]:
    path = Path(f"/proc/{pid}/task/{pid}/children")
    return [int(p) for p in path.read_text().split()] if path.exists() else []


def pool_workers(pid: int) -> list[int]:
    """The spawned pool workers among ``pid``'s children (not the resource tracker)."""
    out = []
    for child in children(pid):
        try:
            if b"spawn_main" in Path(f"/proc/{child}/cmdline").read_bytes():
                out.append(child)
        except OSError:
            pass
    return out


def alive(pid: int) -> bool:
    """Running (a zombie waiting for its reaper has exited)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def wait_until(condition, timeout: float, step: float = 0.02) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(step)
    return condition()


# --- 4. one writer per campaign directory ------------------------------------------------------


def test_a_second_writer_gets_one_line_and_exit_2(tmp_path, capsys):
    spec = spec_of(2)
    with open_store(spec, tmp_path) as store:  # the first writer holds the directory
        store.append({"run_id": "x", "method": "tethered"})
        code = main(["campaign", "slope50", "--job", "analysis", "--runs", "2", "--resume",
                     "--workers", "1", "--out", str(tmp_path)])  # fmt: skip
        _, err = capsys.readouterr()
        assert code == 2 and err.count("\n") == 1
        assert f"another process (pid {os.getpid()})" in err
        with pytest.raises(ConfigError, match="another process"):
            open_store(spec, tmp_path, resume=True)
        assert [r["run_id"] for r in store.load()] == ["x"]
    with open_store(spec, tmp_path, resume=True):  # released: the next writer may go on
        pass


@pytest.mark.slow
def test_a_second_resume_while_the_first_runs_does_no_run_twice(tmp_path):
    out = tmp_path / "camp"
    cmd = [EXE, "campaign", "slope50", "--job", "analysis", "--runs", "3000", "--workers", "2",
           "--methods", "tethered", "--out", str(out)]  # fmt: skip
    first = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert wait_until(lambda: lines(out / "results.jsonl") >= 1, 120)
    second = subprocess.run([*cmd, "--resume"], capture_output=True, text=True, timeout=120)
    running = first.poll() is None
    first.send_signal(signal.SIGINT)
    assert first.wait(timeout=120) in (0, 130), first.stderr.read()
    assert running, "the first campaign ended before the second started"
    assert second.returncode == 2, second.stderr
    assert second.stderr.count("\n") == 1 and "another process" in second.stderr
    assert f"pid {first.pid}" in second.stderr
    ids = [r["run_id"] for r in ResultsStore(out).load()]
    assert len(ids) == len(set(ids)) >= 1
    assert (out / "results.csv").read_text().count("\n") == len(ids) + 1


# --- 3. a lost local worker: restarted, its run retried and counted once -----------------------


def kill_once(args: tuple[str, int]) -> int:
    """Run in a pool worker: the first attempt at job 3 (marked by a file) kills its own
    worker, as the kernel's OOM killer or a stray `kill -9` would."""
    marker, job = args
    if job == 3 and not os.path.exists(marker):
        Path(marker).write_text("killed")
        os.kill(os.getpid(), signal.SIGKILL)
    return job * job


def kill_always(job: int) -> int:
    if job == 2:
        os.kill(os.getpid(), signal.SIGKILL)
    return job * job


def test_a_killed_pool_worker_is_retried_and_every_result_comes_once(tmp_path):
    pool = LocalPoolExecutor(2, retries=2)
    marker = str(tmp_path / "killed")
    try:
        results = list(pool.map_unordered(kill_once, [(marker, j) for j in range(10)]))
    finally:
        pool.close()
    assert sorted(results) == [j * j for j in range(10)]
    assert Path(marker).exists() and pool.restarts == 1


def square(job: int) -> int:
    return job * job


def test_a_pool_that_breaks_between_two_waits_is_rebuilt_and_no_run_is_lost(monkeypatch):
    """The race of a worker killed after the last wait: the pool is already broken when the
    next run is submitted, so ``submit`` itself raises ``BrokenProcessPool`` (it raised out
    of the campaign once). The run goes back to the queue, the pool is rebuilt, and every
    job still yields exactly one result."""
    from concurrent.futures.process import BrokenProcessPool

    pool = LocalPoolExecutor(2, retries=0)
    submitted = {"n": 0}
    first = pool._pool
    real_submit = first.submit

    def submit_then_break(*args, **kwargs):
        submitted["n"] += 1
        if submitted["n"] == 6:  # the pool "broke" after five runs went in
            raise BrokenProcessPool("a child process terminated abruptly")
        return real_submit(*args, **kwargs)

    monkeypatch.setattr(first, "submit", submit_then_break)
    try:
        results = list(pool.map_unordered(square, range(10)))
    finally:
        pool.close()
    assert sorted(results) == [j * j for j in range(10)]
    assert pool.restarts == 1 and submitted["n"] == 6


def test_a_run_whose_worker_dies_every_time_is_lost_after_its_retries(tmp_path):
    pool = LocalPoolExecutor(2, retries=1)
    lost: list[int] = []

    def on_lost(job, error):
        lost.append(job)
        return -1

    try:
        results = list(pool.map_unordered(kill_always, range(6), lost=on_lost))
    finally:
        pool.close()
    # only the run of the dying worker is charged: its neighbours in flight are not lost
    assert lost == [2] and sorted(results) == [-1, 0, 1, 9, 16, 25]
    assert pool.restarts == 2  # its first attempt and its one retry each broke the pool


@pytest.mark.slow
def test_a_campaign_whose_worker_is_killed_equals_a_clean_one(tmp_path):
    """The issue's case, end to end: kill one local pool worker of a running campaign; it
    ends with exit 0, every run exactly once and the same records as a clean campaign."""
    out = tmp_path / "camp"
    cmd = [EXE, "campaign", "slope50", "--job", "analysis", "--runs", "30", "--workers", "2",
           "--sweep", "surface.slope_deg=30,60", "--out", str(out)]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert wait_until(lambda: lines(out / "results.jsonl") >= 10, 120)
    victims = pool_workers(proc.pid)
    assert victims, "no pool worker to kill"
    os.kill(victims[0], signal.SIGKILL)
    at_kill = lines(out / "results.jsonl")
    assert proc.wait(timeout=300) == 0, proc.stderr.read()
    assert at_kill < 120, "the campaign ended before the kill"
    records = ResultsStore(out).load()
    ids = [r["run_id"] for r in records]
    assert len(ids) == len(set(ids)) == 120
    assert all(r["status"] == "ok" for r in records)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["complete"] and summary["lost_runs"] == []
    assert summary["worker_restarts"] == 1  # the pool was rebuilt once
    assert sum(r["n"] for r in summary["rates"]) == 120
    clean_spec = spec_of(30, "surface.slope_deg=30,60")
    manifest = json.loads((out / "campaign.json").read_text())
    assert manifest["fingerprint"] == clean_spec.fingerprint()
    run_campaign(clean_spec, open_store(clean_spec, tmp_path / "clean"), InlineExecutor())
    assert comparable(records) == comparable(ResultsStore(tmp_path / "clean").load())


# --- --resume retries infrastructure errors, never real failures -------------------------------


def test_resume_reruns_lost_runs_but_not_real_errors(tmp_path):
    spec = spec_of(2, "surface.slope_deg=30,80")
    clean = run_campaign(spec, open_store(spec, tmp_path / "clean"), InlineExecutor())
    reference = {r["run_id"]: r for r in ResultsStore(tmp_path / "clean").load()}
    assert clean.done == 8
    jobs = {j.run.run_id: j for j in (Job(spec.scenario, run, spec.job) for run in spec.expand())}
    lost_id, legacy_id, error_id, failed_id = sorted(reference)[:4]
    assert reference[failed_id]["verdict"]["success"] is False  # free-flight at 30/80 deg
    real_error = {
        **reference[error_id],
        "status": "error",
        "error_kind": "run",
        "error": "internal error: ZeroDivisionError",
        "verdict": {"success": False},
    }
    legacy = lost_record(jobs[legacy_id], RuntimeError("gone"))
    del legacy["error_kind"]  # written before records carried error_kind
    tampered = [
        lost_record(jobs[lost_id], RuntimeError("worker died")) if rid == lost_id
        else legacy if rid == legacy_id
        else real_error if rid == error_id
        else r
        for rid, r in reference.items()
    ]  # fmt: skip
    assert [retryable(r) for r in tampered].count(True) == 2
    store_dir = tmp_path / "camp"
    with open_store(spec, store_dir) as store:
        for r in tampered:
            store.append(r)
    result = run_campaign(spec, open_store(spec, store_dir, resume=True), InlineExecutor())
    assert result.new == 2 and result.done == 8
    records = ResultsStore(store_dir).load()
    assert len(records) == 8 == len({r["run_id"] for r in records})  # one line per run
    by_id = {r["run_id"]: r for r in records}
    for rid in (lost_id, legacy_id, failed_id):  # rerun (lost) or kept (a failure): as clean
        assert comparable([by_id[rid]]) == comparable([reference[rid]])
    assert by_id[error_id]["status"] == "error"  # a real error is never retried


def test_lost_runs_are_not_counted_as_failures(tmp_path):
    spec = spec_of(1)
    jobs = [Job(spec.scenario, run, spec.job) for run in spec.expand()]
    with open_store(spec, tmp_path) as store:
        store.append(lost_record(jobs[0], RuntimeError("worker died")))
    result = run_campaign(spec, open_store(spec, tmp_path, resume=True), InlineExecutor())
    assert result.done == 2 and result.lost == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["complete"] and sum(r["errors"] for r in summary["rates"]) == 0


# --- pool workers die with the main process ----------------------------------------------------


@pytest.mark.slow
def test_pool_workers_die_with_the_main_process(tmp_path):
    """SIGKILL of the main process only: its workers, busy in closed-loop missions that
    take tens of seconds, exit within a second or so instead of running on. (A worker
    still starting up, importing the package, exits as soon as that is done.)"""
    out = tmp_path / "camp"
    cmd = [EXE, "campaign", "slope50", "--runs", "4", "--workers", "2", "--out", str(out)]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    # a first result: both workers are past their start-up and into the next missions
    assert wait_until(lambda: lines(out / "results.jsonl") >= 1, 600, step=0.1)
    workers = pool_workers(proc.pid)
    assert len(workers) == 2
    proc.kill()
    proc.wait()
    assert wait_until(lambda: not any(alive(p) for p in workers), 10.0), [
        (p, Path(f"/proc/{p}/cmdline").read_bytes()[:80]) for p in workers if alive(p)
    ]
    assert lines(out / "results.jsonl") < 8


# --- issue 24, item 8: an interrupt stops at once, with the exact resume command ---------------


@pytest.mark.slow
def test_sigint_abandons_the_runs_in_flight_and_prints_the_resume_command(tmp_path):
    """With closed-loop missions in flight (each takes tens of seconds), SIGINT ends the
    campaign without waiting for them: no result is added after the signal, the workers
    are stopped, exit 130, and the printed command resumes the campaign."""
    out = tmp_path / "camp dir"  # a space: the printed command must quote it
    cmd = [EXE, "campaign", "slope50", "--runs", "2", "--workers", "2", "--seed", "5",
           "--set", "surface.friction=0.7", "--out", str(out)]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert wait_until(lambda: len(pool_workers(proc.pid)) == 2, 120)
    workers = pool_workers(proc.pid)
    time.sleep(8.0)
    before = lines(out / "results.jsonl")
    t0 = time.monotonic()
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    stopped = time.monotonic() - t0
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr
    assert lines(out / "results.jsonl") == before  # nothing finished after the signal
    assert wait_until(lambda: not any(alive(p) for p in workers), 5.0)
    printed = [line for line in stdout.splitlines() if line.startswith("tetherland campaign")]
    assert len(printed) == 1, stdout
    argv = shlex.split(printed[0])
    assert argv[argv.index("--out") + 1] == str(out) and argv[-1] == "--resume"
    for option, value in (("--seed", "5"), ("--runs", "2"), ("--workers", "2"),
                          ("--set", "surface.friction=0.7")):  # fmt: skip
        assert argv[argv.index(option) + 1] == value
    # the printed command names the same campaign (same fingerprint: it is accepted)
    spec_check = subprocess.run(
        [EXE, *argv[1:], "--job", "analysis"], capture_output=True, text=True, timeout=120
    )
    assert spec_check.returncode == 2 and "different campaign" in spec_check.stderr
    print(f"stopped {stopped:.2f} s after SIGINT")  # measured in benchmarks too


@pytest.mark.slow
def test_the_printed_resume_command_completes_the_campaign(tmp_path):
    out = tmp_path / "camp"
    # 2 x 40 analysis runs: seconds of work left when the first 5 are saved
    cmd = [EXE, "campaign", "slope50", "--job", "analysis", "--runs", "40", "--workers", "2",
           "--sweep", "surface.slope_deg=40,50", "--methods", "tethered", "--seed", "11",
           "--set", "vehicle.mass=1.1", "--out", str(out)]  # fmt: skip
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    assert wait_until(lambda: lines(out / "results.jsonl") >= 5, 120)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130, stderr
    saved = lines(out / "results.jsonl")
    assert 5 <= saved < 80
    printed = next(line for line in stdout.splitlines() if line.startswith("tetherland "))
    argv = shlex.split(printed)
    done = subprocess.run([EXE, *argv[1:]], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    ids = [r["run_id"] for r in ResultsStore(out).load()]
    assert len(ids) == len(set(ids)) == 80
    assert json.loads((out / "summary.json").read_text())["complete"]


# --- 5. a cluster address that accepts TCP but lets no client in -------------------------------


class _Server:
    """A local TCP server that accepts connections and then says nothing, or garbage."""

    def __init__(self, garbage: bool):
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.garbage = garbage
        self.conns: list[socket.socket] = []
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self.conns.append(conn)
            if self.garbage:
                try:
                    conn.sendall(b"HTTP/1.0 200 OK\r\n\r\nnot a scheduler\n" * 64)
                except OSError:
                    pass

    def close(self) -> None:
        for c in self.conns:
            c.close()
        self.sock.close()


@pytest.mark.slow
def test_an_address_that_lets_no_client_in_fails_within_30_s(tmp_path):
    """Each engine (dask, ray) against a server that stays silent and one that answers
    garbage: one line naming the address, exit 2, no campaign left behind. The four
    commands run at once (each mostly waits out its connection timeouts)."""
    def installed(module: str) -> bool:
        try:  # (a dotted name imports its parent package first)
            return importlib.util.find_spec(module) is not None
        except ModuleNotFoundError:
            return False

    engines = [e for e in ("dask", "ray") if installed("dask.distributed" if e == "dask" else e)]
    if not engines:
        pytest.skip("neither dask.distributed nor ray is installed")
    assert CONNECT_TIMEOUT + HANDSHAKE_TIMEOUT < 30.0
    cases = [(engine, garbage) for engine in engines for garbage in (False, True)]
    servers = {case: _Server(case[1]) for case in cases}
    procs = {}
    try:
        t0 = time.monotonic()
        for (engine, garbage), server in servers.items():
            out = tmp_path / f"{engine}-{garbage}"
            procs[engine, garbage] = subprocess.Popen(
                [EXE, "campaign", "slope50", "--job", "analysis", "--runs", "1", "--engine",
                 engine, "--address", f"127.0.0.1:{server.port}", "--out", str(out)],
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
            )  # fmt: skip
        done = {case: proc.communicate(timeout=120) for case, proc in procs.items()}
        elapsed = time.monotonic() - t0
    finally:
        for proc in procs.values():
            if proc.poll() is None:
                proc.kill()
        for server in servers.values():
            server.close()
    print(f"{len(cases)} addresses refused together in {elapsed:.1f} s")
    for (engine, garbage), (_, stderr) in done.items():
        case = f"{engine} {'garbage' if garbage else 'silent'}"
        assert procs[engine, garbage].returncode == 2, (case, stderr)
        err = stderr.strip()
        assert err.count("\n") == 0 and "Traceback" not in err and len(err) <= 307, case
        assert err.startswith(f"error: --address 127.0.0.1:{servers[engine, garbage].port}")
        assert "no " + engine in err or "cannot connect" in err, (case, err)
        assert not (tmp_path / f"{engine}-{garbage}" / "campaign.json").exists(), case


def test_the_handshake_names_the_clients_last_error():
    """A client that fails at once (a Ray Client address without ray[client], or any
    refusal) is reported with its own last error line."""
    pytest.importorskip("ray")
    with pytest.raises(ConfigError, match=r"ray client cannot connect: .+"):
        check_handshake("ray", "ray://127.0.0.1:1", timeout=25.0)
