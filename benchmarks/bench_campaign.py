"""Campaign throughput (runs per minute) with 1 and 2 workers (issue 7).

Uses the full closed-loop mission job on slope50 (both methods), and the fast analysis
job for reference. Besides runs per minute (wall clock, which on a shared machine depends
on the other load) it prints the CPU seconds per run of the main process and its workers
together (getrusage), which does not depend on the load. Run:
.venv/bin/python benchmarks/bench_campaign.py [runs]

Before (commit d57bf1a, the same script with PYTHONPATH pointing at that checkout's src/)
and after on this machine, measured back to back: see BEFORE below and CHANGELOG.md.
"""

from __future__ import annotations

import resource
import sys
import tempfile
import time

from tetherland.campaign import CampaignSpec, make_executor, open_store, run_campaign
from tetherland.config import load_scenario

BEFORE = {"commit": "d57bf1a", "cpu_s_per_run": {"tethered": 17.3, "free-flight": 5.9}}
"""CPU seconds per slope50 mission job at d57bf1a (mean of 3 seeds, both methods, the
campaign configuration of docs/results.md; measured back to back with the after-numbers)."""


def _cpu_seconds() -> float:
    total = 0.0
    for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN):
        usage = resource.getrusage(who)
        total += usage.ru_utime + usage.ru_stime
    return total


def throughput(job: str, runs: int, workers: int) -> tuple[float, float, int]:
    """Runs per minute, CPU seconds per run and the number of runs done."""
    spec = CampaignSpec(
        scenario=load_scenario("slope50").model_dump(mode="json"), runs=runs, seed=7, job=job
    )
    with tempfile.TemporaryDirectory() as d:
        c0, t0 = _cpu_seconds(), time.perf_counter()
        result = run_campaign(spec, open_store(spec, d), make_executor("local", workers))
        wall, cpu = time.perf_counter() - t0, _cpu_seconds() - c0
    return result.done / wall * 60.0, cpu / max(result.done, 1), result.done


def main() -> None:
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    before = BEFORE["cpu_s_per_run"]
    print(
        f"before ({BEFORE['commit']}): {before['tethered']:.1f} s CPU per tethered run, "
        f"{before['free-flight']:.1f} s per contact-free run "
        f"({60.0 / ((before['tethered'] + before['free-flight']) / 2):.1f} runs/min per core)"
    )
    print(f"{'job':10s} {'workers':>7s} {'runs':>5s} {'runs/min':>9s} {'CPU s/run':>10s}")
    for job, n in (("mission", runs), ("analysis", 50)):
        for workers in (1, 2):
            rate, cpu, done = throughput(job, n, workers)
            print(f"{job:10s} {workers:7d} {done:5d} {rate:9.1f} {cpu:10.2f}")


if __name__ == "__main__":
    main()
