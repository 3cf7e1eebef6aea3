"""One verified-OCP driver for every planner: solve, fall back, refine, verify, report.

A planner *states* its problem (an :class:`~tetherland.planning.ocp.OcpProblem`) and says
how a solution becomes a trajectory and how that is judged; the *solving* is the same for
every planner and lives here (rockit's split of the problem statement from the method):

* :class:`OcpDriver` keeps one :class:`~tetherland.planning.solvers.OcpSolver` per
  (transcription, solver settings), each caching its compiled NLP solver per problem
  structure: later requests only change numbers.
* For each solver of the :class:`SolvePolicy` in turn (the primary, then IPOPT as the
  fallback) the planner's :meth:`VerifiedOcp.candidate` makes its solve(s) through a
  :class:`SolveSession` (one solve, or a search over the duration) and returns the
  candidate solution.
* A converged candidate is re-simulated and checked (:meth:`VerifiedOcp.accept`). When
  the check fails, the shooting integrator was too coarse: the same problem is solved
  again with twice the RK4 steps per interval, warm-started from the candidate, at most
  :data:`MAX_REFINEMENTS` times.
* The :class:`OcpOutcome` carries a :class:`PlanStatus`, a one-line message and every
  :class:`Attempt`; the planners return it as their :class:`VerifiedResult` subclass
  (``PlanResult``, ``PerchResult``).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar, Generic, Protocol, TypeVar

import numpy as np

from tetherland.config import PlannerConfig
from tetherland.errors import TetherlandError
from tetherland.planning.checks import CheckResult
from tetherland.planning.ocp import OcpProblem
from tetherland.planning.solvers import (
    InitialGuess,
    OcpSolution,
    OcpSolver,
    SolverName,
    SolverSettings,
    SolveStatus,
)
from tetherland.planning.transcription import MultipleShooting

MAX_REFINEMENTS = 2
"""How often a solution failing the re-simulation check is solved again with twice the
integrator steps per shooting interval."""


class PlanningError(TetherlandError):
    """A plan was required but could not be produced (one-line message)."""


class PlanStatus(enum.Enum):
    """Outcome of a planning request (every planner)."""

    SOLVED = "solved"
    """A verified trajectory is available."""
    INFEASIBLE = "infeasible"
    """The maneuver cannot be done within the limits (pre-check, solver or spline check)."""
    MAX_ITER = "max_iter"
    """The solver hit its iteration limit."""
    FAILED = "failed"
    """The solver failed, or its solution did not pass the re-simulation check."""


PLAN_STATUS_OF_SOLVE = {
    SolveStatus.SUCCESS: PlanStatus.SOLVED,
    SolveStatus.INFEASIBLE: PlanStatus.INFEASIBLE,
    SolveStatus.MAX_ITER: PlanStatus.MAX_ITER,
    SolveStatus.FAILED: PlanStatus.FAILED,
}
"""The plan status of a request whose last solve ended with this NLP status."""


@dataclass(frozen=True)
class Attempt:
    """One NLP solve made for a plan.

    Attributes
    ----------
    solver : str
    steps : int
        RK4 steps per shooting interval.
    status : SolveStatus
    return_status : str
        The solver's own status.
    iterations : int
    solve_time_s, build_time_s : float
        Solver wall time and solver construction time (0 when cached) [s].
    duration : float
        Horizon T of the solved problem [s].
    candidate : bool
        Whether the driver took this solve as a candidate (or a refinement of one);
        False for the other points of a search.
    verified : bool or None
        Whether the re-simulated solution passed its check (None: not checked).
    """

    solver: str
    steps: int
    status: SolveStatus
    return_status: str
    iterations: int
    solve_time_s: float
    build_time_s: float
    duration: float = float("nan")
    candidate: bool = False
    verified: bool | None = None

    def to_json(self) -> dict[str, Any]:
        return {
            "solver": self.solver,
            "steps_per_interval": self.steps,
            "status": self.status.value,
            "return_status": self.return_status,
            "iterations": self.iterations,
            "solve_time_s": self.solve_time_s,
            "verified": self.verified,
        }

    def describe(self) -> str:
        """``fatrop (steps 2): Success (...), re-simulation failed``."""
        text = f"{self.solver} (steps {self.steps}): {self.return_status}"
        if self.verified is not None:
            text += f", re-simulation {'ok' if self.verified else 'failed'}"
        return text


@dataclass(frozen=True)
class Candidate:
    """A solution the driver is to check: the problem, how it was solved, the result."""

    problem: OcpProblem
    transcription: MultipleShooting
    solution: OcpSolution


class SolveSession:
    """The solves of one request with one solver; records every :class:`Attempt`.

    A planner's :meth:`VerifiedOcp.candidate` solves through :meth:`solve`.
    """

    def __init__(
        self, driver: OcpDriver, settings: SolverSettings, primary: bool, log: list[Attempt]
    ) -> None:
        self.driver = driver
        self.settings = settings
        self.primary = primary
        self._log = log
        self._index: dict[int, int] = {}

    @property
    def name(self) -> str:
        return self.settings.name

    def solve(
        self,
        problem: OcpProblem,
        transcription: MultipleShooting,
        guess: InitialGuess | OcpSolution | None,
        warm: bool | None = None,
    ) -> OcpSolution:
        """Solve ``problem`` (a warm start when ``guess`` is a previous solution, or when
        ``warm`` says so: see :meth:`OcpSolver.solve`)."""
        sol = self.driver.ocp_solver(transcription, self.settings).solve(problem, guess, warm)
        self._index[id(sol)] = len(self._log)
        attempt = Attempt(
            solver=sol.solver, steps=transcription.steps, status=sol.status,
            return_status=sol.return_status, iterations=sol.iterations,
            solve_time_s=sol.solve_time, build_time_s=sol.build_time, duration=problem.duration,
        )  # fmt: skip
        self._log.append(attempt)
        return sol

    def mark(self, sol: OcpSolution, verified: bool | None = None) -> None:
        """Record that ``sol`` is a candidate (and whether its check passed)."""
        i = self._index[id(sol)]
        self._log[i] = replace(self._log[i], candidate=True, verified=verified)


TrajT = TypeVar("TrajT")
CheckT = TypeVar("CheckT", bound=CheckResult)


class VerifiedOcp(Protocol[TrajT, CheckT]):
    """What a planner supplies to :meth:`OcpDriver.run` for one request."""

    def candidate(self, session: SolveSession) -> Candidate:
        """Make the solve(s) with ``session`` and return the solution to check."""
        ...

    def accept(self, candidate: Candidate) -> tuple[TrajT, CheckT]:
        """The trajectory of a converged candidate and its check."""
        ...

    def failure_message(self, solution: OcpSolution) -> str:
        """One line saying why a solve that did not converge failed."""
        ...


@dataclass(frozen=True)
class SolvePolicy:
    """Which solvers the driver tries, in order, and how often it refines.

    Attributes
    ----------
    solvers : tuple of SolverSettings
        The primary solver first, then the fallbacks.
    max_refinements : int
        Integrator-step doublings after a failed re-simulation check (0: none).
    """

    solvers: tuple[SolverSettings, ...]
    max_refinements: int = MAX_REFINEMENTS

    def __post_init__(self) -> None:
        if not self.solvers:
            raise ValueError("a solve policy needs at least one solver")
        if self.max_refinements < 0:
            raise ValueError(f"max_refinements must be >= 0, got {self.max_refinements}")

    @classmethod
    def from_config(cls, cfg: PlannerConfig, solver: SolverName | None = None) -> SolvePolicy:
        """``planner.solver`` (or ``solver``), then IPOPT when ``planner.fallback_solver``."""
        primary: SolverName = solver or cfg.solver
        names: list[SolverName] = [primary]
        if cfg.fallback_solver and primary != "ipopt":
            names.append("ipopt")
        return cls(
            tuple(SolverSettings(n, cfg.tolerance, cfg.max_iter, cfg.mu_init) for n in names)
        )


@dataclass(frozen=True)
class OcpOutcome(Generic[TrajT, CheckT]):
    """What :meth:`OcpDriver.run` found.

    Attributes
    ----------
    status : PlanStatus
    message : str
        ``"ok"`` when solved, otherwise why (with the attempts when there were several).
    candidate : Candidate or None
        The last candidate checked or failed.
    trajectory : TrajT or None
        Present only when solved.
    verification : CheckT or None
        The check of the last candidate that converged (None when it did not).
    attempts : tuple of Attempt
    """

    status: PlanStatus
    message: str
    candidate: Candidate | None
    trajectory: TrajT | None
    verification: CheckT | None
    attempts: tuple[Attempt, ...]


class OcpDriver:
    """Solves, falls back, refines and verifies; keeps the compiled solvers.

    A driver holds mutable caches: use one per thread (each planner owns one).
    """

    def __init__(self) -> None:
        self._solvers: dict[tuple[MultipleShooting, SolverSettings], OcpSolver] = {}

    def ocp_solver(self, transcription: MultipleShooting, settings: SolverSettings) -> OcpSolver:
        """The cached :class:`OcpSolver` for these settings."""
        key = (transcription, settings)
        if key not in self._solvers:
            self._solvers[key] = OcpSolver(transcription, settings)
        return self._solvers[key]

    def run(
        self, job: VerifiedOcp[TrajT, CheckT], policy: SolvePolicy
    ) -> OcpOutcome[TrajT, CheckT]:
        """Try the policy's solvers in turn until a candidate passes its check."""
        log: list[Attempt] = []
        outcome: OcpOutcome[TrajT, CheckT] | None = None
        for i, settings in enumerate(policy.solvers):
            session = SolveSession(self, settings, i == 0, log)
            outcome = self._check(job, session, job.candidate(session), policy.max_refinements)
            if outcome.status is PlanStatus.SOLVED:
                return replace(outcome, attempts=tuple(log))
        assert outcome is not None
        tried = [a for a in log if a.candidate]
        message = outcome.message
        if len(tried) > 1:
            message += " [attempts: " + "; ".join(a.describe() for a in tried) + "]"
        return replace(outcome, message=message, attempts=tuple(log))

    def _check(
        self,
        job: VerifiedOcp[TrajT, CheckT],
        session: SolveSession,
        candidate: Candidate,
        max_refinements: int,
    ) -> OcpOutcome[TrajT, CheckT]:
        for refine in range(max_refinements + 1):
            sol = candidate.solution
            if not sol.success:
                session.mark(sol)
                return OcpOutcome(
                    PLAN_STATUS_OF_SOLVE[sol.status], job.failure_message(sol), candidate,
                    None, None, (),
                )  # fmt: skip
            trajectory, check = job.accept(candidate)
            session.mark(sol, check.ok)
            if check.ok:
                return OcpOutcome(PlanStatus.SOLVED, "ok", candidate, trajectory, check, ())
            failed: OcpOutcome[TrajT, CheckT] = OcpOutcome(
                PlanStatus.FAILED,
                "re-simulated solution fails its check: " + "; ".join(check.problems),
                candidate, None, check, (),
            )  # fmt: skip
            if refine == max_refinements:
                return failed
            # A converged solution that fails the fine re-simulation: the shooting
            # integrator was too coarse. Refine it, warm-started from this solution.
            steps = 2 * candidate.transcription.steps
            transcription = replace(candidate.transcription, steps=steps)
            new = session.solve(candidate.problem, transcription, sol)
            candidate = Candidate(candidate.problem, transcription, new)
        raise AssertionError("unreachable")  # pragma: no cover


def usable_warm_start(warm: OcpSolution | None, problem: OcpProblem, nodes: int) -> bool:
    """Whether ``warm`` can start a solve of ``problem`` at ``nodes`` intervals."""
    return (
        warm is not None
        and warm.structure_key == problem.structure_key
        and warm.X.shape[0] == nodes + 1
        and bool(np.all(np.isfinite(warm.X)))
    )


@dataclass(frozen=True, kw_only=True)
class VerifiedResult(Generic[TrajT, CheckT]):
    """Base of the planners' results: status, why, the trajectory and its check.

    Attributes
    ----------
    status : PlanStatus
    message : str
        Why (one line); ``"ok"`` when solved.
    solver : str or None
        NLP solver of the last candidate.
    cost : float or None
        Optimal cost J of the last candidate when its solve converged.
    trajectory : TrajT or None
        Present only when ``status`` is SOLVED.
    verification : CheckT or None
        The check of the last converged candidate.
    solution : OcpSolution or None
        Raw output of the last candidate's solve (also when not solved: for warm starts
        and diagnosis).
    attempts : tuple of Attempt
        Every NLP solve made, in order; ``solve_time_s``, ``build_time_s`` and
        ``iterations`` are their totals.
    """

    status: PlanStatus
    message: str
    solver: str | None = None
    cost: float | None = None
    trajectory: TrajT | None = None
    verification: CheckT | None = None
    solution: OcpSolution | None = field(default=None, repr=False)
    attempts: tuple[Attempt, ...] = ()

    error: ClassVar[type[PlanningError]] = PlanningError

    @property
    def success(self) -> bool:
        return self.status is PlanStatus.SOLVED

    @property
    def solve_time_s(self) -> float:
        """Total NLP solver wall time of the request [s]."""
        return sum(a.solve_time_s for a in self.attempts)

    @property
    def build_time_s(self) -> float:
        """Total solver construction time of the request (0 when all were cached) [s]."""
        return sum(a.build_time_s for a in self.attempts)

    @property
    def iterations(self) -> int:
        """Total solver iterations of the request."""
        return sum(a.iterations for a in self.attempts)

    def _label(self) -> str:
        return "plan"

    def require(self) -> TrajT:
        """The trajectory, or :attr:`error` (a :class:`PlanningError`) with the reason."""
        if self.status is not PlanStatus.SOLVED or self.trajectory is None:
            raise self.error(f"{self._label()} {self.status.value}: {self.message}")
        return self.trajectory

    def outcome_fields(self, outcome: OcpOutcome[TrajT, CheckT]) -> dict[str, Any]:
        """The base fields of a result from a driver outcome (for ``replace``)."""
        sol = None if outcome.candidate is None else outcome.candidate.solution
        return {
            "status": outcome.status,
            "message": outcome.message,
            "solver": None if sol is None else sol.solver,
            "cost": sol.cost if sol is not None and sol.success else None,
            "trajectory": outcome.trajectory,
            "verification": outcome.verification,
            "solution": sol,
            "attempts": outcome.attempts,
        }
