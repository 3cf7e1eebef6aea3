"""Contact-free perching planner: the baseline of chapter section 6.4.1 (issue 7).

* :mod:`.model`: the planar free-flight model with thrust dynamics and the numbers of one
  request (:class:`PerchSpec`);
* :mod:`.problem`: the OCP, stated with the shared :class:`~tetherland.planning.OcpProblem`;
* :mod:`.planner`: fixed or free final time, verification, :class:`PerchResult`;
* :mod:`.trajectory`: the free-flight reference (flat outputs up to snap, nominal
  attitude, body rate and thrusts) with CSV files;
* :mod:`.verify`: the re-simulation check.
"""

from tetherland.planning.perching.model import PerchSpec
from tetherland.planning.perching.planner import (
    PerchingError,
    PerchingPlanner,
    PerchResult,
    PerchStatus,
    plan_perching,
    precheck,
)
from tetherland.planning.perching.problem import build_perching_ocp
from tetherland.planning.perching.trajectory import (
    FreeFlightMeta,
    FreeFlightSamples,
    FreeFlightTrajectory,
    free_flight_trajectory_from_csv,
    load_free_flight_trajectory,
)
from tetherland.planning.perching.verify import PerchTolerances, PerchVerification, verify_perch

__all__ = [
    "FreeFlightMeta",
    "FreeFlightSamples",
    "FreeFlightTrajectory",
    "PerchResult",
    "PerchSpec",
    "PerchStatus",
    "PerchTolerances",
    "PerchVerification",
    "PerchingError",
    "PerchingPlanner",
    "build_perching_ocp",
    "free_flight_trajectory_from_csv",
    "load_free_flight_trajectory",
    "plan_perching",
    "precheck",
    "verify_perch",
]
