"""Planner speed (issue 25 item 1): the 50-degree landing plan, fatrop against the plain
IPOPT statement at N = 100, and the online re-plan, each against its target.

Run: ``.venv/bin/python benchmarks/bench_planner.py [--repeats 21] [--details]``

* **plan**: :meth:`Planner.plan` of the ``slope50`` landing (N = 50, fatrop, cold start
  from the spline reference, the dense re-simulation check included): process CPU time,
  least of the repeats (the compiled solver is reused; its one-off build is printed).
* **fatrop / IPOPT, N = 100**: the NLP solve of the same landing at N = 100 from the
  spline reference with fatrop as the planner runs it, against IPOPT on CasADi's own
  functions of the same statement (the plain ``nlpsol`` use): the ratio of their process
  CPU times, least of the repeats (the wall-time ratio is printed beside it).
* **re-plan**: :meth:`Planner.replan` of the rest of the landing (N = 50 nodes over 2 s)
  from the planned state at t = 2 s with errors of +0.01 rad in phi, -0.01 rad in
  theta_A and +-0.02 rad/s in their rates, warm-started from the plan shifted in time,
  default :class:`ReplanSettings`: the whole call's process CPU time, least of the
  repeats (its wall time beside it).

``--details`` adds the cold/warm table of both solvers and the re-plan variants. The
machine's load average is printed before and after: other jobs on a shared machine
inflate the numbers (compare ratios measured back to back, e.g. with the commit before
checked out beside this one and run with ``PYTHONPATH=<its src>``).
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from tetherland.config import Scenario, load_scenario
from tetherland.planning import (
    CheckScope,
    ManeuverSpec,
    MultipleShooting,
    OcpSolver,
    Planner,
    PlanResult,
    ReplanSettings,
    SolverSettings,
)
from tetherland.planning.planner import trajectory_meta

REPLAN_AT = 2.0
"""Time into the 4 s landing of the re-plan [s]."""
TARGET_PLAN_S = 15e-3
"""Landing plan, verification included, CPU [s]."""
TARGET_RATIO = 0.5
"""fatrop solve / IPOPT solve of the plain statement at N = 100 [-]."""
TARGET_REPLAN_S = 2e-3
"""Warm re-plan of the rest of a landing, N = 50 [s]."""


def _runs(fn: Callable[[], PlanResult], repeats: int) -> list[tuple[PlanResult, float, float]]:
    """(result, wall [s], CPU [s]) of ``repeats`` calls."""
    out = []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        result = fn()
        out.append((result, time.perf_counter() - t0, time.process_time() - c0))
        if not result.success:
            raise SystemExit(f"benchmark plan failed: {result.message}")
    return out


def _verdict(value: float, target: float) -> str:
    return "met" if value <= target else "MISSED"


def headline(repeats: int) -> dict[str, Any]:
    """The three numbers of issue 25 item 1 with their targets."""
    base = load_scenario("slope50")
    planner = Planner()
    first = planner.plan(base)
    runs = _runs(lambda: planner.plan(base), repeats)
    plan_cpu = min(c for _, _, c in runs)
    plan_solve = min(r.solve_time_s for r, _, _ in runs)
    print(
        f"plan (slope50 landing, N = 50, verification included): {plan_cpu * 1e3:6.1f} ms CPU "
        f"(target <= {TARGET_PLAN_S * 1e3:.0f} ms: {_verdict(plan_cpu, TARGET_PLAN_S)}); "
        f"solve {plan_solve * 1e3:.1f} ms, {runs[0][0].iterations} iterations, "
        f"build once {first.build_time_s:.1f} s"
    )
    ratio = solver_ratio(repeats)
    x0 = first.trajectory.state(REPLAN_AT)
    x0[:4] += np.array([0.01, -0.01, 0.02, -0.02])
    settings = ReplanSettings()
    planner.replan(first, x0, REPLAN_AT, nodes=50, settings=settings)
    rs = _runs(lambda: planner.replan(first, x0, REPLAN_AT, nodes=50, settings=settings), repeats)
    replan = min(c for _, _, c in rs)
    print(
        f"re-plan (rest of the landing, N = 50, warm):          {replan * 1e3:6.2f} ms CPU "
        f"(target <= {TARGET_REPLAN_S * 1e3:.0f} ms: {_verdict(replan, TARGET_REPLAN_S)}); "
        f"wall {min(w for _, w, _ in rs) * 1e3:.2f} ms, {rs[0][0].iterations} iterations"
    )
    return {"plan_cpu_s": plan_cpu, "ratio": ratio, "replan_s": replan}


def solver_ratio(repeats: int, nodes: int = 100) -> float:
    """fatrop (as the planner runs it) against IPOPT on CasADi's own functions of the same
    statement: the landing NLP at ``nodes`` intervals from the spline reference; prints
    and returns the ratio of the least solve CPU times."""
    sc = load_scenario("slope50", [f"planner.nodes={nodes}"])
    cfg = sc.planner
    planner = Planner()
    spec = ManeuverSpec.from_scenario(sc)
    problem = planner.problem(sc)
    guess = planner.initial_guess(trajectory_meta(sc, spec), spec, nodes)
    transcription = MultipleShooting(nodes, "rk4", 1)
    cpu, wall, iterations = {}, {}, {}
    for name in ("fatrop", "ipopt"):
        settings = SolverSettings(name, cfg.tolerance, cfg.max_iter, cfg.mu_init)
        solver = OcpSolver(transcription, settings)
        solver.prepare(problem)
        times = []
        for _ in range(repeats):
            c0 = time.process_time()
            sol = solver.solve(problem, guess)
            times.append((time.process_time() - c0, sol.solve_time))
            if not sol.success:
                raise SystemExit(f"benchmark solve failed: {name} {sol.return_status}")
        cpu[name], wall[name] = min(c for c, _ in times), min(w for _, w in times)
        iterations[name] = sol.iterations
    ratio = cpu["fatrop"] / cpu["ipopt"]
    print(
        f"fatrop / IPOPT (plain statement), N = {nodes}:            {ratio:5.2f}x "
        f"(target <= {TARGET_RATIO:g}x: {_verdict(ratio, TARGET_RATIO)}); CPU fatrop "
        f"{cpu['fatrop'] * 1e3:.1f} ms ({iterations['fatrop']} it), IPOPT "
        f"{cpu['ipopt'] * 1e3:.1f} ms ({iterations['ipopt']} it); wall "
        f"{wall['fatrop'] / wall['ipopt']:.2f}x"
    )
    return ratio


def bench_solver(solver: str, base: Scenario, nearby: Scenario, repeats: int) -> None:
    """Print the build time and the cold/warm solve times of one solver."""
    planner = Planner()
    first = planner.plan(base, solver=solver)
    print(f"{solver:7} {'build (once)':14} {first.build_time_s * 1e3:10.0f} ms")
    cases: dict[str, Callable[[], PlanResult]] = {
        "cold": lambda: planner.plan(base, solver=solver),
        "warm (same)": lambda: planner.plan(base, solver=solver, warm_start=first),
        "warm (+1 deg)": lambda: planner.plan(nearby, solver=solver, warm_start=first),
    }
    for name, fn in cases.items():
        runs = _runs(fn, repeats)
        solve = [r.solve_time_s for r, _, _ in runs]
        plan = [c for _, _, c in runs]
        iters = statistics.median(r.iterations for r, _, _ in runs)
        print(
            f"{solver:7} {name:14} {statistics.median(solve) * 1e3:10.1f} ms "
            f"{min(solve) * 1e3:5.1f} ms {min(plan) * 1e3:9.1f} ms {iters:6.0f}"
        )


def bench_replan(base: Scenario, repeats: int) -> None:
    """Print the re-plan times with the settings of plan() and the online settings."""
    planner = Planner()
    landing = planner.plan(base)
    x0 = landing.trajectory.state(REPLAN_AT)
    x0[:4] += np.array([0.01, -0.01, 0.02, -0.02])
    cases = {
        "plan settings, full check": ReplanSettings(
            tol=1e-6, constr_viol_tol=1e-8, max_iter=500, warm_mu_init=1e-4,
            check=CheckScope.RESIMULATION,
        ),
        "online, node check": ReplanSettings(),
        "online, full check": ReplanSettings(check=CheckScope.RESIMULATION),
        "online, CasADi's functions": ReplanSettings(jit=False),
    }  # fmt: skip
    header = (
        f"{'re-plan at t = 2 s, N = 50':30} {'median':>9} {'min':>8} {'cpu':>8} "
        f"{'solve':>8} {'iters':>5}"
    )
    print(header)
    print("-" * len(header))
    for name, settings in cases.items():
        planner.replan(landing, x0, REPLAN_AT, nodes=50, settings=settings)
        runs = _runs(
            lambda s=settings: planner.replan(landing, x0, REPLAN_AT, nodes=50, settings=s),  # type: ignore[misc]
            repeats,
        )
        wall = [w for _, w, _ in runs]
        print(
            f"{name:30} {statistics.median(wall) * 1e3:6.2f} ms {min(wall) * 1e3:5.2f} ms "
            f"{min(c for _, _, c in runs) * 1e3:5.2f} ms "
            f"{min(r.solve_time_s for r, _, _ in runs) * 1e3:5.2f} ms {runs[0][0].iterations:5d}"
        )


def _load() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=21)
    parser.add_argument("--details", action="store_true", help="cold/warm table, re-plan variants")
    args = parser.parse_args()
    print(f"load average before: {_load()} ({os.cpu_count()} cpus)")
    headline(args.repeats)
    if args.details:
        base = load_scenario("slope50")
        nearby = load_scenario("slope50", ["surface.slope_deg=51"])
        print()
        header = (
            f"{'solver':7} {'case':14} {'median solve':>13} {'min':>8} {'min plan cpu':>12} "
            f"{'iters':>6}"
        )
        print(header)
        print("-" * len(header))
        for solver in ("fatrop", "ipopt"):
            bench_solver(solver, base, nearby, args.repeats)
        print()
        bench_replan(base, args.repeats)
    print(f"load average after:  {_load()}")


if __name__ == "__main__":
    main()
