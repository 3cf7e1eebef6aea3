"""The contact-free baseline (section 6.4.1): a kinodynamic perching maneuver, no tether.

The vehicle starts at rest, level, at the planned start point with the rotors at hover
speed, hovers ``perching.hover_time``, flies the planned maneuver onto the landing point,
switches its motors off at (estimated) touchdown and rests ``perching.rest_time``.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from tetherland.config import Scenario
from tetherland.control.tracking import FreeFlightTracker
from tetherland.errors import ConfigError, InfeasibleError
from tetherland.geometry import LandingGeometry, effective_h_R
from tetherland.interfaces import Controller
from tetherland.methods.base import ControllerChoice, Flight, Planners
from tetherland.perching.reference import LanderGeometry, PerchingReference, PerchPhase
from tetherland.planning.perching import FreeFlightTrajectory, PerchResult
from tetherland.rotations import rotation_from_z_and_yaw, rotmat_to_quat
from tetherland.state import RigidBodyState
from tetherland.verdict.record import Expectations, PhaseSpan, RunRecord

MARGIN_TIME = 0.1
"""Extra simulated time after the planned end of the run (the reference terminates) [s]."""


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
