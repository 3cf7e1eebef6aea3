"""The one verified-OCP driver: fallback, refinement, attempts, cache; both planners on it."""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np
import pytest

from tetherland.planning import (
    CheckResult,
    MultipleShooting,
    OcpDriver,
    OcpProblem,
    Planner,
    PlanningError,
    PlanResult,
    PlanStatus,
    SolvePolicy,
    SolverSettings,
    VerifiedResult,
)
from tetherland.planning.driver import Candidate, SolveSession
from tetherland.planning.perching import PerchingError, PerchingPlanner, PerchResult, PerchStatus


def double_integrator(v_max: float = np.inf) -> OcpProblem:
    """min int u^2, x'' = u, x(0) = 0, x(T = 1) = [1, 0], x' <= v_max: without the bound
    the optimum is u = 6 - 12 t."""
    x, u, p = ca.SX.sym("x", 2), ca.SX.sym("u"), ca.SX.sym("p", 2)
    t, T, h = ca.SX.sym("t"), ca.SX.sym("T"), ca.SX.sym("h")
    return OcpProblem(
        x=x, u=u, p=p, t=t, T=T, h=h, ode=ca.vertcat(x[1], u), stage_cost=u**2,
        terminal_cost=ca.SX(0), path=x[1], terminal=x - p, duration=1.0,
        x0=np.zeros(2), p_value=np.array([1.0, 0.0]), path_lb=[-np.inf], path_ub=[v_max],
        x_lb=np.full(2, -np.inf), x_ub=np.full(2, np.inf), u_lb=[-np.inf], u_ub=[np.inf],
    )  # fmt: skip


@dataclass(frozen=True)
class StepCheck(CheckResult):
    steps: int


class DoubleIntegratorJob:
    """A toy planner: its check demands ``needed`` RK4 steps per interval (to drive the
    refinement loop) and that the final state is reached."""

    def __init__(self, needed: int = 1, v_max: float = np.inf) -> None:
        self.problem = double_integrator(v_max)
        self.needed = needed
        self.sessions: list[SolveSession] = []

    def candidate(self, session: SolveSession) -> Candidate:
        self.sessions.append(session)
        tr = MultipleShooting(10, "rk4", 1)
        return Candidate(self.problem, tr, session.solve(self.problem, tr, None))

    def accept(self, candidate: Candidate) -> tuple[np.ndarray, StepCheck]:
        sol, steps = candidate.solution, candidate.transcription.steps
        problems = []
        if steps < self.needed:
            problems.append(f"needs {self.needed} steps")
        if not np.allclose(sol.X[-1], [1.0, 0.0], atol=1e-8):
            problems.append("misses the final state")
        return sol.X, StepCheck(problems=tuple(problems), steps=steps)

    def failure_message(self, solution):
        return f"{solution.solver}: {solution.return_status}"


def policy(*solvers: SolverSettings, refinements: int = 2) -> SolvePolicy:
    return SolvePolicy(solvers, refinements)


def test_solved_at_once_with_one_candidate_attempt():
    driver = OcpDriver()
    out = driver.run(DoubleIntegratorJob(), policy(SolverSettings("ipopt", tol=1e-9)))
    assert out.status is PlanStatus.SOLVED and out.message == "ok"
    (a,) = out.attempts
    assert a.candidate and a.verified is True and a.steps == 1 and a.duration == 1.0
    np.testing.assert_allclose(out.trajectory[-1], [1.0, 0.0], atol=1e-8)
    # the compiled solver is cached: the same request builds nothing the second time
    again = driver.run(DoubleIntegratorJob(), policy(SolverSettings("ipopt", tol=1e-9)))
    assert a.build_time_s > 0 and again.attempts[0].build_time_s == 0.0


def test_failed_check_doubles_the_steps_warm_started():
    job = DoubleIntegratorJob(needed=4)
    out = OcpDriver().run(job, policy(SolverSettings("ipopt", tol=1e-9)))
    assert out.status is PlanStatus.SOLVED
    assert [a.steps for a in out.attempts] == [1, 2, 4]
    assert [a.verified for a in out.attempts] == [False, False, True]
    assert out.candidate.transcription.steps == 4
    # the refinements start from the previous solution: far fewer iterations
    assert out.attempts[1].iterations < out.attempts[0].iterations


def test_refinements_run_out_and_fallback_solver_is_tried():
    job = DoubleIntegratorJob(needed=8)
    out = OcpDriver().run(
        job, policy(SolverSettings("fatrop", tol=1e-9), SolverSettings("ipopt", tol=1e-9))
    )
    assert out.status is PlanStatus.FAILED
    assert [(a.solver, a.steps) for a in out.attempts] == [
        ("fatrop", 1), ("fatrop", 2), ("fatrop", 4), ("ipopt", 1), ("ipopt", 2), ("ipopt", 4),
    ]  # fmt: skip
    assert [s.primary for s in job.sessions] == [True, False]
    assert "needs 8 steps" in out.message and "[attempts: fatrop (steps 1)" in out.message
    assert out.verification is not None and not out.verification.ok


def test_unconverged_solve_is_reported_with_the_solver_status():
    job = DoubleIntegratorJob(v_max=1.3)  # the speed bound makes it take a few iterations
    out = OcpDriver().run(job, policy(SolverSettings("ipopt", max_iter=1)))
    assert out.status is PlanStatus.MAX_ITER and out.trajectory is None
    assert out.message == "ipopt: Maximum_Iterations_Exceeded"
    assert out.attempts[0].candidate and out.attempts[0].verified is None


def test_both_planners_are_implementations_of_the_one_driver():
    """One status enum, one result base, one error family, one driver type."""
    assert PerchStatus is PlanStatus
    assert issubclass(PlanResult, VerifiedResult) and issubclass(PerchResult, VerifiedResult)
    assert issubclass(PerchingError, PlanningError)
    assert isinstance(Planner().driver, OcpDriver)
    assert isinstance(PerchingPlanner().driver, OcpDriver)


def test_result_base_totals_and_require():
    out = OcpDriver().run(DoubleIntegratorJob(needed=2), policy(SolverSettings("ipopt")))
    result = VerifiedResult(status=PlanStatus.FAILED, message="")
    result = VerifiedResult(**result.outcome_fields(out))
    assert result.success and result.cost == pytest.approx(12.0, rel=0.05)  # int (6-12t)^2
    assert result.iterations == sum(a.iterations for a in out.attempts)
    assert result.solve_time_s == pytest.approx(sum(a.solve_time_s for a in out.attempts))
    failed = VerifiedResult(status=PlanStatus.INFEASIBLE, message="no way")
    with pytest.raises(PlanningError, match="plan infeasible: no way"):
        failed.require()
