"""Solve times of the 50-degree landing OCP (6.21) with fatrop and IPOPT, cold and warm,
and of the online re-plan from a perturbed mid-trajectory state (issue 13 item 5).

Run: ``.venv/bin/python benchmarks/bench_planner.py [--repeats 21] [--no-jit]``

* cold: from the spline initial guess (the compiled solver is reused; its one-off build
  time is printed separately);
* warm (same): warm-started from the previous solution of the same problem;
* warm (+1 deg): warm-started from the 50-degree solution, solving the 51-degree landing.

"solve" is the NLP solver's wall time; "plan" adds building the problem, the fine
re-simulation of the solution and its verification.

Re-plan: :meth:`Planner.replan` of the rest of the landing (N = 50 nodes over 2 s) from
the planned state at t = 2 s with errors of +0.01 rad in phi, -0.01 rad in theta_A and
+-0.02 rad/s in their rates, warm-started from the plan shifted in time. "before" is that
re-plan with the settings of ``plan()`` (tol 1e-6, warm barrier 1e-4, dense re-simulation
check); "after" are the online settings (tol 1e-4, barrier 1e-8, node check), without and
with the NLP functions compiled to C (``jit``). "replan" is the whole call's wall time
(median and least of the repeats), "cpu" its process CPU time, "solve" the NLP solver's
wall time, "build" the one-off construction (and C compilation) of the solver. The
machine's load average is printed before and after: other jobs on a shared machine
inflate the numbers (the least time and the CPU time are less affected).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable

import numpy as np

from tetherland.config import Scenario, load_scenario
from tetherland.planning import CheckScope, Planner, PlanResult, ReplanSettings

REPLAN_AT = 2.0
"""Time into the 4 s landing of the re-plan [s]."""


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


def bench_replan(base: Scenario, repeats: int, jit: bool) -> None:
    """Print the re-plan times before (plan() settings) and after (online settings)."""
    planner = Planner()
    landing = planner.plan(base)
    x0 = landing.trajectory.state(REPLAN_AT)
    x0[:4] += np.array([0.01, -0.01, 0.02, -0.02])
    cases = {
        "before (plan settings, full check)": ReplanSettings(
            tol=1e-6, constr_viol_tol=1e-8, max_iter=500, warm_mu_init=1e-4,
            check=CheckScope.RESIMULATION,
        ),
        "after (online, node check)": ReplanSettings(),
        "after + full check": ReplanSettings(check=CheckScope.RESIMULATION),
    }  # fmt: skip
    if jit:
        cases["after + jit (node check)"] = ReplanSettings(jit=True)
    header = (
        f"{'re-plan at t = 2 s, N = 50':36} {'median replan':>13} {'min':>8} {'cpu':>8} "
        f"{'solve':>8} {'iters':>5} {'build':>8}"
    )
    print(header)
    print("-" * len(header))
    for name, settings in cases.items():
        first = planner.replan(landing, x0, REPLAN_AT, nodes=50, settings=settings)
        if not first.success:
            raise SystemExit(f"benchmark re-plan failed: {first.message}")
        wall, cpu, solve = [], [], []
        for _ in range(repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            result = planner.replan(landing, x0, REPLAN_AT, nodes=50, settings=settings)
            wall.append(time.perf_counter() - t0)
            cpu.append(time.process_time() - c0)
            solve.append(result.solve_time_s)
            if not result.success:
                raise SystemExit(f"benchmark re-plan failed: {result.message}")
        print(
            f"{name:36} {statistics.median(wall) * 1e3:10.2f} ms {min(wall) * 1e3:5.2f} ms "
            f"{statistics.median(cpu) * 1e3:5.2f} ms {statistics.median(solve) * 1e3:5.2f} ms "
            f"{result.iterations:5d} {first.build_time_s:7.1f} s"
        )


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=21)
    parser.add_argument("--no-jit", action="store_true", help="skip the compiled re-plan (20 s)")
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
    print()
    bench_replan(base, max(args.repeats, 51), jit=not args.no_jit)
    print(f"load average after:  {_load()}")


if __name__ == "__main__":
    main()
