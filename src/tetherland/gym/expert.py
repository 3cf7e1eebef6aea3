"""The expert: the OCP plan tracked by the hierarchical controller, as a policy.

It maps an observation of :class:`~tetherland.gym.env.TetheredEnv` to an action, for
learning from demonstration. It holds the plan (a :class:`TrajectoryTrack` started at
t = 0) and the mission's :class:`~tetherland.control.SwitchingController` in tethered mode.
Landing ends as the mission's touchdown phase does, by the same rule
(:mod:`tetherland.mission.contact`): contact is confirmed near the end of the plan, and
past it in a guarded descent that lowers phi_d at ``mission.touchdown.descent_rate_deg_s``, when the
clearance, the link stall and (if the estimate carries it) the surface force agree; the
expert then holds the link where it touched for ``mission.settle_time`` and idles the
rotors at f_min (the action's zero: the motors-off of the mission). An observation holds
no external force, so the expert's rule uses the clearance and the link stall. Takeoff
holds the planned end hover.

The expert is a robot like the mission's: it plans and controls on what it believes.
:meth:`ExpertPolicy.for_env` gives it the env's *belief* (``env.belief``, the scenario
its estimator believes: perturbed with ``randomize=True``), re-read and re-planned at
every :meth:`ExpertPolicy.reset`; the truth the plant simulates never reaches it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from tetherland.config import Scenario
from tetherland.control import SwitchingController
from tetherland.control.ground_effect import GroundEffectCompensation
from tetherland.geometry import FloatArray
from tetherland.gym.env import estimate_of
from tetherland.interfaces import Reference
from tetherland.mission.contact import (
    ContactRule,
    contact_hold,
    early_contact_armed,
    guarded_descent,
)
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
        planner: Planner | None = None,
    ) -> None:
        self.maneuver = Maneuver(maneuver)
        self.kind = controller
        self._planner = planner
        self._belief_source: Callable[[], Scenario] | None = None
        self._believe(scenario, plan)
        self.reset()

    @classmethod
    def for_env(
        cls, env: Any, controller: str | None = None, planner: Planner | None = None
    ) -> ExpertPolicy:
        """The expert of a :class:`TetheredEnv` (or a wrapper of one), on its belief.

        It plans and controls on ``env.belief`` (never on the truth the plant simulates)
        and reads it again at every :meth:`reset`, re-planning when a ``randomize`` env
        drew another belief. ``planner`` (default: the env's) keeps the compiled solvers.
        """
        e = env.unwrapped
        expert = cls(e.belief, e.maneuver, controller=controller,
                     planner=planner or e.planner)  # fmt: skip
        expert._belief_source = lambda: e.belief
        return expert

    def _believe(self, scenario: Scenario, plan: Trajectory | None = None) -> None:
        """Plan (unless given) and set up the tracking for a believed scenario."""
        if plan is None:
            self._planner = self._planner or Planner()
            plan = self._planner.plan(scenario, self.maneuver).require()
        self.scenario = scenario
        self.plan = plan
        self.track = TrajectoryTrack(plan, 0.0, scenario.controller.rate_hz)
        v = scenario.vehicle
        self.rotors = RotorModel.from_config(v)
        self._f_min, self._f_span = v.f_min, v.f_max - v.f_min

    def reset(self) -> None:
        """Start a new episode (fresh controller state, no touchdown yet); an expert of an
        env first takes up the env's current belief."""
        if self._belief_source is not None:
            belief = self._belief_source()
            if belief != self.scenario:
                self._believe(belief)
        controller = SwitchingController(self.scenario, self.kind)
        if self.scenario.controller.ground_effect_compensation:  # as the mission composes it
            controller = GroundEffectCompensation(controller, self.scenario)
        self.controller = controller
        self._contact = ContactRule(self.scenario)
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

        As the mission's supervisor (:class:`~tetherland.mission.contact.ContactRule`):
        contact counts from the last ``mission.contact.window`` of the plan on; past the
        plan's end phi_d descends at ``mission.touchdown.descent_rate_deg_s``.
        """
        if self._hold is not None:
            return self._hold
        ref = self.track.reference(t)
        if self.maneuver is Maneuver.TAKEOFF:
            return ref
        m = self.scenario.mission
        T = self.plan.duration
        if t >= T:
            ref = guarded_descent(m.touchdown, ref, t - T, ref.phase)
        if early_contact_armed(m.contact, t, 0.0, T):
            if self._contact.update(t, est, ref.output[0, 0]).confirmed:
                self._hold = contact_hold(m.contact, t, est, ref, ref.phase)
                return self._hold
        else:
            self._contact.idle()
        return ref
