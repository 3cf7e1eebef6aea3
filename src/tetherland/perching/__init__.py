"""Contact-free perching baseline (chapter section 6.4.1, issue 7): closed-loop run and verdict.

* :mod:`.reference`: :class:`PerchingReference`, the run's reference source (hover,
  maneuver, motors off at touchdown, rest);
* :mod:`.verdict`: :func:`evaluate_perch`, landing conditions (1)-(5) from a run log;
* :mod:`.run`: :func:`run_perching`, plan on the belief, fly in the plant, judge.

The planner is :mod:`tetherland.planning.perching`; the controller is
:class:`tetherland.control.tracking.FreeFlightTracker`.
"""

from tetherland.perching.reference import LanderGeometry, PerchingReference, PerchPhase
from tetherland.perching.run import EstimatorFactory, build_run, run_perching
from tetherland.perching.verdict import PerchVerdict, contact_index, evaluate_perch

__all__ = [
    "EstimatorFactory",
    "LanderGeometry",
    "PerchPhase",
    "PerchVerdict",
    "PerchingReference",
    "build_run",
    "contact_index",
    "evaluate_perch",
    "run_perching",
]
