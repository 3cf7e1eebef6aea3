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
only a trajectory that passes is handed out.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import minimize_scalar

from tetherland.config import Scenario
from tetherland.errors import TetherlandError
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
MAX_REFINEMENTS = 2
"""Integrator-step halvings after a failed re-simulation check."""


class PerchingError(TetherlandError):
    """A perching plan was required but none could be made (one-line message)."""


class PerchStatus(enum.Enum):
    """Outcome of a perching plan request."""

    SOLVED = "solved"
    """A verified trajectory is available."""
    INFEASIBLE = "infeasible"
    """No trajectory meets the conditions within the limits (pre-check or solver)."""
    MAX_ITER = "max_iter"
    """The solver hit its iteration limit."""
    FAILED = "failed"
    """The solver failed, or its solution did not pass the re-simulation check."""


_FROM_SOLVE = {
    SolveStatus.INFEASIBLE: PerchStatus.INFEASIBLE,
    SolveStatus.MAX_ITER: PerchStatus.MAX_ITER,
    SolveStatus.FAILED: PerchStatus.FAILED,
}


@dataclass(frozen=True)
class PerchResult:
    """What :meth:`PerchingPlanner.plan` returns.

    Attributes
    ----------
    status : PerchStatus
    message : str
        Why (one line); ``"ok"`` when solved.
    cost : float or None
        Optimal cost J*(T) of the chosen duration (without the time term).
    duration : float or None
        Chosen maneuver duration t_L - t_0 [s].
    solve_time_s : float
        Total NLP solver wall time of this request (all solves) [s].
    build_time_s : float
        Solver construction time (0 when cached) [s].
    iterations : int
        Total solver iterations.
    solves : int
        NLP solves made (search points, fallbacks and refinements).
    solver : str or None
        Solver of the chosen solution.
    trajectory : FreeFlightTrajectory or None
        Present only when SOLVED.
    verification : PerchVerification or None
    solution : OcpSolution or None
        Raw solver output of the chosen (or last) solve.
    spec : PerchSpec
    """

    status: PerchStatus
    message: str
    cost: float | None
    duration: float | None
    solve_time_s: float
    build_time_s: float
    iterations: int
    solves: int
    solver: str | None
    trajectory: FreeFlightTrajectory | None
    verification: PerchVerification | None
    solution: OcpSolution | None
    spec: PerchSpec

    @property
    def success(self) -> bool:
        return self.status is PerchStatus.SOLVED

    def require(self) -> FreeFlightTrajectory:
        """The trajectory, or :class:`PerchingError` with the reason."""
        if self.status is not PerchStatus.SOLVED or self.trajectory is None:
            raise PerchingError(f"perching plan {self.status.value}: {self.message}")
        return self.trajectory

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


@dataclass(frozen=True)
class _Point:
    duration: float
    solution: OcpSolution
    transcription: MultipleShooting
    settings: SolverSettings

    @property
    def objective(self) -> float:
        return self.solution.cost if self.solution.success else math.inf


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
        self._solvers: dict[tuple[MultipleShooting, SolverSettings], OcpSolver] = {}
        self._template: OcpProblem | None = None
        self._log: list[OcpSolution] = []

    def ocp_solver(self, transcription: MultipleShooting, settings: SolverSettings) -> OcpSolver:
        """The cached :class:`OcpSolver` for these settings."""
        key = (transcription, settings)
        if key not in self._solvers:
            self._solvers[key] = OcpSolver(transcription, settings)
        return self._solvers[key]

    def problem(self, spec: PerchSpec, duration: float) -> OcpProblem:
        """The perching OCP of ``spec`` over ``duration`` (statement built once)."""
        self._template = build_perching_ocp(spec, duration, self._template)
        return self._template

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
        cfg, pcfg = scenario.perching, scenario.planner
        duration = cfg.duration if duration is None else duration
        base = PerchResult(
            status=PerchStatus.FAILED, message="", cost=None, duration=None, solve_time_s=0.0,
            build_time_s=0.0, iterations=0, solves=0, solver=None, trajectory=None,
            verification=None, solution=None, spec=spec,
        )  # fmt: skip
        reasons = precheck(spec)
        if reasons:
            return replace(base, status=PerchStatus.INFEASIBLE, message="; ".join(reasons))
        order: list[SolverName] = [solver or pcfg.solver]
        if pcfg.fallback_solver and order[0] != "ipopt":
            order.append("ipopt")
        self._log = []
        result = base
        for name in order:
            settings = SolverSettings(name, pcfg.tolerance, pcfg.max_iter, pcfg.mu_init)
            # One step count for every duration of the request: one compiled solver.
            longest = cfg.max_duration if duration is None else duration
            steps = max(1, math.ceil(longest / (cfg.nodes * cfg.integrator_step) - 1e-9))
            transcription = MultipleShooting(cfg.nodes, "rk4", steps)
            if duration is not None:
                best = self._solve(spec, duration, settings, transcription, None)
            else:
                bounds = (cfg.min_duration, cfg.max_duration)
                best = self._search(spec, settings, transcription, bounds)
            result = self._finish(base, spec, best)
            if result.success:
                break
        return result

    # -- solving -------------------------------------------------------------------------
    def _solve(
        self,
        spec: PerchSpec,
        duration: float,
        settings: SolverSettings,
        transcription: MultipleShooting,
        guess: InitialGuess | None,
    ) -> _Point:
        problem = self.problem(spec, duration)
        sol = self.ocp_solver(transcription, settings).solve(
            problem, guess or cold_guess(spec, duration, transcription.nodes)
        )
        self._log.append(sol)
        return _Point(duration, sol, transcription, settings)

    def _search(
        self,
        spec: PerchSpec,
        settings: SolverSettings,
        transcription: MultipleShooting,
        bounds: tuple[float, float],
    ) -> _Point:
        """Free final time: coarse grid, then a bounded scalar search around the best point."""
        k_time = spec.weights.k_time
        points: dict[float, _Point] = {}

        def evaluate(T: float) -> float:
            if T not in points:
                near = [p for p in points.values() if p.solution.success]
                guess = None
                if near:
                    closest = min(near, key=lambda p: abs(p.duration - T))
                    guess = _rescaled(closest.solution, T)
                points[T] = self._solve(spec, T, settings, transcription, guess)
            return points[T].objective + k_time * T

        grid = np.geomspace(bounds[0], bounds[1], GRID)[::-1]  # long (easy) first
        values = [evaluate(float(T)) for T in grid]
        i = int(np.argmin(values))
        if not math.isfinite(values[i]):
            return points[float(grid[0])]  # nothing solved: report the longest (easiest) try
        lo = float(grid[min(i + 1, GRID - 1)])
        hi = float(grid[max(i - 1, 0)])
        if hi > lo:
            minimize_scalar(
                evaluate, bounds=(lo, hi), method="bounded", options={"xatol": SEARCH_TOL}
            )
        return min(points.values(), key=lambda p: p.objective + k_time * p.duration)

    def _finish(self, base: PerchResult, spec: PerchSpec, best: _Point) -> PerchResult:
        meta = FreeFlightMeta.from_spec(spec)
        point = best
        for refine in range(MAX_REFINEMENTS + 1):
            sol = point.solution
            result = self._totals(base, point)
            if not sol.success:
                return replace(
                    result,
                    status=_FROM_SOLVE[sol.status],
                    message=self._failure_message(spec, point),
                )
            traj = FreeFlightTrajectory.simulate(meta, sol.times, spec.x_start, sol.U)
            check = verify_perch(traj, spec, self.tolerances)
            result = replace(result, verification=check)
            if check.ok:
                return replace(result, status=PerchStatus.SOLVED, message="ok", trajectory=traj)
            if refine == MAX_REFINEMENTS:
                return replace(
                    result,
                    status=PerchStatus.FAILED,
                    message="re-simulated solution fails its check: " + "; ".join(check.problems),
                )
            # The shooting integrator was too coarse: halve its step, warm-started.
            steps = point.transcription.steps * 2
            transcription = MultipleShooting(point.transcription.nodes, "rk4", steps)
            problem = self.problem(spec, point.duration)
            guess = InitialGuess(X=sol.X, U=sol.U)
            new = self.ocp_solver(transcription, point.settings).solve(problem, guess)
            self._log.append(new)
            point = _Point(point.duration, new, transcription, point.settings)
        raise AssertionError("unreachable")  # pragma: no cover

    def _totals(self, base: PerchResult, point: _Point) -> PerchResult:
        sol = point.solution
        return replace(
            base,
            cost=sol.cost if sol.success else None,
            duration=point.duration,
            solve_time_s=sum(s.solve_time for s in self._log),
            build_time_s=sum(s.build_time for s in self._log),
            iterations=sum(s.iterations for s in self._log),
            solves=len(self._log),
            solver=sol.solver,
            solution=sol,
        )

    def _failure_message(self, spec: PerchSpec, point: _Point) -> str:
        sol = point.solution
        what = (
            f"cannot reach z_B = z_S at the landing point with rotor limits "
            f"[{spec.f_lo:g}, {spec.f_hi:g}] N per rotor"
        )
        if sol.status is SolveStatus.INFEASIBLE:
            return f"infeasible: {what} ({sol.solver}: {sol.return_status})"
        return (
            f"{sol.solver} found no perching trajectory ({sol.return_status} after "
            f"{sol.iterations} iterations); possibly {what}"
        )


def plan_perching(
    scenario: Scenario, *, planner: PerchingPlanner | None = None, **kwargs: Any
) -> PerchResult:
    """One-shot :meth:`PerchingPlanner.plan` (pass ``planner`` to reuse compiled solvers)."""
    return (planner or PerchingPlanner()).plan(scenario, **kwargs)
