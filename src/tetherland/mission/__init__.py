"""The mission of chapter 6.6: supervisor, phases, closed-loop run and verdict."""

from tetherland.mission.phases import Phase, PhaseRecord
from tetherland.mission.run import MissionResult, run_mission, with_overrides
from tetherland.mission.supervisor import MissionError, MissionSupervisor

__all__ = [
    "MissionError",
    "MissionResult",
    "MissionSupervisor",
    "Phase",
    "PhaseRecord",
    "run_mission",
    "with_overrides",
]
