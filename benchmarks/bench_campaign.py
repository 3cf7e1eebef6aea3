"""Campaign throughput (runs per minute) with 1 and 2 workers (issue 7).

Uses the full closed-loop mission job on slope50 (both methods), and the fast analysis
job for reference. Run: .venv/bin/python benchmarks/bench_campaign.py [runs]
"""

from __future__ import annotations

import sys
import tempfile
import time

from tetherland.campaign import CampaignSpec, make_executor, open_store, run_campaign
from tetherland.config import load_scenario


def throughput(job: str, runs: int, workers: int) -> tuple[float, int]:
    spec = CampaignSpec(
        scenario=load_scenario("slope50").model_dump(mode="json"), runs=runs, seed=7, job=job
    )
    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        result = run_campaign(spec, open_store(spec, d), make_executor("local", workers))
        wall = time.perf_counter() - t0
    return result.done / wall * 60.0, result.done


def main() -> None:
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    print(f"{'job':10s} {'workers':>7s} {'runs':>5s} {'runs/min':>9s}")
    for job, n in (("mission", runs), ("analysis", 50)):
        for workers in (1, 2):
            rate, done = throughput(job, n, workers)
            print(f"{job:10s} {workers:7d} {done:5d} {rate:9.1f}")


if __name__ == "__main__":
    main()
