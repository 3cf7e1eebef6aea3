"""Campaign CPU per run (issue 25 item 3): a ``slope50`` mission campaign with both
methods on a pool of worker processes, against the target of 1.0 s of CPU per run.

Run: ``.venv/bin/python benchmarks/bench_campaign.py [--runs 20] [--workers 2] [--seed 1]``

``--runs`` runs per method (20: the 40-run campaign of the target). The CPU time is the
process CPU (user + system) of the main process and of its worker processes together
(``getrusage``, the workers counted when the pool has joined them), which depends much
less on the other load of a shared machine than the wall time. Per method: the mean of
the runs' own CPU (``cpu_time_s`` of their records, measured in the workers) plus an equal
share of what the runs do not contain (the workers' start-up: imports, compiled kernels
loaded, planners built; the main process), which is printed on its own line.

Per method also the simulated time per CPU second of its runs (the closed loop's real-time
factor in CPU terms): a tethered run flies about 80 s, a contact-free run about 8 s, so the
closed loop, not the start-up, decides the CPU per run. What each worker pays only once
(imports, compiled kernels loaded, planners built, each distinct scene's MuJoCo model
compiled: ``tetherland.sim.model_cache``) is in the start-up line.

Equivalent command line: ``tetherland campaign slope50 --runs 20 --workers 2 --seed 1
--out out/cpu --overwrite`` under ``/usr/bin/time -f %U+%S``.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import tempfile
import time

from tetherland.campaign import CampaignSpec, make_executor, open_store, run_campaign
from tetherland.config import load_scenario

TARGET_CPU_PER_RUN_S = 1.0
"""CPU per campaign run, both methods, start-up included [s]."""


def _cpu_seconds() -> float:
    """User + system CPU of this process and of its joined children [s]."""
    total = 0.0
    for who in (resource.RUSAGE_SELF, resource.RUSAGE_CHILDREN):
        usage = resource.getrusage(who)
        total += usage.ru_utime + usage.ru_stime
    return total


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=20, help="runs per method")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    spec = CampaignSpec(
        scenario=load_scenario("slope50").model_dump(mode="json"), runs=args.runs,
        seed=args.seed,
    )  # fmt: skip
    print(f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())} "
          f"({os.cpu_count()} cpus)")  # fmt: skip
    records: list[dict] = []
    with tempfile.TemporaryDirectory() as d:
        c0, t0 = _cpu_seconds(), time.perf_counter()
        run_campaign(spec, open_store(spec, d), make_executor("local", args.workers),
                     on_result=records.append, keep="none")  # fmt: skip
        wall, cpu = time.perf_counter() - t0, _cpu_seconds() - c0
    n = len(records)
    print(f"campaign slope50, {args.runs} runs per method, {args.workers} workers, seed "
          f"{args.seed}: {n} runs, {cpu:.1f} s CPU, {wall:.1f} s wall")  # fmt: skip
    if all("cpu_time_s" in r for r in records):  # (records of older commits lack it)
        _per_method(records, cpu, args.workers)
    per_run = cpu / n
    verdict = "met" if per_run <= TARGET_CPU_PER_RUN_S else "MISSED"
    print(f"CPU per run, both methods: {per_run:.2f} s (target <= "
          f"{TARGET_CPU_PER_RUN_S:.1f} s: {verdict})")  # fmt: skip
    print(f"load average after:  {' '.join(f'{x:.2f}' for x in os.getloadavg())}")


def _per_method(records: list[dict], cpu: float, workers: int) -> None:
    """CPU per run of each method, the runs' own plus an equal share of the rest."""
    n = len(records)
    overhead = cpu - sum(r["cpu_time_s"] for r in records)
    print(f"  outside the runs (worker start-up, main process): {overhead:.1f} s CPU "
          f"({overhead / workers:.1f} s per worker)")  # fmt: skip
    for method in sorted({r["method"] for r in records}):
        mine = [r for r in records if r["method"] == method]
        own = [r["cpu_time_s"] for r in mine]
        ok = sum(bool(r["verdict"].get("success")) for r in mine)
        sim = sum(r["verdict"].get("sim_time_s") or 0.0 for r in mine)
        print(f"  {method:12s} {statistics.fmean(own) + overhead / n:5.2f} s CPU per run "
              f"(own {statistics.fmean(own):.2f}, least {min(own):.2f}, most {max(own):.2f}; "
              f"{sim / len(mine):.1f} s simulated per run, {sim / sum(own):.1f} s per CPU s; "
              f"{ok}/{len(own)} succeeded)")  # fmt: skip


if __name__ == "__main__":
    main()
