"""Mission phases (chapter 6.6.2) and the record of each phase's span."""

from __future__ import annotations

import enum
from dataclasses import dataclass


class Phase(enum.IntEnum):
    """Phases of the mission; the integer is written into the log's ``phase`` column."""

    TAKEOFF = 1
    """Climb from the start pad (free flight)."""
    APPROACH = 2
    """(a) Fly to the start of the hooking pass (free flight)."""
    HOOKING = 3
    """(b) Straight pass of the hook through the anchoring mechanism."""
    STRETCH = 4
    """(c) Radial move beyond the cable length until the estimated tension is high enough."""
    RETRY = 5
    """Missed hook: back to the start of the hooking pass."""
    TETHERED_LANDING = 6
    """(d) Tracking the planned landing in inclined hovering (tethered control)."""
    TOUCHDOWN = 7
    """Holding the landed output until the motors go off (t_L to t_G)."""
    MOTORS_OFF = 8
    """Deploying on the surface with the motors off (t_G to t_T)."""
    SPIN_UP = 9
    """Motors back on, holding the landed output."""
    TETHERED_TAKEOFF = 10
    """Tracking the planned takeoff (tethered control)."""
    RELEASE = 11
    """Free flight towards the anchor until the cable is slack."""
    UNHOOK = 12
    """Reverse hooking pass: the hook leaves the anchoring mechanism."""
    RETURN = 13
    """Flight back above the start pad."""
    LAND = 14
    """Descent onto the start pad."""
    DONE = 15
    """Landed at the start, motors off."""
    SAFE_HOVER = 16
    """After an abort: holding position in free flight."""
    ABORTED = 17
    """Terminal state after an abort."""

    @property
    def tethered(self) -> bool:
        return self in (
            Phase.TETHERED_LANDING,
            Phase.TOUCHDOWN,
            Phase.SPIN_UP,
            Phase.TETHERED_TAKEOFF,
        )


@dataclass(frozen=True)
class PhaseRecord:
    """One phase of a run: its span and why it ended."""

    phase: Phase
    start: float
    end: float
    exit_reason: str

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.phase.name.lower(),
            "start": self.start,
            "end": self.end,
            "exit_reason": self.exit_reason,
        }
