"""The landing/takeoff planner: OCP (6.21) or spline, verified, with a rich result.

>>> from tetherland.config import load_scenario
>>> from tetherland.planning import Planner, Maneuver
>>> planner = Planner()                       # keeps compiled solvers between calls
>>> result = planner.plan(load_scenario("slope50"), Maneuver.LANDING)
>>> result.status.name, result.trajectory.duration
('SOLVED', 4.0)

A result is :attr:`PlanStatus.SOLVED` only when its trajectory passed
:func:`~tetherland.planning.verify.verify` (the fine re-simulation meets the final
conditions, thrust and tension bounds); otherwise ``trajectory`` is None and
``message`` says why.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np

from tetherland.analysis.feasibility import landed_hover_rotor_reason
from tetherland.config import PlannerConfig, Scenario
from tetherland.errors import TetherlandError
from tetherland.geometry import LandingGeometry
from tetherland.planning.maneuver import Maneuver, ManeuverSpec, StateForm, build_ocp, precheck
from tetherland.planning.ocp import OcpProblem
from tetherland.planning.solvers import (
    InitialGuess,
    OcpSolution,
    OcpSolver,
    SolverName,
    SolverSettings,
    SolveStatus,
)
from tetherland.planning.trajectory import (
    PlanarSimulator,
    PolynomialTrajectory,
    ShootingTrajectory,
    Trajectory,
    TrajectoryMeta,
)
from tetherland.planning.transcription import MultipleShooting
from tetherland.planning.verify import Tolerances, Verification, verify

Method = Literal["ocp", "spline"]


class PlanningError(TetherlandError):
    """A plan was requested but could not be produced (one-line message)."""


class PlanStatus(enum.Enum):
    """Outcome of a planning request."""

    SOLVED = "solved"
    """A verified trajectory is available."""
    INFEASIBLE = "infeasible"
    """The maneuver cannot be done within the limits (pre-check, solver or spline check)."""
    MAX_ITER = "max_iter"
    """The solver hit its iteration limit."""
    FAILED = "failed"
    """The solver failed, or its solution did not pass the re-simulation check."""


MAX_REFINEMENTS = 2
"""How often a solution failing the re-simulation is re-solved with twice the integrator
steps per shooting interval."""


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
    verified : bool or None
        Whether the re-simulated solution passed :func:`verify` (None: not checked).
    """

    solver: str
    steps: int
    status: SolveStatus
    return_status: str
    iterations: int
    solve_time_s: float
    build_time_s: float
    verified: bool | None = None


def _totals(attempts: list[Attempt]) -> dict[str, Any]:
    return {
        "solve_time_s": sum(a.solve_time_s for a in attempts),
        "build_time_s": sum(a.build_time_s for a in attempts),
        "iterations": sum(a.iterations for a in attempts),
    }


def _usable(warm: OcpSolution | None, problem: OcpProblem, nodes: int) -> bool:
    return (
        warm is not None
        and warm.structure_key == problem.structure_key
        and warm.X.shape[0] == nodes + 1
        and bool(np.all(np.isfinite(warm.X)))
    )


@dataclass(frozen=True)
class PlanResult:
    """What :meth:`Planner.plan` returns.

    Attributes
    ----------
    status : PlanStatus
    message : str
        Why (one line); ``"ok"`` when solved.
    maneuver : Maneuver
    method : {"ocp", "spline"}
    solver : str or None
        NLP solver (ocp only).
    cost : float or None
        Optimal cost J (ocp only).
    solve_time_s : float
        Wall time of the NLP solve (0 for the spline) [s].
    build_time_s : float
        Time spent building the solver for this call (0 when cached) [s].
    iterations : int
    trajectory : Trajectory or None
        Present only when ``status`` is SOLVED.
    verification : Verification or None
    solution : OcpSolution or None
        Raw output of the last solve (also when not solved: for warm starts and diagnosis).
    spec : ManeuverSpec
    attempts : tuple of Attempt
        Every NLP solve made (fallback solver, integrator refinements), in order;
        ``solve_time_s``, ``build_time_s`` and ``iterations`` are their totals.
    """

    status: PlanStatus
    message: str
    maneuver: Maneuver
    method: str
    solver: str | None
    cost: float | None
    solve_time_s: float
    build_time_s: float
    iterations: int
    trajectory: Trajectory | None
    verification: Verification | None
    solution: OcpSolution | None
    spec: ManeuverSpec
    attempts: tuple[Attempt, ...] = ()

    @property
    def success(self) -> bool:
        return self.status is PlanStatus.SOLVED

    def require(self) -> Trajectory:
        """The trajectory, or :class:`PlanningError` with the reason."""
        if self.status is not PlanStatus.SOLVED or self.trajectory is None:
            raise PlanningError(f"{self.maneuver.value} plan {self.status.value}: {self.message}")
        return self.trajectory

    def summary(self) -> dict[str, Any]:
        """JSON-ready key numbers (``final_error`` etc. are None when unavailable)."""
        v = self.verification
        return {
            "status": self.status.value,
            "message": self.message,
            "maneuver": self.maneuver.value,
            "method": self.method,
            "solver": self.solver,
            "solve_time_s": self.solve_time_s,
            "build_time_s": self.build_time_s,
            "iterations": self.iterations,
            "cost": self.cost,
            "duration_s": self.spec.duration,
            "attempts": [
                {
                    "solver": a.solver,
                    "steps_per_interval": a.steps,
                    "status": a.status.value,
                    "return_status": a.return_status,
                    "iterations": a.iterations,
                    "solve_time_s": a.solve_time_s,
                    "verified": a.verified,
                }
                for a in self.attempts
            ],
            "final_error": None if v is None else dict(v.final_error),
            "min_tension_N": None if v is None else v.min_tension,
            "min_rotor_thrust_N": None if v is None else v.min_rotor_thrust,
            "max_rotor_thrust_N": None if v is None else v.max_rotor_thrust,
            "boundary": {
                "phi_start_deg": math.degrees(self.spec.phi_start),
                "theta_A_start_deg": math.degrees(self.spec.theta_start),
                "phi_final_deg": math.degrees(self.spec.phi_final),
                "theta_A_final_deg": math.degrees(self.spec.theta_final),
            },
        }


_STATUS = {
    SolveStatus.INFEASIBLE: PlanStatus.INFEASIBLE,
    SolveStatus.MAX_ITER: PlanStatus.MAX_ITER,
    SolveStatus.FAILED: PlanStatus.FAILED,
}


def trajectory_meta(scenario: Scenario, spec: ManeuverSpec) -> TrajectoryMeta:
    """The :class:`TrajectoryMeta` of a scenario's maneuver."""
    geo = LandingGeometry.from_scenario(scenario)
    p = spec.params
    return TrajectoryMeta(
        scenario=scenario.name,
        maneuver=spec.maneuver.value,
        mass=p.mass,
        length=p.length,
        inertia_B=np.asarray(scenario.vehicle.inertia, dtype=float),
        allocation=p.allocation,
        heading=p.heading,
        R_WA=geo.R_WA,
        p_A=geo.p_A,
        gravity=p.gravity,
    )


def spline_trajectory(meta: TrajectoryMeta, spec: ManeuverSpec) -> PolynomialTrajectory:
    """The rest-to-rest polynomial reference between the maneuver's boundary outputs."""
    return PolynomialTrajectory(
        meta, spec.duration, (spec.phi_start, spec.phi_final), (spec.theta_start, spec.theta_final)
    )


class Planner:
    """Plans landing and takeoff trajectories; keeps one compiled solver per structure.

    The first OCP plan builds the NLP solver (a few hundred ms); later plans of any
    scenario reuse it. A planner holds mutable caches: use one per thread.

    Parameters
    ----------
    form : {"wrench", "rotor"}
        State coordinates of the OCP (see :func:`build_ocp`).
    tolerances : Tolerances
        Acceptance thresholds of the re-simulation check.
    """

    def __init__(self, form: StateForm = "wrench", tolerances: Tolerances | None = None) -> None:
        self.form: StateForm = form
        self.tolerances = tolerances or Tolerances()
        self._solvers: dict[tuple[MultipleShooting, SolverSettings], OcpSolver] = {}
        self._template: OcpProblem | None = None
        self.simulator = PlanarSimulator()

    def ocp_solver(self, transcription: MultipleShooting, settings: SolverSettings) -> OcpSolver:
        """The cached :class:`OcpSolver` for these settings."""
        key = (transcription, settings)
        if key not in self._solvers:
            self._solvers[key] = OcpSolver(transcription, settings)
        return self._solvers[key]

    def problem(
        self, scenario: Scenario, maneuver: Maneuver | str = Maneuver.LANDING
    ) -> OcpProblem:
        """The OCP (6.21) of a scenario's maneuver (for inspection or custom solving)."""
        return self._problem(ManeuverSpec.from_scenario(scenario, maneuver))

    def _problem(self, spec: ManeuverSpec) -> OcpProblem:
        # The statement holds no numbers: build it once, then only swap the data.
        problem = build_ocp(spec, self.form, self._template)
        self._template = problem
        return problem

    def plan(
        self,
        scenario: Scenario,
        maneuver: Maneuver | str = Maneuver.LANDING,
        *,
        method: Method | None = None,
        solver: SolverName | None = None,
        warm_start: PlanResult | OcpSolution | None = None,
    ) -> PlanResult:
        """Plan ``maneuver`` for ``scenario``.

        Parameters
        ----------
        method, solver
            Override ``scenario.planner.method`` / ``.solver``.
        warm_start
            A previous result (or solution) of a problem with the same structure: its
            nodes (and multipliers with IPOPT) start the solver. Ignored otherwise.
        """
        cfg = scenario.planner
        method = method or cfg.method
        spec = ManeuverSpec.from_scenario(scenario, maneuver)
        meta = trajectory_meta(scenario, spec)
        base = PlanResult(
            status=PlanStatus.FAILED, message="", maneuver=spec.maneuver, method=method,
            solver=None, cost=None, solve_time_s=0.0, build_time_s=0.0, iterations=0,
            trajectory=None, verification=None, solution=None, spec=spec,
        )  # fmt: skip
        reasons = precheck(spec)
        landed = landed_hover_rotor_reason(scenario)
        if landed is not None and not reasons:
            reasons.append(landed)
        if reasons:
            return replace(base, status=PlanStatus.INFEASIBLE, message="; ".join(reasons))
        if method == "spline":
            traj = spline_trajectory(meta, spec)
            return self._accept(base, traj, infeasible_if_bad=True)
        if method != "ocp":
            raise ValueError(f"method must be 'ocp' or 'spline', got {method!r}")
        return self._plan_ocp(base, meta, cfg, solver or cfg.solver, warm_start)

    def _plan_ocp(
        self,
        base: PlanResult,
        meta: TrajectoryMeta,
        cfg: PlannerConfig,
        primary: SolverName,
        warm_start: PlanResult | OcpSolution | None,
    ) -> PlanResult:
        spec = base.spec
        problem = self._problem(spec)
        steps = max(1, math.ceil(spec.duration / (cfg.nodes * cfg.integrator_step) - 1e-9))
        if isinstance(warm_start, PlanResult):
            warm_start = warm_start.solution
        order: list[SolverName] = [primary]
        if cfg.fallback_solver and primary != "ipopt":
            order.append("ipopt")
        attempts: list[Attempt] = []
        last: PlanResult = base
        for name in order:
            settings = SolverSettings(name, cfg.tolerance, cfg.max_iter, cfg.mu_init)
            guess: InitialGuess | OcpSolution
            if _usable(warm_start, problem, cfg.nodes) and name == primary:
                guess = warm_start  # type: ignore[assignment]
            else:
                guess = self.initial_guess(meta, spec, cfg.nodes)
            for refine in range(MAX_REFINEMENTS + 1):
                transcription = MultipleShooting(cfg.nodes, "rk4", steps * 2**refine)
                sol = self.ocp_solver(transcription, settings).solve(problem, guess)
                attempt = Attempt(
                    solver=name, steps=transcription.steps, status=sol.status,
                    return_status=sol.return_status, iterations=sol.iterations,
                    solve_time_s=sol.solve_time, build_time_s=sol.build_time,
                )  # fmt: skip
                last = replace(
                    base, solver=name, cost=sol.cost, solution=sol,
                    **_totals([*attempts, attempt]), attempts=(*attempts, attempt),
                )  # fmt: skip
                if not sol.success:
                    attempts.append(attempt)
                    last = replace(
                        last,
                        status=_STATUS[sol.status],
                        message=f"{name} did not solve the OCP: {sol.return_status} "
                        f"after {sol.iterations} iterations",
                    )
                    break
                traj = ShootingTrajectory.simulate(
                    meta, sol.times, spec.x_start, self._rotor_inputs(spec, sol), self.simulator
                )
                check = verify(traj, spec, self.tolerances)
                attempt = replace(attempt, verified=check.ok)
                attempts.append(attempt)
                last = replace(last, attempts=tuple(attempts), verification=check)
                if check.ok:
                    return replace(last, status=PlanStatus.SOLVED, message="ok", trajectory=traj)
                # A converged solution that fails the fine re-simulation: the shooting
                # integrator was too coarse. Refine it, warm-started from this solution.
                last = replace(
                    last,
                    status=PlanStatus.FAILED,
                    message="re-simulated solution fails its check: " + "; ".join(check.problems),
                )
                guess = sol
        if len(attempts) > 1:
            tried = "; ".join(
                f"{a.solver} (steps {a.steps}): {a.return_status}"
                + (
                    ""
                    if a.verified is None
                    else f", re-simulation {'ok' if a.verified else 'failed'}"
                )
                for a in attempts
            )
            statuses = {a.status for a in attempts}
            status = PlanStatus.INFEASIBLE if statuses == {SolveStatus.INFEASIBLE} else last.status
            return replace(last, status=status, message=f"{last.message} [attempts: {tried}]")
        return last

    def initial_guess(self, meta: TrajectoryMeta, spec: ManeuverSpec, nodes: int) -> InitialGuess:
        """The spline reference at the nodes, in the OCP's state coordinates (cold start)."""
        times = np.linspace(0.0, spec.duration, nodes + 1)
        s = spline_trajectory(meta, spec).sample(times)
        X = s.states()
        GM = spec.params.Gamma_M
        v = s.thrust_accels[:-1] @ GM.T
        if self.form == "wrench":
            X = np.column_stack((X[:, :4], s.thrusts @ GM.T, s.thrust_rates @ GM.T))
        return InitialGuess(X=X, U=v)

    def _rotor_inputs(self, spec: ManeuverSpec, sol: OcpSolution) -> np.ndarray:
        # The OCP input is v = [f_R'', tau_y'']; the rotors' is f'' = G v.
        return sol.U @ spec.params.G.T

    def _accept(self, base: PlanResult, traj: Trajectory, *, infeasible_if_bad: bool) -> PlanResult:
        check = verify(traj, base.spec, self.tolerances)
        if check.ok:
            return replace(
                base, status=PlanStatus.SOLVED, message="ok", trajectory=traj, verification=check
            )
        what = "the spline reference" if infeasible_if_bad else "re-simulated solution"
        return replace(
            base,
            status=PlanStatus.INFEASIBLE if infeasible_if_bad else PlanStatus.FAILED,
            message=f"{what} fails its check: " + "; ".join(check.problems),
            verification=check,
        )


def plan(
    scenario: Scenario,
    maneuver: Maneuver | str = Maneuver.LANDING,
    *,
    method: Method | None = None,
    solver: SolverName | None = None,
    planner: Planner | None = None,
) -> PlanResult:
    """One-shot :meth:`Planner.plan` (pass ``planner`` to reuse compiled solvers)."""
    return (planner or Planner()).plan(scenario, maneuver, method=method, solver=solver)
