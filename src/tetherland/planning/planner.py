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
``message`` says why. Solving, fallback, refinement and the result base are the shared
:mod:`~tetherland.planning.driver`'s; this module states the maneuver's OCP job.

Online re-planning (receding horizon): :meth:`Planner.replan` plans the rest of the
maneuver from the current state on the same compiled solver, warm-started from the plan
being flown, and by default checks only the solver's nodes
(:func:`~tetherland.planning.verify.verify_nodes`; ``verification.scope`` says so):

>>> x = result.trajectory.state(2.0)          # mid-way, with an error in phi
>>> x[0] += 0.01
>>> rest = planner.replan(result, x, elapsed=2.0)
>>> rest.status.name, rest.verification.scope.value, rest.spec.duration
('SOLVED', 'nodes', 2.0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike

from tetherland.analysis.feasibility import landed_hover_rotor_reason
from tetherland.config import Scenario
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.planning.checks import CheckScope
from tetherland.planning.driver import (
    MAX_REFINEMENTS,
    Attempt,
    Candidate,
    OcpDriver,
    PlanningError,
    PlanStatus,
    SolvePolicy,
    SolveSession,
    VerifiedResult,
    usable_warm_start,
)
from tetherland.planning.maneuver import (
    Maneuver,
    ManeuverSpec,
    StateForm,
    build_ocp,
    precheck,
    remainder_ocp,
    statement_key,
)
from tetherland.planning.ocp import OcpProblem
from tetherland.planning.solvers import (
    InitialGuess,
    OcpSolution,
    OcpSolver,
    SolverName,
    SolverSettings,
)
from tetherland.planning.trajectory import (
    PlanarSimulator,
    PolynomialTrajectory,
    ShootingTrajectory,
    Trajectory,
    TrajectoryMeta,
)
from tetherland.planning.transcription import MultipleShooting
from tetherland.planning.verify import Tolerances, Verification, verify, verify_nodes

Method = Literal["ocp", "spline"]

__all__ = [
    "MAX_REFINEMENTS",
    "Attempt",
    "PlanResult",
    "PlanStatus",
    "Planner",
    "PlanningError",
    "ReplanSettings",
    "plan",
    "spline_trajectory",
    "trajectory_meta",
]


@dataclass(frozen=True, kw_only=True)
class PlanResult(VerifiedResult[Trajectory, Verification]):
    """What :meth:`Planner.plan` and :meth:`Planner.replan` return.

    The fields of :class:`~tetherland.planning.driver.VerifiedResult` (status, message,
    solver, cost, trajectory, verification, solution, attempts) and:

    Attributes
    ----------
    maneuver : Maneuver
    method : {"ocp", "spline"}
    spec : ManeuverSpec
        The maneuver planned (for a re-plan: the rest of the maneuver, from its state).
    start_time : float
        Time since the start of the maneuver at which this plan's t = 0 lies (0 for
        :meth:`Planner.plan`, the ``elapsed`` time of a re-plan) [s].

    ``verification.scope`` says what was checked: the dense re-simulation, or for an
    online re-plan possibly the solver's nodes only.
    """

    maneuver: Maneuver
    method: str
    spec: ManeuverSpec
    start_time: float = 0.0

    def _label(self) -> str:
        return f"{self.maneuver.value} plan"

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
            "start_time_s": self.start_time,
            "checked": None if v is None else v.scope.value,
            "attempts": [a.to_json() for a in self.attempts],
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


@dataclass(frozen=True)
class ReplanSettings:
    """How :meth:`Planner.replan` solves and checks (online use: one solve, no fallback).

    Attributes
    ----------
    solver : {"fatrop", "ipopt"}
    tol : float
        KKT tolerance of the solve [-].
    constr_viol_tol : float
        Constraint violation tolerance (terminal conditions, gaps, bounds) [-].
    max_iter : int
        Iteration limit; a re-plan near the previous solution needs 3-6.
    warm_mu_init : float
        Initial barrier parameter of the warm start [-].
    check : CheckScope
        NODES (default): the cheap check of the solver's nodes
        (:func:`~tetherland.planning.verify.verify_nodes`, about 0.1 ms);
        RESIMULATION: the dense re-simulation of :meth:`Planner.plan` (about 5 ms).
    jit : bool
        Evaluate the NLP through its compiled interval functions
        (:attr:`SolverSettings.jit`; the speed needed for 2 ms re-plans, see
        ``bench_planner.py``).
    max_refinements : int
        Integrator-step doublings after a failed check (0: report the failure; the
        caller keeps flying the previous plan).
    """

    solver: SolverName = "fatrop"
    tol: float = 1e-4
    constr_viol_tol: float = 1e-6
    max_iter: int = 30
    warm_mu_init: float = 1e-8
    check: CheckScope = CheckScope.NODES
    jit: bool = True
    max_refinements: int = 0

    def solver_settings(self) -> SolverSettings:
        return SolverSettings(
            self.solver, self.tol, self.max_iter, None, warm_mu_init=self.warm_mu_init,
            constr_viol_tol=self.constr_viol_tol, jit=self.jit,
        )  # fmt: skip


def trajectory_meta(
    scenario: Scenario, spec: ManeuverSpec, geometry: LandingGeometry | None = None
) -> TrajectoryMeta:
    """The :class:`TrajectoryMeta` of a scenario's maneuver (``geometry``: the scenario's
    :class:`LandingGeometry` when the caller has it)."""
    geo = geometry or LandingGeometry.from_scenario(scenario)
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
        r_att_B=np.asarray(scenario.vehicle.cable_attachment, dtype=float),
    )


def spline_trajectory(meta: TrajectoryMeta, spec: ManeuverSpec) -> PolynomialTrajectory:
    """The rest-to-rest polynomial reference between the maneuver's boundary outputs."""
    return PolynomialTrajectory(
        meta, spec.duration, (spec.phi_start, spec.phi_final), (spec.theta_start, spec.theta_final)
    )


class _ManeuverOcp:
    """The landing/takeoff OCP of one request, as the driver's :class:`VerifiedOcp`."""

    def __init__(
        self,
        planner: Planner,
        spec: ManeuverSpec,
        meta: TrajectoryMeta,
        problem: OcpProblem,
        transcription: MultipleShooting,
        warm: OcpSolution | InitialGuess | None,
        check: CheckScope = CheckScope.RESIMULATION,
    ) -> None:
        self.planner, self.spec, self.meta, self.problem = planner, spec, meta, problem
        self.transcription, self.warm, self.check = transcription, warm, check

    def candidate(self, session: SolveSession) -> Candidate:
        warm = self.warm if session.primary else None
        if isinstance(warm, OcpSolution) and not usable_warm_start(
            warm, self.problem, self.transcription.nodes
        ):
            warm = None
        guess = warm or self.planner.initial_guess(self.meta, self.spec, self.transcription.nodes)
        # An InitialGuess as warm start is a previous solution shifted in time (re-plan):
        # start with the warm-start options, without its multipliers.
        force = True if isinstance(warm, InitialGuess) else None
        sol = session.solve(self.problem, self.transcription, guess, warm=force)
        return Candidate(self.problem, self.transcription, sol)

    def accept(self, candidate: Candidate) -> tuple[Trajectory, Verification]:
        sol, spec = candidate.solution, self.spec
        U = self.planner.rotor_inputs(spec, sol)
        if self.check is CheckScope.NODES:
            X = self.planner.rotor_states(spec, sol)
            check = verify_nodes(
                spec, sol.times, X, U, candidate.transcription.steps, self.planner.tolerances
            )
            traj: Trajectory = ShootingTrajectory(
                self.meta, sol.times, X, U, simulator=self.planner.simulator
            )
            return traj, check
        traj = ShootingTrajectory.simulate(
            self.meta, sol.times, spec.x_start, U, self.planner.simulator
        )
        return traj, verify(traj, spec, self.planner.tolerances)

    def failure_message(self, solution: OcpSolution) -> str:
        return (
            f"{solution.solver} did not solve the OCP: {solution.return_status} "
            f"after {solution.iterations} iterations"
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
        self.driver = OcpDriver()
        self._templates: dict[tuple[str, bytes] | None, OcpProblem] = {}
        """The statements built so far, the last of each :func:`statement_key` (None: the
        acting thrusts bounded; else the believed ground effect's kind and samples)."""
        self.simulator = PlanarSimulator()

    def ocp_solver(self, transcription: MultipleShooting, settings: SolverSettings) -> OcpSolver:
        """The cached :class:`OcpSolver` for these settings."""
        return self.driver.ocp_solver(transcription, settings)

    def problem(
        self, scenario: Scenario, maneuver: Maneuver | str = Maneuver.LANDING
    ) -> OcpProblem:
        """The OCP (6.21) of a scenario's maneuver (for inspection or custom solving)."""
        return self._problem(ManeuverSpec.from_scenario(scenario, maneuver))

    def _problem(self, spec: ManeuverSpec) -> OcpProblem:
        # The statement holds no numbers: build it once, then only swap the data.
        key = statement_key(spec)
        problem = build_ocp(spec, self.form, self._templates.get(key))
        self._templates[key] = problem
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
        geometry = LandingGeometry.from_scenario(scenario)
        spec = ManeuverSpec.from_scenario(scenario, maneuver, geometry)
        meta = trajectory_meta(scenario, spec, geometry)
        base = PlanResult(
            status=PlanStatus.FAILED, message="", maneuver=spec.maneuver, method=method, spec=spec
        )
        reasons = precheck(spec)
        # (with the believed ground effect, precheck holds the landed hover's rotor
        # commands; the analysis' floor and ceiling hold the acting thrusts)
        landed = landed_hover_rotor_reason(scenario, rotor_bounds=spec.ground_effect is None)
        if landed is not None and not reasons:
            reasons.append(landed)
        if reasons:
            return replace(base, status=PlanStatus.INFEASIBLE, message="; ".join(reasons))
        if method == "spline":
            traj = spline_trajectory(meta, spec)
            check = verify(traj, spec, self.tolerances)
            if check.ok:
                return replace(
                    base, status=PlanStatus.SOLVED, message="ok", trajectory=traj,
                    verification=check,
                )  # fmt: skip
            return replace(
                base, status=PlanStatus.INFEASIBLE, verification=check,
                message="the spline reference fails its check: " + "; ".join(check.problems),
            )  # fmt: skip
        if method != "ocp":
            raise ValueError(f"method must be 'ocp' or 'spline', got {method!r}")
        if isinstance(warm_start, PlanResult):
            warm_start = warm_start.solution
        steps = max(1, math.ceil(spec.duration / (cfg.nodes * cfg.integrator_step) - 1e-9))
        job = _ManeuverOcp(
            self, spec, meta, self._problem(spec), MultipleShooting(cfg.nodes, "rk4", steps),
            warm_start,
        )  # fmt: skip
        outcome = self.driver.run(job, SolvePolicy.from_config(cfg, solver))
        return replace(base, **base.outcome_fields(outcome))

    def replan(
        self,
        plan: PlanResult,
        x0: ArrayLike,
        elapsed: float = 0.0,
        *,
        nodes: int | None = None,
        settings: ReplanSettings | None = None,
    ) -> PlanResult:
        """Plan the rest of a maneuver again from the state ``x0`` (online re-planning).

        The same compiled solver serves every re-plan (the initial state, the duration and
        the tension bound are numbers of the statement), warm-started from ``plan``
        shifted to the new node times, with the options of :class:`ReplanSettings`
        (tolerance, warm barrier parameter, no fallback solver, by default the cheap node
        check: ``result.verification.scope`` says what was checked).

        Parameters
        ----------
        plan : PlanResult
            The solved plan being flown (from :meth:`plan` or an earlier re-plan).
        x0 : (12,) array
            Rotor-form planar state [phi, theta_A, phi', theta_A', f_1..4, f_1'..4'] at
            ``elapsed`` [rad, rad/s, N, N/s] (e.g. the estimate, or
            ``plan.trajectory.state(t)`` with errors).
        elapsed : float
            Time since the start of the maneuver [s]; the re-plan lasts the rest,
            ``spec.duration - elapsed`` (plan.start_time + plan.spec.duration - elapsed).
        nodes : int, optional
            Shooting intervals N (default: those of ``plan``'s solution).
        settings : ReplanSettings, optional

        Returns
        -------
        PlanResult
            With ``start_time = elapsed`` and ``spec`` the rest of the maneuver.
        """
        settings = settings or ReplanSettings()
        if plan.trajectory is None or plan.method != "ocp" or plan.solution is None:
            raise PlanningError("replan needs a solved OCP plan to start from")
        prev = plan.solution
        N = nodes or len(prev.U)
        into = elapsed - plan.start_time  # time into the previous plan [s]
        spec = plan.spec.remainder(x0, into)
        if prev.X.shape[1] != (8 if self.form == "wrench" else 12):
            raise PlanningError("replan: the plan was made by a planner of another state form")
        # The statement and all numbers but x0, T and the tension ramp are the plan's.
        template = self._templates.get(statement_key(spec))
        problem = self._problem(spec) if template is None else remainder_ocp(template, spec)
        # Node times of the re-plan on the previous plan's clock; its nodes interpolated
        # there (inputs held) start the solver; the first node is the new initial state.
        t_new = into + np.linspace(0.0, spec.duration, N + 1)
        k = np.clip(np.searchsorted(prev.times, t_new, side="right") - 1, 0, len(prev.U) - 1)
        w = ((t_new - prev.times[k]) / (prev.times[k + 1] - prev.times[k]))[:, None]
        X = (1.0 - w) * prev.X[k] + w * prev.X[k + 1]
        X[0] = problem.x0
        guess = InitialGuess(X=X, U=prev.U[k[:-1]])
        # The previous plan's integrator step length, at most (one compiled solver).
        candidate = [a for a in plan.attempts if a.candidate]
        steps0 = candidate[-1].steps if candidate else 1
        step = plan.spec.duration / len(prev.U) / steps0
        steps = max(1, math.ceil(spec.duration / (N * step) - 1e-9))
        job = _ManeuverOcp(
            self, spec, plan.trajectory.meta, problem, MultipleShooting(N, "rk4", steps), guess,
            settings.check,
        )  # fmt: skip
        policy = SolvePolicy((settings.solver_settings(),), settings.max_refinements)
        outcome = self.driver.run(job, policy)
        base = PlanResult(
            status=PlanStatus.FAILED, message="", maneuver=spec.maneuver, method="ocp",
            spec=spec, start_time=elapsed,
        )  # fmt: skip
        return replace(base, **base.outcome_fields(outcome))

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

    def rotor_inputs(self, spec: ManeuverSpec, sol: OcpSolution) -> FloatArray:
        """The rotors' f'' = G v of the OCP input v = [f_R'', tau_y''] (N, 4) [N/s^2]."""
        return sol.U @ spec.params.G.T

    def rotor_states(self, spec: ManeuverSpec, sol: OcpSolution) -> FloatArray:
        """The solution's node states in rotor form (N+1, 12)."""
        if self.form == "rotor":
            return sol.X
        G = spec.params.G
        return np.hstack((sol.X[:, :4], sol.X[:, 4:6] @ G.T, sol.X[:, 6:8] @ G.T))


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
