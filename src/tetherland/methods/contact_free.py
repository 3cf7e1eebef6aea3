"""The contact-free baseline (section 6.4.1): a kinodynamic perching maneuver, no tether.

The vehicle starts at rest, level, at the planned start point with the rotors at hover
speed, hovers ``perching.hover_time``, flies the planned maneuver onto the landing point,
switches its motors off at (estimated) touchdown and rests ``perching.rest_time``.

* :class:`ContactFreeMethod`: the landing method (plan with
  :mod:`tetherland.planning.perching`, fly, record), judged like every method by
  :func:`tetherland.verdict.judge`;
* :class:`PerchingReference`: the run as a
  :class:`~tetherland.interfaces.ReferenceSource`. Phases: hover at the start point, the
  planned maneuver, motors off right after touchdown, rest (the physics decides whether
  the vehicle stays: condition (5)), then terminate. Touchdown is declared when the
  estimated lowest lander tip reaches the surface (``contact_threshold``). A vehicle that
  has not touched at the planned t_L keeps flying with the touchdown thrust and attitude
  (:meth:`FreeFlightTrajectory.continuation`: it goes on towards the surface at the
  approach speed) for at most ``contact_grace``; then the motors go off anyway: a
  contact-free vehicle cannot hover with z_B = z_S on a slope.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from tetherland.config import Scenario
from tetherland.control.tracking import FreeFlightTracker
from tetherland.errors import ConfigError, InfeasibleError
from tetherland.geometry import FloatArray, LandingGeometry, effective_h_R
from tetherland.interfaces import (
    Controller,
    ControlMode,
    EventRecord,
    Reference,
    StateEstimate,
)
from tetherland.methods.base import ControllerChoice, Flight, Planners
from tetherland.models.airframe import lander_tips_B
from tetherland.planning.perching import FreeFlightTrajectory, PerchResult
from tetherland.rotations import rotation_from_z_and_yaw, rotmat_to_quat
from tetherland.state import RigidBodyState
from tetherland.verdict.record import Expectations, PhaseSpan, RunRecord

MARGIN_TIME = 0.1
"""Extra simulated time after the planned end of the run (the reference terminates) [s]."""


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
        """From the landers' half-width [m] and height h_R [m] below the centre of mass
        (:func:`tetherland.models.airframe.lander_tips_B`), the surface normal and a point
        of the surface [m]."""
        tips = lander_tips_B(half_width, h_R)
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
        self._drag_in_rows = trajectory.meta.rotor_drag > 0.0
        """The maneuver's rows are the thrust's (:meth:`FreeFlightTrajectory.reference_at`),
        the plan's rotor drag in them (``Reference.drag_in_rows``)."""
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
        if tau <= T:  # the plan's rows (its modelled drag in them, when it has one)
            rows, thrust = self.trajectory.reference_at(tau)
            drag_in_rows = self._drag_in_rows
        else:
            rows, thrust = self.trajectory.continuation(tau - T), self._thrust_final
            drag_in_rows = False
        return Reference(
            t=t,
            mode=ControlMode.FREE_FLIGHT,
            phase=int(self.phase),
            p_W=rows,
            yaw=self.yaw,
            thrust_ff=thrust,
            drag_in_rows=drag_in_rows,
        )


class ContactFreeMethod:
    """Plan a perching maneuver, fly it with the feed-forward tracker, cut the motors."""

    name = "free-flight"
    expects = Expectations(required_conditions=(1, 2, 3, 5))
    """Condition (4) is reported but not required: without a tether it can hold only on
    horizontal ground (section 6.4.1, Table 6.1: "all but condition (4)")."""

    def plan(self, belief: Scenario, start: RigidBodyState, planners: Planners) -> PerchResult:
        result = planners.perching.plan(belief)
        if not result.success:
            raise InfeasibleError(f"no perching plan: {result.status.value}: {result.message}")
        return result

    def fly(self, plan: PerchResult, belief: Scenario, controller: ControllerChoice) -> Flight:
        traj = plan.require()
        cfg = belief.perching
        geo = LandingGeometry.from_scenario(belief)
        landers = LanderGeometry.create(
            belief.vehicle.lander_half_width, effective_h_R(belief), geo.surface.z_S, geo.p_L
        )
        reference = PerchingReference(
            traj, landers, t_start=cfg.hover_time, rest_time=cfg.rest_time,
            contact_grace=cfg.contact_grace,
        )  # fmt: skip
        tilt = max(cfg.max_pitch_deg, belief.controller.free_flight.max_tilt_deg)
        tracker = FreeFlightTracker(
            belief, lag_compensation=cfg.lag_compensation, max_tilt_deg=tilt
        )
        p0 = traj.flat_outputs(0.0)[0]
        R0 = rotation_from_z_and_yaw(np.array([0.0, 0.0, 1.0]), traj.meta.heading)
        if controller is not None and not isinstance(controller, Controller):
            raise ConfigError(
                f"the {self.name} method has no controller named {controller!r}: give a "
                "Controller or None"
            )
        return Flight(
            reference=reference,
            controller=tracker if controller is None else controller,
            initial_state=RigidBodyState.at_rest(p0, rotmat_to_quat(R0)),
            rotor_speeds=tracker.hover_speeds,
            duration=cfg.hover_time + traj.duration + cfg.contact_grace + cfg.rest_time
            + MARGIN_TIME,
            diagnostic_keys=FreeFlightTracker.diagnostic_keys,
        )

    def trajectories(self, plan: PerchResult) -> dict[str, FreeFlightTrajectory]:
        return {"perching_trajectory": plan.require()}

    def record(self, plan: PerchResult, flight: Flight, t_end: float, base: RunRecord) -> RunRecord:
        ref = flight.reference
        assert isinstance(ref, PerchingReference)
        t_start, t_off = ref.t_start, ref.t_motors_off
        spans = [PhaseSpan("hover", 0.0, min(t_start, t_end), "maneuver started")]
        if t_end > t_start:
            end = t_off if t_off is not None else t_end
            why = "motors off at touchdown" if t_off is not None else "end of run"
            spans.append(PhaseSpan("maneuver", t_start, end, why))
        if t_off is not None:
            spans.append(PhaseSpan("motors_off", t_off, t_end, "end of run"))
        times = {"t_maneuver": t_start, "t_L_plan": ref.t_touchdown_planned}
        if t_off is not None:
            times["t_motors_off"] = t_off
        return replace(
            base,
            controller=base.controller or "free-flight tracker",
            phase_codes={p.name.lower(): int(p) for p in PerchPhase},
            phases=tuple(spans),
            times=times,
            finished=t_off is not None and t_end >= t_off + ref.rest_time - 1e-9,
            plans={"perching": plan.summary()},
        )
