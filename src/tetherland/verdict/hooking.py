"""What the hook did in each hooking attempt, from the plant's truth.

The robot decides when it hooks (its hooking passes) and never sees whether the hook is
caught; the plant knows. Each attempt is the time from the start of one of the robot's
hooking passes to the start of the next (or to the end of the run): those are the
robot's actions. What happened in it is read from the plant's truth alone: the hook
state (``hook``, 1 = caught, the plant's contact-based rule), the hook's crown
(``hook_p_W``), the line's true tension (``tension``) and the anchoring cable's true
geometry (the bar's axis through p_A along y_A).

Outcomes of an attempt (:class:`HookingOutcome`), the first that applies:

* ``caught``: the hook is caught when the attempt ends (the tethered landing starts
  with it, or the run ends with it);
* ``bounced``: caught in the attempt, but not held to its end; or, never caught, the
  hook came to the anchoring cable (its crown within the hook's reach of the bar's
  axis, :func:`tetherland.models.hook.bar_near_distance`) without the line being loaded;
* ``wrong_side``: never caught, but the line loaded (true tension above the catch load,
  ``mechanism.catch_threshold`` times the hook's weight) with the crown away from the
  bar: the hook snagged on something else (under the bar against the surface, a post);
* ``tangled``: never caught, the line loaded with the crown at the bar: the line caught
  around the bar without the hook in its crook;
* ``missed``: none of these: the hook never came to the anchoring cable.

For the point hook (``disk``) and the magnet only the hook state counts (caught, bounced
or missed): neither has a line that can load without the catch.

Held: ``t_lost`` is when a hook caught at the start of the tethered landing came off
before the robot's release (under load). The release (:class:`ReleaseOutcome`): once the
robot has flown its release or unhooking, ``released`` when the hook is free at the end
of the run, ``not_released`` when it is caught then (never freed, or caught again by the
reverse pass).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Any

import numpy as np

from tetherland.config import Scenario
from tetherland.geometry import LandingGeometry
from tetherland.models.hook import bar_near_distance
from tetherland.sim.log import SimLog
from tetherland.verdict.record import PhaseSpan, RunRecord

GRAVITY = 9.81
"""Gravity of the plant's hook weight [m/s^2] (as the plant's catch rule)."""
HOOKING_PHASE = "hooking"
"""The robot's phase that starts an attempt."""
LANDING_PHASE = "tethered_landing"
"""The robot's phase that ends the hooking: the landing on the cable."""
RELEASE_PHASES = ("release", "unhook")
"""The robot's phases in which it frees the hook."""


class HookingOutcome(enum.Enum):
    """What the hook did in one attempt (module docstring)."""

    CAUGHT = "caught"
    BOUNCED = "bounced"
    WRONG_SIDE = "wrong_side"
    TANGLED = "tangled"
    MISSED = "missed"


class ReleaseOutcome(enum.Enum):
    """Whether the hook was freed after the robot's release."""

    NOT_TRIED = "not_tried"
    """The robot never flew its release (no landing on the cable, or the run ended)."""
    RELEASED = "released"
    NOT_RELEASED = "not_released"


@dataclass(frozen=True)
class HookingAttempt:
    """One hooking attempt, judged on the plant's truth.

    Attributes
    ----------
    t_start, t_end : float
        Start of the robot's pass and end of the attempt [s].
    outcome : HookingOutcome
    t_caught : float or None
        First time the hook was caught in the attempt [s].
    min_distance_m : float or None
        Closest approach of the hook's crown to the bar's axis (bar mechanism) [m].
    max_free_tension_N : float
        Largest true line tension while the hook was not caught [N].
    """

    t_start: float
    t_end: float
    outcome: HookingOutcome
    t_caught: float | None
    min_distance_m: float | None
    max_free_tension_N: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {"t_start": self.t_start, "t_end": self.t_end, "outcome": self.outcome.value,
                "t_caught": self.t_caught, "min_distance_m": self.min_distance_m,
                "max_free_tension_N": self.max_free_tension_N}  # fmt: skip


@dataclass(frozen=True)
class HookingReport:
    """Every attempt of a run and the release.

    Attributes
    ----------
    attempts : tuple of HookingAttempt
    release : ReleaseOutcome
    t_lost : float or None
        First time the hook was free again after the tethered landing started with it
        caught and before the robot's release (None: held, or never landed on it) [s]:
        the hook came off the anchoring cable under load.
    """

    attempts: tuple[HookingAttempt, ...]
    release: ReleaseOutcome
    t_lost: float | None = None

    @property
    def outcome(self) -> HookingOutcome | None:
        """The last attempt's outcome (None: no attempt)."""
        return self.attempts[-1].outcome if self.attempts else None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (``summary.json``'s ``hooking``)."""
        return {
            "outcome": None if self.outcome is None else self.outcome.value,
            "release": self.release.value,
            "t_lost": self.t_lost,
            "attempts": [a.to_dict() for a in self.attempts],
        }


def _windows(phases: tuple[PhaseSpan, ...], t_last: float) -> list[tuple[float, float]]:
    """(start, end) of every attempt: from one hooking pass's start to the next's, or to
    the start of the tethered landing or the end of the run."""
    starts = [p.start for p in phases if p.name == HOOKING_PHASE]
    out = []
    for k, t0 in enumerate(starts):
        t1 = starts[k + 1] if k + 1 < len(starts) else t_last
        landing = [p.start for p in phases if p.name == LANDING_PHASE and t0 <= p.start <= t1]
        out.append((t0, landing[0] if landing else t1))
    return out


def _bar_distance(log: SimLog, geo: LandingGeometry, scenario: Scenario) -> np.ndarray:
    """Distance of the hook's crown from the bar's axis segment, every tick [m]."""
    u = geo.R_WA[:, 1]
    d = np.asarray(log["hook_p_W"], dtype=float) - geo.p_A
    half = 0.5 * scenario.mechanism.bar_length
    s = np.clip(d @ u, -half, half)
    return np.linalg.norm(d - s[:, None] * u, axis=1)


def judge_hooking(log: SimLog, record: RunRecord, scenario: Scenario) -> HookingReport:
    """Every hooking attempt of the run and the release, on the plant's truth (module
    docstring). ``scenario`` is the truth."""
    t = np.asarray(log["t"], dtype=float)
    if not len(t):
        return HookingReport((), ReleaseOutcome.NOT_TRIED)
    caught = np.asarray(log["hook"]).reshape(-1) > 0
    tension = np.asarray(log["tension"], dtype=float).reshape(-1)
    mech = scenario.mechanism
    geo = LandingGeometry.from_scenario(scenario)
    dist = _bar_distance(log, geo, scenario) if mech.kind == "bar" else None
    near = bar_near_distance(mech)
    load = mech.catch_threshold * mech.hook_mass * GRAVITY
    attempts = []
    for t0, t1 in _windows(record.phases, float(t[-1])):
        i0, i1 = int(np.searchsorted(t, t0)), int(np.searchsorted(t, t1, side="right"))
        w = slice(i0, max(i1, i0 + 1))
        c = caught[w]
        free = ~c
        t_caught = float(t[w][np.argmax(c)]) if c.any() else None
        max_free = float(tension[w][free].max(initial=0.0))
        d_min = float(dist[w].min()) if dist is not None else None
        end_caught = bool(caught[min(max(i1, i0 + 1), len(t)) - 1])
        if end_caught:
            outcome = HookingOutcome.CAUGHT
        elif c.any():
            outcome = HookingOutcome.BOUNCED
        elif dist is not None and d_min is not None:  # the bar (both, or neither)
            loaded = free & (tension[w] > load)
            if (loaded & (dist[w] > near)).any():
                outcome = HookingOutcome.WRONG_SIDE
            elif loaded.any():
                outcome = HookingOutcome.TANGLED
            elif d_min <= near:
                outcome = HookingOutcome.BOUNCED
            else:
                outcome = HookingOutcome.MISSED
        else:
            outcome = HookingOutcome.MISSED
        attempts.append(HookingAttempt(t0, t1, outcome, t_caught, d_min, max_free))
    released = [p.start for p in record.phases if p.name in RELEASE_PHASES]
    if not released:
        release = ReleaseOutcome.NOT_TRIED
    else:
        release = ReleaseOutcome.NOT_RELEASED if caught[-1] else ReleaseOutcome.RELEASED
    t_lost = None
    landed = [p.start for p in record.phases if p.name == LANDING_PHASE]
    if landed and attempts and attempts[-1].outcome is HookingOutcome.CAUGHT:
        i0 = int(np.searchsorted(t, landed[0]))
        i1 = int(np.searchsorted(t, released[0])) if released else len(t)
        free = ~caught[i0:i1]
        if free.any():
            t_lost = float(t[i0 + int(np.argmax(free))])
    return HookingReport(tuple(attempts), release, t_lost)
