"""Landing and takeoff trajectory planning (chapter section 6.5, docs/theory.md section 6).

* :mod:`.ocp` states an optimal control problem; :mod:`.transcription` turns it into an
  NLP by multiple shooting; :mod:`.solvers` solves it with IPOPT or fatrop, caching the
  compiled solver per problem structure.
* :mod:`.maneuver` builds the tethered landing/takeoff OCP (6.21) from a scenario.
* :mod:`.spline` is the planner-free rest-to-rest polynomial reference.
* :mod:`.driver` is the one verified-OCP driver of every planner (solver cache, fallback
  solver, integrator refinement, verification call, :class:`PlanStatus` and the result
  base :class:`VerifiedResult`); :mod:`.checks` is the verification core.
* :mod:`.shooting` integrates held inputs into dense RK4 tables; :mod:`.trajectory`
  samples a plan (outputs with derivatives, nominal state and input) and saves/loads it
  with the CSV :mod:`.codec`; :mod:`.verify` re-checks it; :mod:`.planner` ties it
  together (:meth:`Planner.plan`, and :meth:`Planner.replan` for online re-planning).
* :mod:`.start` places the vehicle at a tethered plan's first state, the cable taut at
  the planned tension (where a run that starts on the plan begins).
"""

from tetherland.planning.checks import CheckResult, CheckScope
from tetherland.planning.driver import (
    Attempt,
    OcpDriver,
    PlanningError,
    PlanStatus,
    SolvePolicy,
    VerifiedResult,
)
from tetherland.planning.maneuver import Maneuver, ManeuverSpec, build_ocp, precheck
from tetherland.planning.ocp import OcpProblem
from tetherland.planning.planner import (
    Planner,
    PlanResult,
    ReplanSettings,
    plan,
    spline_trajectory,
    trajectory_meta,
)
from tetherland.planning.solvers import (
    InitialGuess,
    OcpSolution,
    OcpSolver,
    SolverSettings,
    SolveStatus,
)
from tetherland.planning.trajectory import (
    PolynomialTrajectory,
    ShootingTrajectory,
    Trajectory,
    TrajectoryMeta,
    TrajectorySamples,
    load_trajectory,
    trajectory_from_csv,
)
from tetherland.planning.transcription import MultipleShooting, Transcript
from tetherland.planning.verify import Tolerances, Verification, verify, verify_nodes

__all__ = [
    "Attempt",
    "CheckResult",
    "CheckScope",
    "InitialGuess",
    "Maneuver",
    "ManeuverSpec",
    "MultipleShooting",
    "OcpDriver",
    "OcpProblem",
    "OcpSolution",
    "OcpSolver",
    "PlanResult",
    "PlanStatus",
    "Planner",
    "PlanningError",
    "PolynomialTrajectory",
    "ReplanSettings",
    "ShootingTrajectory",
    "SolvePolicy",
    "SolveStatus",
    "SolverSettings",
    "Tolerances",
    "Trajectory",
    "TrajectoryMeta",
    "TrajectorySamples",
    "Transcript",
    "Verification",
    "VerifiedResult",
    "build_ocp",
    "load_trajectory",
    "plan",
    "precheck",
    "spline_trajectory",
    "trajectory_from_csv",
    "trajectory_meta",
    "verify",
    "verify_nodes",
]
