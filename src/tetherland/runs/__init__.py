"""Closed-loop runs in the MuJoCo plant, and their run directories.

* :func:`run_mission`: one run of any landing method (plant truth, robot belief), judged;
* :func:`save_run`, :func:`load_run`, :func:`rejudge`: the run directory on disk.
"""

from tetherland.runs.closed_loop import (
    EstimatorFactory,
    RunResult,
    run_mission,
    truth_estimator,
    ukf_estimator,
)
from tetherland.runs.directory import (
    jsonable_summary,
    load_run,
    rejudge,
    save_run,
)

__all__ = [
    "EstimatorFactory",
    "RunResult",
    "jsonable_summary",
    "load_run",
    "rejudge",
    "run_mission",
    "save_run",
    "truth_estimator",
    "ukf_estimator",
]
