"""The expert: the OCP plan tracked by the hierarchical controller, as a policy.

It maps an observation of :class:`~tetherland.gym.env.TetheredEnv` to an action, for
learning from demonstration. It holds the plan (a :class:`TrajectoryTrack` started at
t = 0) and the mission's :class:`~tetherland.control.SwitchingController` in tethered mode.
Landing ends as the mission's touchdown phase does: contact is believed near the end of
the plan when the estimated link stops following the reference, past the planned end a
guarded descent lowers phi_d at ``mission.touchdown_rate_deg`` until it does; the expert
then holds the link where it touched for ``mission.settle_time`` and idles the rotors at
f_min (the action's zero: the motors-off of the mission). Takeoff holds the planned end
hover.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from tetherland.config import Scenario
from tetherland.control import SwitchingController
from tetherland.estimation import ThresholdDwell
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.gym.env import estimate_of
from tetherland.interfaces import ControlMode, Reference
from tetherland.models.quadrotor import RotorModel
from tetherland.planning import Planner
from tetherland.planning.maneuver import Maneuver
from tetherland.planning.tracking import TrajectoryTrack
from tetherland.planning.trajectory import Trajectory


class ExpertPolicy:
    """Observation -> normalised rotor thrusts, by the plan and the tethered controller.

    Parameters
    ----------
    scenario : Scenario
        The believed scenario (controller gains, vehicle, mission settings).
    maneuver : str or Maneuver
        ``"landing"`` or ``"takeoff"``.
    plan : Trajectory, optional
        The planned maneuver (default: planned now).
    controller : str, optional
        Tethered controller, ``"hierarchical"`` or ``"dfl"`` (default from the scenario).
    """

    def __init__(
        self,
        scenario: Scenario,
        maneuver: str | Maneuver = Maneuver.LANDING,
        *,
        plan: Trajectory | None = None,
        controller: str | None = None,
    ) -> None:
        self.scenario = scenario
        self.maneuver = Maneuver(maneuver)
        self.plan = plan or Planner().plan(scenario, self.maneuver).require()
        self.track = TrajectoryTrack(self.plan, 0.0, scenario.controller.rate_hz)
        self.kind = controller
        v = scenario.vehicle
        self.rotors = RotorModel.from_config(v)
        self._phi_star = LandingGeometry.from_scenario(scenario).phi_star
        self._f_min, self._f_span = v.f_min, v.f_max - v.f_min
        self.reset()

    @classmethod
    def for_env(cls, env: Any, controller: str | None = None) -> ExpertPolicy:
        """The expert of a :class:`TetheredEnv` (or a wrapper of one): its plan, scenario."""
        e = env.unwrapped
        return cls(e.scenario, e.maneuver, plan=e.plan, controller=controller)

    def reset(self) -> None:
        """Start a new episode (fresh controller state, no touchdown yet)."""
        self.controller = SwitchingController(self.scenario, self.kind)
        m = self.scenario.mission
        self._contact = ThresholdDwell(math.radians(m.contact_error_deg), m.contact_dwell)
        self._hold: Reference | None = None

    def __call__(self, observation: FloatArray) -> FloatArray:
        est = estimate_of(observation)
        hold = self._hold
        if hold is not None and est.t >= hold.t + self.scenario.mission.settle_time:
            return np.zeros(4, dtype=np.float32)  # landed: rotors idle
        ref = self.reference(est.t, est)
        command = self.controller.update(est.t, est, ref)
        f = self.rotors.thrust(command.rotor_speeds)
        return np.clip((f - self._f_min) / self._f_span, 0.0, 1.0).astype(np.float32)

    def reference(self, t: float, est: Any) -> Reference:
        """The tethered reference at ``t``: the plan, then the guarded touchdown (landing).

        As the mission's supervisor: contact counts from the last ``mission.contact_window``
        of the plan on, once the link is within ``mission.contact_gate_deg`` of phi*, when
        the estimated link stays ``contact_error_deg`` above the reference for
        ``contact_dwell``; past the plan's end phi_d descends at ``touchdown_rate_deg``.
        """
        if self._hold is not None:
            return self._hold
        ref = self.track.reference(t)
        if self.maneuver is Maneuver.TAKEOFF:
            return ref
        m = self.scenario.mission
        T = self.plan.duration
        out = ref.output
        if t >= T:
            rate, depth = math.radians(m.touchdown_rate_deg), math.radians(m.touchdown_search_deg)
            s = min(rate * (t - T), depth)
            out = out.copy()
            out[0, 0] -= s
            out[1, 0] = -rate if s < depth else 0.0
            ref = Reference(t=t, mode=ControlMode.TETHERED, output=out, thrust_ff=ref.thrust_ff,
                            feedforward=ref.feedforward)  # fmt: skip
        link = est.link
        near = link is not None and link.phi - self._phi_star < math.radians(m.contact_gate_deg)
        if t > (1.0 - m.contact_window) * T and near:
            if self._contact.update(t, link.phi - out[0, 0]):
                hold = np.zeros((5, 4))
                hold[0] = out[0]
                hold[0, 0] = link.phi
                self._hold = Reference(
                    t=t, mode=ControlMode.TETHERED, output=hold, thrust_ff=ref.thrust_ff,
                    feedforward=ref.feedforward,
                )  # fmt: skip
                return self._hold
        else:
            self._contact.reset()
        return ref
