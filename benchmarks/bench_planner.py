"""Solve times of the 50-degree landing OCP (6.21) with fatrop and IPOPT, cold and warm.

Run: ``.venv/bin/python benchmarks/bench_planner.py [--repeats 21]``

* cold: from the spline initial guess (the compiled solver is reused; its one-off build
  time is printed separately);
* warm (same): warm-started from the previous solution of the same problem;
* warm (+1 deg): warm-started from the 50-degree solution, solving the 51-degree landing.

"solve" is the NLP solver's wall time; "plan" adds building the problem, the fine
re-simulation of the solution and its verification. The machine's load average is
printed before and after: other jobs on a shared machine inflate the numbers.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable

from tetherland.config import Scenario, load_scenario
from tetherland.planning import Planner, PlanResult


def _runs(fn: Callable[[], PlanResult], repeats: int) -> list[tuple[PlanResult, float]]:
    out = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        out.append((result, time.perf_counter() - t0))
        if not result.success:
            raise SystemExit(f"benchmark plan failed: {result.message}")
    return out


def bench_solver(solver: str, base: Scenario, nearby: Scenario, repeats: int) -> None:
    """Print the build time and the cold/warm solve times of one solver."""
    planner = Planner()
    first = _runs(lambda: planner.plan(base, solver=solver), 1)[0][0]
    print(f"{solver:7} {'build (once)':14} {first.build_time_s * 1e3:10.0f} ms")
    cases: dict[str, Callable[[], PlanResult]] = {
        "cold": lambda: planner.plan(base, solver=solver),
        "warm (same)": lambda: planner.plan(base, solver=solver, warm_start=first),
        "warm (+1 deg)": lambda: planner.plan(nearby, solver=solver, warm_start=first),
    }
    for name, fn in cases.items():
        runs = _runs(fn, repeats)
        solve = [r.solve_time_s for r, _ in runs]
        plan = [t for _, t in runs]
        iters = statistics.median(r.iterations for r, _ in runs)
        print(
            f"{solver:7} {name:14} {statistics.median(solve) * 1e3:10.1f} ms "
            f"{min(solve) * 1e3:5.1f} ms {statistics.median(plan) * 1e3:9.1f} ms {iters:6.0f}"
        )


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=21)
    args = parser.parse_args()
    base = load_scenario("slope50")
    nearby = load_scenario("slope50", ["surface.slope_deg=51"])
    print(f"load average before: {_load()} ({os.cpu_count()} cpus)")
    header = (
        f"{'solver':7} {'case':14} {'median solve':>13} {'min':>8} {'median plan':>12} {'iters':>6}"
    )
    print(header)
    print("-" * len(header))
    for solver in ("fatrop", "ipopt"):
        bench_solver(solver, base, nearby, args.repeats)
    print(f"load average after:  {_load()}")


if __name__ == "__main__":
    main()
