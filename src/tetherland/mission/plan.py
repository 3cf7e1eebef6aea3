"""The mission plan: everything fixed before the mission flies (chapter 6.6.2).

:func:`plan_mission` turns the believed scenario and the start pad into a frozen
:class:`MissionPlan`: the verified landing and takeoff trajectories (OCP (6.21)), the
free-flight waypoints of the hooking, stretching and return legs, and the clearance of the
hooking pass. The supervisor (:mod:`tetherland.mission.supervisor`) only executes it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tetherland.analysis.clearance import HookingClearance
from tetherland.config import Scenario
from tetherland.errors import InfeasibleError
from tetherland.geometry import FloatArray, LandingGeometry, link_direction
from tetherland.mission.hooking import check_pass, hooking_pass
from tetherland.planning import Maneuver, Planner, PlanResult
from tetherland.planning.trajectory import Trajectory
from tetherland.rotations import rotation_from_z_and_yaw
from tetherland.state import RigidBodyState

Z_W = np.array([0.0, 0.0, 1.0])
Z_W.setflags(write=False)


class MissionError(InfeasibleError):
    """The mission cannot start (e.g. no feasible landing or takeoff plan)."""


@dataclass(frozen=True)
class Waypoints:
    """Centre-of-mass points of the free-flight legs, F_W [m].

    Attributes
    ----------
    start : (3,) array
        On the start pad.
    hook_start, hook_end : (3,) array
        Ends of the straight hooking pass: the hook point ``approach_distance`` before and
        ``hook_overshoot`` beyond the anchor along the approach direction, in level flight.
    slack_out : (3,) array
        Inside the cable length, on the line of the planned start elevation.
    stretch : (3,) array
        Just beyond the cable length: the pull that makes the cable taut (phase (c)).
    z_safe : float
        Height of the transfers between the pad and the anchor [m].
    yaw : float
        Heading of every free-flight leg: x_B along x_A, downhill [rad].
    attachment_W : (3,) array
        Cable attachment point relative to the centre of mass in level flight [m].
    """

    start: FloatArray
    hook_start: FloatArray
    hook_end: FloatArray
    slack_out: FloatArray
    stretch: FloatArray
    z_safe: float
    yaw: float
    attachment_W: FloatArray


@dataclass(frozen=True)
class MissionPlan:
    """The frozen plan of one mission (see the module docstring).

    Attributes
    ----------
    start : RigidBodyState
        The vehicle at rest on the start pad.
    geometry : LandingGeometry
        The believed landing geometry (anchor, landing point, phi*).
    landing, takeoff : PlanResult
        Verified plans of the tethered landing and takeoff.
    waypoints : Waypoints
    clearance : HookingClearance
        Clearance of the frame from the surface along the hooking pass.
    """

    start: RigidBodyState
    geometry: LandingGeometry
    landing: PlanResult
    takeoff: PlanResult
    waypoints: Waypoints
    clearance: HookingClearance

    @property
    def landing_trajectory(self) -> Trajectory:
        return self.landing.require()

    @property
    def takeoff_trajectory(self) -> Trajectory:
        return self.takeoff.require()


def _frozen(v: FloatArray) -> FloatArray:
    a = np.array(v, dtype=float)
    a.setflags(write=False)
    return a


def plan_mission(
    scenario: Scenario, start: RigidBodyState, planner: Planner | None = None
) -> MissionPlan:
    """Plan the mission of section 6.6 on the believed ``scenario`` from ``start``.

    Raises
    ------
    MissionError
        No verified landing or takeoff plan, or a hooking pass that would hit the surface
        (the message names the ``tether.hook_drop`` the surface needs).
    """
    cfg = scenario.mission
    v = scenario.vehicle
    geo = LandingGeometry.from_scenario(scenario)
    planner = planner or Planner()
    landing = planner.plan(scenario, Maneuver.LANDING)
    takeoff = planner.plan(scenario, Maneuver.TAKEOFF)
    for result in (landing, takeoff):
        if not result.success:
            raise MissionError(f"no {result.maneuver.value} plan: {result.message}")
    R_WA = geo.R_WA
    hooking = hooking_pass(scenario, geo)
    yaw = hooking.yaw
    attachment_W = rotation_from_z_and_yaw(Z_W, yaw) @ np.asarray(v.cable_attachment, float)
    p_A = geo.p_A
    p_start = np.asarray(start.p_W, dtype=float)
    hook_start, hook_end = hooking.p_start_W, hooking.p_end_W
    clearance = check_pass(scenario, geo, hooking)
    if not clearance.ok:
        t = scenario.tether
        raise MissionError(
            f"tether.hook_drop = {t.hook_drop:g} m is too short for this "
            f"{math.degrees(geo.surface.slope):.1f} deg surface: the frame would pass "
            f"{clearance.clearance_m * 100:.1f} cm from it while hooking (needs >= "
            f"{clearance.margin_m * 100:.0f} cm); use hook_drop >= "
            f"{clearance.required_hook_drop_m:.2f} m with hook_drop + capture_radius < "
            f"length = {t.length:g} m"
        )
    length = scenario.tether.length
    phi0 = float(landing.require().output(0.0).phi[0])
    d0 = R_WA @ link_direction(phi0, 0.0)
    wn = scenario.controller.free_flight.position_frequency
    pull = scenario.planner.start_tension / (v.mass * wn * wn) + cfg.stretch_margin
    waypoints = Waypoints(
        start=_frozen(p_start),
        hook_start=_frozen(hook_start),
        hook_end=_frozen(hook_end),
        slack_out=_frozen(p_A + (length - cfg.slack_out_distance) * d0 - attachment_W),
        stretch=_frozen(p_A + (length + pull) * d0 - attachment_W),
        z_safe=max(float(hook_start[2]), float(p_start[2]) + cfg.takeoff_height)
        + cfg.safe_height_margin,
        yaw=yaw,
        attachment_W=_frozen(attachment_W),
    )
    return MissionPlan(
        start=start,
        geometry=geo, landing=landing, takeoff=takeoff, waypoints=waypoints, clearance=clearance
    )
