"""Touchdowns and the rest, found in the plant's truth over the whole run.

What the robot declared (its phases, its control mode) plays no part here: a touchdown is
a lander pressed by the landing surface (the log's ``lander_surface_forces``, the plant's
contact sensors filtered by partner geom, peak over the physics steps of each control
tick), so the start pad and the final landing on it (the ground) are not touchdowns; the
rest is the interval in which the plant's true total rotor thrust (``rotor_thrusts``) is
below the motors-off level (:func:`tetherland.config.verdict.motors_off_thrust`).

* the touchdown t_L is the first tick of contact with the landing surface;
* a bounce is contact lost (no lander touches the surface, at any physics step, for at
  least the contact's time constant ``sim.contact_time_constant``) and regained; every
  touchdown from t_L to the contact that starts the rest is judged by conditions (1)-(4).
  Shorter losses are the soft contact's own transient, not a flight: MuJoCo's contact is
  a spring-damper with that time constant, and a lander that pivots or unloads chatters
  on and off within micrometres of the surface from one physics step to the next;
* the rest is the first low-thrust interval that ends after t_L; it ends at spin-up (the
  first tick with the thrust back up) or at the end of the log;
* the contact that starts the rest is the contact under way when the rest begins, or
  the first one within it (the motors went off above the surface).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tetherland.errors import TetherlandError
from tetherland.sim.log import SimLog

REQUIRED_COLUMNS = ("lander_surface_forces", "rotor_thrusts")
"""Log columns the judge reads to find touchdowns and the rest."""


class LogTooOldError(TetherlandError):
    """The log lacks a column the judge reads (written by an older tetherland)."""


@dataclass(frozen=True)
class Rest:
    """The judged rest: the true thrust below the motors-off level.

    Attributes
    ----------
    start : int
        First tick with the thrust below the level.
    end : int
        First tick with the thrust back up (spin-up), or the number of ticks when the
        log ends resting (exclusive).
    t_start, t_end : float
        Their times [s] (``t_end`` the last tick's time when the log ends resting).
    """

    start: int
    end: int
    t_start: float
    t_end: float

    @property
    def duration(self) -> float:
        """t_end - t_start [s]."""
        return self.t_end - self.t_start


@dataclass(frozen=True)
class Touchdowns:
    """The contacts of the landers with the landing surface, and the rest.

    Attributes
    ----------
    onsets : tuple of int
        Ticks at which contact with the landing surface begins, over the whole run.
    first : int or None
        The touchdown t_L (the first onset).
    rest : Rest or None
        The first low-thrust interval that ends after t_L (None: none, or no touchdown).
    rest_contact : int or None
        Onset of the contact that starts the rest (None: no contact during the rest).
    """

    onsets: tuple[int, ...]
    first: int | None
    rest: Rest | None
    rest_contact: int | None

    @property
    def judged(self) -> tuple[int, ...]:
        """Onsets judged by conditions (1)-(4): from t_L to the contact that starts the
        rest (every bounce on the way), or t_L alone when there is no such contact."""
        if self.first is None:
            return ()
        last = self.first if self.rest_contact is None else self.rest_contact
        return tuple(k for k in self.onsets if self.first <= k <= last)


def require_columns(log: SimLog) -> None:
    """Raise :class:`LogTooOldError` (one line) if the log lacks a column the judge reads."""
    missing = [c for c in REQUIRED_COLUMNS if c not in log]
    if missing:
        raise LogTooOldError(
            f"the log has no {', '.join(missing)} column (written by an older tetherland, "
            "whose judge trusted the robot's phases); fly the run again to judge it"
        )


def onsets(touching: np.ndarray) -> tuple[int, ...]:
    """Indices where ``touching`` turns true (index 0 if it starts true)."""
    m = np.asarray(touching, dtype=bool)
    if m.size == 0:
        return ()
    starts = np.flatnonzero(m[1:] & ~m[:-1]) + 1
    return tuple(int(k) for k in ([0] if m[0] else []) + starts.tolist())


def bridged(mask: np.ndarray, gap: int) -> np.ndarray:
    """``mask`` with every run of fewer than ``gap`` False entries between two True ones
    set True (a contact lost for less than ``gap`` ticks was never lost)."""
    m = np.asarray(mask, dtype=bool).copy()
    on = np.flatnonzero(m)
    d = np.diff(on)
    for i in np.flatnonzero((d > 1) & (d <= gap)):
        m[on[i] + 1 : on[i + 1]] = True
    return m


def surface_contact(log: SimLog, threshold: float) -> np.ndarray:
    """(n,) bool: some lander pressed by the landing surface above ``threshold`` [N]
    during the control period that ends at each tick."""
    return np.nan_to_num(log["lander_surface_forces"]).max(axis=1) > threshold


def rest_after(thrust: np.ndarray, t: np.ndarray, level: float, k: int) -> Rest | None:
    """The first interval of ``thrust`` [N] below ``level`` [N] that ends after tick ``k``
    (it may begin before k: the motors went off above the surface)."""
    low = np.asarray(thrust) < level
    n = len(low)
    for start in onsets(low):
        stop = np.flatnonzero(~low[start:])
        end = start + int(stop[0]) if stop.size else n
        if end > k:
            t_end = float(t[end]) if end < n else float(t[-1])
            return Rest(start, end, float(t[start]), t_end)
    return None


def find_touchdowns(
    log: SimLog, contact_force: float, motors_off: float, bounce_time: float
) -> Touchdowns:
    """Touchdowns and the rest of a run (see the module docstring).

    Parameters
    ----------
    log : SimLog
        The run's log (plant truth).
    contact_force : float
        A lander force above this counts as contact (``verdict.touchdown_force``) [N].
    motors_off : float
        The motors-off level of the total true thrust [N].
    bounce_time : float
        Contact lost for less than this was not lost (the contact's time constant) [s].
    """
    require_columns(log)
    t = log["t"]
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    # a run of m ticks without contact spans at least m control periods
    touching = bridged(surface_contact(log, contact_force), math.ceil(bounce_time / dt - 1e-9))
    on = onsets(touching)
    if not on:
        return Touchdowns((), None, None, None)
    first = on[0]
    rest = rest_after(log["rotor_thrusts"].sum(axis=1), log["t"], motors_off, first)
    contact = None
    if rest is not None:
        if touching[rest.start]:
            contact = max(k for k in on if k <= rest.start)
        else:
            contact = next((k for k in on if rest.start < k < rest.end), None)
    return Touchdowns(on, first, rest, contact)
