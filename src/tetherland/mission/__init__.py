"""The supervised mission of chapter 6.6: the plan stage and the supervisor's state machine.

* :mod:`.plan`: :func:`plan_mission` -> :class:`MissionPlan` (trajectories, waypoints,
  clearance), fixed before the mission flies;
* :mod:`.supervisor`: :class:`MissionSupervisor`, the phases and their transition table;
* :mod:`.phases`, :mod:`.paths`: phase codes and free-flight reference paths.

Nothing here imports the simulator: the same supervisor can drive a real vehicle. The
closed loop in MuJoCo is :func:`tetherland.runs.run_mission`.
"""

from tetherland.mission.hooking import HookingPass, check_pass, hooking_pass, hooking_pass_for
from tetherland.mission.phases import Phase, PhaseRecord
from tetherland.mission.plan import MissionError, MissionPlan, Waypoints, plan_mission
from tetherland.mission.supervisor import TRANSITIONS, MissionSupervisor, TransitionError

__all__ = [
    "TRANSITIONS",
    "HookingPass",
    "MissionError",
    "MissionPlan",
    "MissionSupervisor",
    "Phase",
    "PhaseRecord",
    "TransitionError",
    "Waypoints",
    "check_pass",
    "hooking_pass",
    "hooking_pass_for",
    "plan_mission",
]
