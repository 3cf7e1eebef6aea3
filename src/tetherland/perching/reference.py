"""The contact-free perching run as a :class:`~tetherland.interfaces.ReferenceSource`.

Phases: hover at the start point, the planned maneuver, motors off right after
touchdown, rest (the physics decides whether the vehicle stays: condition (5)), then
terminate. Touchdown is declared when the estimated lowest lander tip reaches the
surface (``contact_threshold``). A vehicle that has not touched at the planned t_L keeps
flying with the touchdown thrust and attitude (:meth:`FreeFlightTrajectory.continuation`:
it goes on towards the surface at the approach speed) for at most ``contact_grace``; then
the motors go off anyway: a contact-free vehicle cannot hover with z_B = z_S on a slope.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland.geometry import FloatArray
from tetherland.interfaces import ControlMode, EventRecord, Reference, StateEstimate
from tetherland.planning.perching import FreeFlightTrajectory


class PerchPhase(enum.IntEnum):
    """Phase codes of the perching run (logged in the ``phase`` column)."""

    HOVER = 0
    MANEUVER = 1
    MOTORS_OFF = 2


@dataclass(frozen=True)
class LanderGeometry:
    """Where the lander tips are and where the surface is (as the vehicle believes).

    Attributes
    ----------
    tips_B : (4, 3) array
        Lowest points of the landers in F_B [m].
    z_S : (3,) array
        Surface normal, F_W.
    p_L : (3,) array
        A point of the surface (the landing point), F_W [m].
    """

    tips_B: FloatArray
    z_S: FloatArray
    p_L: FloatArray

    @classmethod
    def create(
        cls, half_width: float, h_R: float, z_S: ArrayLike, p_L: ArrayLike
    ) -> LanderGeometry:
        w = half_width
        tips = np.array([[w, w, -h_R], [-w, w, -h_R], [-w, -w, -h_R], [w, -w, -h_R]])
        return cls(tips, np.asarray(z_S, dtype=float), np.asarray(p_L, dtype=float))

    def clearance(self, p_W: FloatArray, R_WB: FloatArray) -> float:
        """Height of the lowest lander tip above the surface [m]."""
        tips_W = p_W + self.tips_B @ R_WB.T
        return float(np.min((tips_W - self.p_L) @ self.z_S))


class PerchingReference:
    """Plays a perching trajectory: hover, maneuver, motors off, rest, terminate.

    Parameters
    ----------
    trajectory : FreeFlightTrajectory
    landers : LanderGeometry
        For the early-contact check on the estimate.
    t_start : float
        Hover time before the maneuver starts [s].
    rest_time : float
        Time with the motors off before the run terminates [s].
    contact_threshold : float
        Estimated lowest-tip clearance at or below which contact is declared [m].
    contact_grace : float
        Longest flight past t_L waiting for contact [s].
    """

    def __init__(
        self,
        trajectory: FreeFlightTrajectory,
        landers: LanderGeometry,
        *,
        t_start: float,
        rest_time: float,
        contact_threshold: float = 0.0,
        contact_grace: float = 0.1,
    ) -> None:
        self.trajectory = trajectory
        self.landers = landers
        self.t_start = float(t_start)
        self.rest_time = float(rest_time)
        self.contact_threshold = float(contact_threshold)
        self.contact_grace = float(contact_grace)
        self.yaw = trajectory.meta.heading
        rows = np.zeros((5, 3))
        rows[0] = trajectory.flat_outputs(0.0)[0]
        self._hover_rows = rows
        self._hover_rows.setflags(write=False)
        self._thrust_final = float(trajectory.sample([trajectory.duration]).thrust[0])
        self._events: list[EventRecord] = []
        self.phase = PerchPhase.HOVER
        self.t_motors_off: float | None = None

    @property
    def t_touchdown_planned(self) -> float:
        """Planned touchdown time t_L in run time [s]."""
        return self.t_start + self.trajectory.duration

    @property
    def events(self) -> list[EventRecord]:
        return list(self._events)

    def _switch(self, t: float, phase: PerchPhase, message: str) -> None:
        self.phase = phase
        self._events.append(EventRecord(t, "perching", "phase", f"{phase.name}: {message}"))

    def reference(self, t: float, estimate: StateEstimate) -> Reference:
        """Reference for run time ``t`` (switches phases on time and estimated contact)."""
        if self.phase is PerchPhase.MOTORS_OFF:
            assert self.t_motors_off is not None
            done = t >= self.t_motors_off + self.rest_time
            return Reference(t=t, mode=ControlMode.MOTORS_OFF, phase=int(self.phase),
                             yaw=self.yaw, terminate=done)  # fmt: skip
        if t < self.t_start:
            return Reference(t=t, mode=ControlMode.FREE_FLIGHT, phase=int(self.phase),
                             p_W=self._hover_rows, yaw=self.yaw)  # fmt: skip
        if self.phase is PerchPhase.HOVER:
            self._switch(t, PerchPhase.MANEUVER, "perching maneuver started")
        tau = t - self.t_start
        T = self.trajectory.duration
        body = estimate.body
        clearance = self.landers.clearance(body.p_W, body.R_WB)
        reason = None
        if clearance <= self.contact_threshold:
            reason = f"contact at t_L {tau - T:+.3f} s (estimated lander clearance " \
                     f"{clearance:.4f} m)"  # fmt: skip
        elif tau >= T + self.contact_grace:
            reason = f"no contact {self.contact_grace:g} s after t_L (estimated lander " \
                     f"clearance {clearance:.4f} m)"  # fmt: skip
        if reason is not None:
            self.t_motors_off = t
            self._switch(t, PerchPhase.MOTORS_OFF, reason)
            return Reference(t=t, mode=ControlMode.MOTORS_OFF, phase=int(self.phase), yaw=self.yaw)
        if tau <= T:
            s = self.trajectory.sample([tau])
            rows, thrust = s.p_W[0], float(s.thrust[0])
        else:
            rows, thrust = self.trajectory.continuation(tau - T), self._thrust_final
        return Reference(
            t=t,
            mode=ControlMode.FREE_FLIGHT,
            phase=int(self.phase),
            p_W=rows,
            yaw=self.yaw,
            thrust_ff=thrust,
        )
