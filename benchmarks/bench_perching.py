"""Solve times of the contact-free perching planner per slope (free and fixed final time).

Run: ``.venv/bin/python benchmarks/bench_perching.py [--repeats 5]``

"solve" is the total NLP solver wall time of one request (the free-final-time search
makes several solves); "plan" adds building the problems, the fine re-simulation and the
verification. The compiled solver is built once (its time is printed separately). The
machine's load average is printed: other jobs on a shared machine inflate the numbers.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

from tetherland.config import load_scenario
from tetherland.planning.perching import PerchingPlanner


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    planner = PerchingPlanner()
    first = planner.plan(load_scenario("slope50"))
    print(f"load average before: {_load()} ({os.cpu_count()} cpus)")
    print(f"solver build (once): {first.build_time_s * 1e3:.0f} ms")
    header = (
        f"{'slope':>5} {'final time':11} {'T [s]':>6} {'solves':>6} {'median solve':>13} "
        f"{'median plan':>12}"
    )
    print(header)
    print("-" * len(header))
    for slope in (0, 20, 40, 50, 60):
        sc = load_scenario("slope50", [f"surface.slope_deg={slope}"])
        for label, duration in (("free", None), ("fixed 2.5 s", 2.5)):
            solve, wall = [], []
            for _ in range(args.repeats):
                t0 = time.perf_counter()
                result = planner.plan(sc, duration=duration)
                wall.append(time.perf_counter() - t0)
                if not result.success:
                    raise SystemExit(f"benchmark plan failed: {result.message}")
                solve.append(result.solve_time_s)
            print(
                f"{slope:5d} {label:11} {result.duration:6.2f} {result.solves:6d} "
                f"{statistics.median(solve) * 1e3:10.0f} ms {statistics.median(wall) * 1e3:9.0f} ms"
            )
    print(f"load average after:  {_load()}")


if __name__ == "__main__":
    main()
