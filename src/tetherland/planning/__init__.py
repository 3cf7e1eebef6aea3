"""Landing and takeoff trajectory planning (chapter section 6.5, docs/theory.md section 6).

* :mod:`.ocp` states an optimal control problem; :mod:`.transcription` turns it into an
  NLP by multiple shooting; :mod:`.solvers` solves it with IPOPT or fatrop, caching the
  compiled solver per problem structure.
* :mod:`.maneuver` builds the tethered landing/takeoff OCP (6.21) from a scenario.
* :mod:`.spline` is the planner-free rest-to-rest polynomial reference.
* :mod:`.trajectory` samples a plan (outputs with derivatives, nominal state and input)
  and saves/loads it as CSV; :mod:`.verify` re-checks it; :mod:`.planner` ties it together.
"""

from tetherland.planning.maneuver import Maneuver, ManeuverSpec, build_ocp, precheck
from tetherland.planning.ocp import OcpProblem
from tetherland.planning.planner import (
    Planner,
    PlanningError,
    PlanResult,
    PlanStatus,
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
from tetherland.planning.verify import Tolerances, Verification, verify

__all__ = [
    "InitialGuess",
    "Maneuver",
    "ManeuverSpec",
    "MultipleShooting",
    "OcpProblem",
    "OcpSolution",
    "OcpSolver",
    "PlanResult",
    "PlanStatus",
    "Planner",
    "PlanningError",
    "PolynomialTrajectory",
    "ShootingTrajectory",
    "SolveStatus",
    "SolverSettings",
    "Tolerances",
    "Trajectory",
    "TrajectoryMeta",
    "TrajectorySamples",
    "Transcript",
    "Verification",
    "build_ocp",
    "load_trajectory",
    "plan",
    "precheck",
    "spline_trajectory",
    "trajectory_from_csv",
    "trajectory_meta",
    "verify",
]
