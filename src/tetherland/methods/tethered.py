"""The tethered method of chapter 6.6: hook, stretch, land in inclined hovering, take off."""

from __future__ import annotations

from dataclasses import replace

from tetherland.config import Scenario
from tetherland.control import SwitchingController
from tetherland.methods.base import ControllerChoice, Flight, Planners
from tetherland.mission import MissionPlan, MissionSupervisor, Phase, plan_mission
from tetherland.planning.trajectory import Trajectory
from tetherland.state import RigidBodyState
from tetherland.verdict.record import Expectations, PhaseSpan, RunRecord, SwitchSpan

DIAGNOSTICS = (
    "e_phi", "e_delta", "e_theta_A", "e_psi", "singular", "saturation", "e_x", "e_y", "e_z",
    "ff_tension",
)  # fmt: skip
"""Controller diagnostics recorded as ``diag.<key>`` log columns."""


class TetheredMethod:
    """Plan the mission, fly it with the supervisor and the switching controller."""

    name = "tethered"
    expects = Expectations(required_conditions=(1, 2, 3, 4, 5), tension=True, takeoff=True,
                           return_home=True)  # fmt: skip

    def plan(self, belief: Scenario, start: RigidBodyState, planners: Planners) -> MissionPlan:
        return plan_mission(belief, start, planners.tethered)

    def fly(self, plan: MissionPlan, belief: Scenario, controller: ControllerChoice) -> Flight:
        return Flight(
            reference=MissionSupervisor(belief, plan),
            controller=SwitchingController(belief, controller or belief.controller.kind),
            initial_state=plan.start,
            rotor_speeds=None,
            duration=belief.mission.time_limit,
            diagnostic_keys=DIAGNOSTICS,
        )

    def trajectories(self, plan: MissionPlan) -> dict[str, Trajectory]:
        return {
            "landing_trajectory": plan.landing_trajectory,
            "takeoff_trajectory": plan.takeoff_trajectory,
        }

    def record(self, plan: MissionPlan, flight: Flight, t_end: float, base: RunRecord) -> RunRecord:
        sup = flight.reference
        ctrl = flight.controller
        assert isinstance(sup, MissionSupervisor) and isinstance(ctrl, SwitchingController)
        sup.finish(t_end)
        takeoff = plan.takeoff_trajectory
        return replace(
            base,
            phase_codes={p.name.lower(): int(p) for p in Phase},
            tension_phases=("tethered_landing", "tethered_takeoff"),
            tethered_phases=("tethered_landing", "touchdown", "spin_up", "tethered_takeoff"),
            phases=tuple(
                PhaseSpan(r.phase.name.lower(), r.start, r.end, r.exit_reason) for r in sup.records
            ),
            times=dict(sup.times),
            abort_reason=sup.abort_reason,
            safe_state=sup.safe_state,
            finished=any(r.phase == Phase.DONE for r in sup.records),
            takeoff_target=tuple(float(x) for x in takeoff.output(takeoff.duration).value),
            home_pad_W=tuple(float(x) for x in plan.waypoints.start),
            hook_attempts=sup.hook_attempts,
            switches=tuple(
                SwitchSpan(
                    s.t, s.from_mode.name.lower(), s.to_mode.name.lower(), s.thrust_jump,
                    s.rotor_speed_jump,
                )
                for s in ctrl.switches
            ),
            plans={"landing": plan.landing.summary(), "takeoff": plan.takeoff.summary()},
        )
