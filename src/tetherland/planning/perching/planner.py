"""The contact-free perching planner: fixed or free final time, verified, rich result.

>>> from tetherland.config import load_scenario
>>> from tetherland.planning.perching import PerchingPlanner
>>> result = PerchingPlanner().plan(load_scenario("slope50", ["surface.slope_deg=20"]))
>>> result.status.name
'SOLVED'

The OCP of :mod:`.problem` is solved with the shared :class:`OcpSolver` (fatrop, IPOPT as
fallback). Free final time: the duration T minimises J*(T) + k_time T over
[``min_duration``, ``max_duration``], J*(T) the optimal cost of the fixed-time OCP,
found on a coarse grid and refined by Brent's bounded search (each solve warm-started
from the nearest one). The chosen solution is re-simulated with fine RK4 steps from the
initial state (:meth:`FreeFlightTrajectory.simulate`) and checked (:func:`verify_perch`);
only a trajectory that passes is handed out. Solving, fallback, refinement and the result
record are the shared :mod:`tetherland.planning.driver`'s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from tetherland.config import PerchingConfig, Scenario
from tetherland.planning.driver import (
    Candidate,
    OcpDriver,
    PlanningError,
    PlanStatus,
    SolvePolicy,
    SolveSession,
    VerifiedResult,
)
from tetherland.planning.ocp import OcpProblem
from tetherland.planning.perching.model import PerchSpec
from tetherland.planning.perching.problem import build_perching_ocp
from tetherland.planning.perching.trajectory import FreeFlightMeta, FreeFlightTrajectory
from tetherland.planning.perching.verify import PerchTolerances, PerchVerification, verify_perch
from tetherland.planning.solvers import (
    InitialGuess,
    OcpSolution,
    OcpSolver,
    SolverName,
    SolverSettings,
    SolveStatus,
)
from tetherland.planning.spline import rest_to_rest
from tetherland.planning.transcription import MultipleShooting

GRID = 4
"""Durations tried on the coarse grid of the free-final-time search."""
SEARCH_TOL = 0.05
"""Absolute tolerance on the duration of the bounded scalar search [s]."""


class PerchingError(PlanningError):
    """A perching plan was required but none could be made (one-line message)."""


PerchStatus = PlanStatus
"""Outcome of a perching plan request: the planners' one :class:`PlanStatus`."""


@dataclass(frozen=True, kw_only=True)
class PerchResult(VerifiedResult[FreeFlightTrajectory, PerchVerification]):
    """What :meth:`PerchingPlanner.plan` returns.

    The fields of :class:`~tetherland.planning.driver.VerifiedResult` (``cost`` is
    J*(T) of the chosen duration, without the time term; ``attempts`` holds every search
    point, fallback and refinement) and:

    Attributes
    ----------
    spec : PerchSpec
    duration : float or None
        Chosen maneuver duration t_L - t_0 [s] (None when no solve was made).
    """

    spec: PerchSpec
    duration: float | None = None

    error = PerchingError

    @property
    def solves(self) -> int:
        """NLP solves made (search points, fallbacks and refinements)."""
        return len(self.attempts)

    def _label(self) -> str:
        return "perching plan"

    def summary(self) -> dict[str, Any]:
        """JSON-ready key numbers."""
        v = self.verification
        return {
            "status": self.status.value,
            "message": self.message,
            "cost": self.cost,
            "duration_s": self.duration,
            "solve_time_s": self.solve_time_s,
            "build_time_s": self.build_time_s,
            "iterations": self.iterations,
            "solves": self.solves,
            "solver": self.solver,
            "approach_speed_mps": self.spec.approach_speed,
            "verification": None if v is None else v.to_dict(),
        }


def precheck(spec: PerchSpec) -> list[str]:
    """Reasons why the request is infeasible before any solve (empty: none found)."""
    reasons = []
    mg = spec.mass * spec.gravity
    per_rotor = spec.G @ np.array([mg, 0.0])
    cannot_hover = bool(per_rotor.max() > spec.f_hi + 1e-9)
    if cannot_hover:
        reasons.append(
            f"infeasible: the rotors cannot hover: m g = {mg:.2f} N needs {per_rotor.max():.2f} N "
            f"per rotor > f_max - control_margin = {spec.f_hi:g} N"
        )
    touch = spec.G @ np.array([spec.f_R_final, 0.0])
    if touch.min() < spec.f_lo - 1e-9:
        reasons.append(
            f"infeasible: cannot reach z_B = z_S with rotor limits: the touchdown thrust "
            f"m g cos(beta) = {spec.f_R_final:.2f} N is {touch.min():.2f} N per rotor < "
            f"f_min + control_margin = {spec.f_lo:g} N (slope too steep)"
        )
    if abs(spec.beta) > spec.max_pitch:
        reasons.append(
            f"infeasible: the slope {math.degrees(spec.beta):.1f} deg exceeds "
            f"perching.max_pitch_deg = {math.degrees(spec.max_pitch):g} deg"
        )
    start = spec.x_start
    if abs(start[2]) > spec.max_pitch:
        reasons.append("infeasible: the start pitch exceeds perching.max_pitch_deg")
    f0 = spec.rotor_thrusts(start)[0]
    hover_start = np.allclose(start[6:], [mg, 0.0, 0.0, 0.0])
    if (f0.min() < spec.f_lo - 1e-9 or f0.max() > spec.f_hi + 1e-9) and not (
        hover_start and cannot_hover
    ):
        reasons.append(
            f"infeasible: the start rotor thrusts {f0.min():.2f}..{f0.max():.2f} N leave "
            f"[{spec.f_lo:g}, {spec.f_hi:g}] N"
        )
    clear = spec.clearances(start)[0].min()
    if clear < spec.clearance_margin:
        reasons.append(
            f"infeasible: the start point is {clear:.3f} m above the surface (the landers and "
            f"rotor guards need {spec.clearance_margin:g} m)"
        )
    return reasons


def cold_guess(spec: PerchSpec, duration: float, nodes: int) -> InitialGuess:
    """Rest-to-rest polynomials from the start to the landed pose, hover thrust."""
    t = np.linspace(0.0, duration, nodes + 1)
    X = np.zeros((nodes + 1, 10))
    for i in range(2):
        y = rest_to_rest(spec.x_start[i], spec.p_landed[i], duration, t, 1)
        X[:, i], X[:, 3 + i] = y[0], y[1]
    th = rest_to_rest(spec.x_start[2], spec.beta, duration, t, 1)
    X[:, 2], X[:, 5] = th[0], th[1]
    X[:, 6] = spec.mass * spec.gravity
    return InitialGuess(X=X, U=np.zeros((nodes, 2)))


def _rescaled(sol: OcpSolution, duration: float) -> InitialGuess:
    """A solution of another duration as a guess: same node values, rates rescaled."""
    r = sol.times[-1] / duration
    X = sol.X.copy()
    X[:, 3:6] *= r
    X[:, 8:10] *= r
    return InitialGuess(X=X, U=sol.U * r * r)


def _objective(candidate: Candidate) -> float:
    sol = candidate.solution
    return sol.cost if sol.success else math.inf


class _PerchOcp:
    """The perching OCP of one request (fixed or free final time), for the driver."""

    def __init__(
        self, planner: PerchingPlanner, spec: PerchSpec, cfg: PerchingConfig, duration: float | None
    ) -> None:
        self.planner, self.spec, self.cfg, self.duration = planner, spec, cfg, duration
        self.meta = FreeFlightMeta.from_spec(spec)
        # One step count for every duration of the request: one compiled solver.
        longest = cfg.max_duration if duration is None else duration
        steps = max(1, math.ceil(longest / (cfg.nodes * cfg.integrator_step) - 1e-9))
        self.transcription = MultipleShooting(cfg.nodes, "rk4", steps)

    def candidate(self, session: SolveSession) -> Candidate:
        if self.duration is not None:
            return self._solve(session, self.duration, None)
        return self._search(session, (self.cfg.min_duration, self.cfg.max_duration))

    def _solve(
        self, session: SolveSession, duration: float, guess: InitialGuess | None
    ) -> Candidate:
        problem = self.planner.problem(self.spec, duration)
        guess = guess or cold_guess(self.spec, duration, self.transcription.nodes)
        sol = session.solve(problem, self.transcription, guess)
        return Candidate(problem, self.transcription, sol)

    def _search(self, session: SolveSession, bounds: tuple[float, float]) -> Candidate:
        """Free final time: coarse grid, then a bounded scalar search around the best point."""
        k_time = self.spec.weights.k_time
        points: dict[float, Candidate] = {}

        def evaluate(T: float) -> float:
            if T not in points:
                near = [p for p in points.values() if p.solution.success]
                guess = None
                if near:
                    closest = min(near, key=lambda p: abs(p.problem.duration - T))
                    guess = _rescaled(closest.solution, T)
                points[T] = self._solve(session, T, guess)
            return _objective(points[T]) + k_time * T

        grid = np.geomspace(bounds[0], bounds[1], GRID)[::-1]  # long (easy) first
        values = [evaluate(float(T)) for T in grid]
        i = int(np.argmin(values))
        if not math.isfinite(values[i]):
            return points[float(grid[0])]  # nothing solved: report the longest (easiest) try
        lo = float(grid[min(i + 1, GRID - 1)])
        hi = float(grid[max(i - 1, 0)])
        if hi > lo:
            from scipy.optimize import minimize_scalar  # 0.5 s to import: only when needed

            minimize_scalar(
                evaluate, bounds=(lo, hi), method="bounded", options={"xatol": SEARCH_TOL}
            )
        return min(points.values(), key=lambda p: _objective(p) + k_time * p.problem.duration)

    def accept(self, candidate: Candidate) -> tuple[FreeFlightTrajectory, PerchVerification]:
        sol = candidate.solution
        traj = FreeFlightTrajectory.simulate(self.meta, sol.times, self.spec.x_start, sol.U)
        return traj, verify_perch(traj, self.spec, self.planner.tolerances)

    def failure_message(self, solution: OcpSolution) -> str:
        spec = self.spec
        what = (
            f"cannot reach z_B = z_S at the landing point with rotor limits "
            f"[{spec.f_lo:g}, {spec.f_hi:g}] N per rotor"
        )
        if solution.status is SolveStatus.INFEASIBLE:
            return f"infeasible: {what} ({solution.solver}: {solution.return_status})"
        return (
            f"{solution.solver} found no perching trajectory ({solution.return_status} after "
            f"{solution.iterations} iterations); possibly {what}"
        )


class PerchingPlanner:
    """Plans contact-free perching maneuvers; keeps compiled solvers between calls.

    Parameters
    ----------
    tolerances : PerchTolerances
        Acceptance thresholds of the re-simulation check.

    A planner holds mutable caches: use one per thread.
    """

    def __init__(self, tolerances: PerchTolerances | None = None) -> None:
        self.tolerances = tolerances or PerchTolerances()
        self.driver = OcpDriver()
        self._templates: dict[bool, OcpProblem] = {}
        """The statements built so far, drag-free (False) and with rotor drag (True)."""

    def ocp_solver(self, transcription: MultipleShooting, settings: SolverSettings) -> OcpSolver:
        """The cached :class:`OcpSolver` for these settings."""
        return self.driver.ocp_solver(transcription, settings)

    def problem(self, spec: PerchSpec, duration: float) -> OcpProblem:
        """The perching OCP of ``spec`` over ``duration`` (each statement built once)."""
        drag = spec.rotor_drag > 0.0
        problem = build_perching_ocp(spec, duration, self._templates.get(drag))
        self._templates[drag] = problem
        return problem

    def plan(
        self,
        scenario: Scenario,
        *,
        start: ArrayLike | None = None,
        duration: float | None = None,
        approach_speed: float | None = None,
        solver: SolverName | None = None,
    ) -> PerchResult:
        """Plan the perching maneuver of ``scenario``.

        Parameters
        ----------
        start : (10,) array, optional
            Initial planar extended state (see :class:`PerchSpec`); default: the hover
            start of ``[perching]``.
        duration : float, optional
            Fixed duration [s]; default ``perching.duration``, and when that is None the
            free-final-time search.
        approach_speed : float, optional
            Overrides ``perching.approach_speed`` [m/s].
        solver : {"fatrop", "ipopt"}, optional
            Overrides ``planner.solver``.
        """
        spec = PerchSpec.from_scenario(scenario, start, approach_speed)
        cfg = scenario.perching
        duration = cfg.duration if duration is None else duration
        base = PerchResult(status=PlanStatus.FAILED, message="", spec=spec)
        reasons = precheck(spec)
        if reasons:
            return replace(base, status=PlanStatus.INFEASIBLE, message="; ".join(reasons))
        job = _PerchOcp(self, spec, cfg, duration)
        outcome = self.driver.run(job, SolvePolicy.from_config(scenario.planner, solver))
        chosen = outcome.candidate
        return replace(
            base, **base.outcome_fields(outcome),
            duration=None if chosen is None else chosen.problem.duration,
        )  # fmt: skip


def plan_perching(
    scenario: Scenario, *, planner: PerchingPlanner | None = None, **kwargs: Any
) -> PerchResult:
    """One-shot :meth:`PerchingPlanner.plan` (pass ``planner`` to reuse compiled solvers)."""
    return (planner or PerchingPlanner()).plan(scenario, **kwargs)
