"""The mission plan: everything fixed before the mission flies (chapter 6.6.2).

:func:`plan_mission` turns the believed scenario and the start pad into a frozen
:class:`MissionPlan`: the verified landing and takeoff trajectories (OCP (6.21)), the
free-flight waypoints of the hooking, stretching and return legs, and the clearance of the
hooking pass. The supervisor (:mod:`tetherland.mission.supervisor`) only executes it.
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass

import numpy as np

from tetherland import GRAVITY
from tetherland.analysis.clearance import (
    MECHANISM_MARGIN,
    HookingClearance,
    VehicleClearance,
    level_clearance,
)
from tetherland.config import Scenario
from tetherland.errors import InfeasibleError
from tetherland.geometry import (
    FloatArray,
    LandingGeometry,
    approach_at_elevation_A,
    link_direction,
)
from tetherland.mission.hooking import (
    bar_seating_path,
    check_pass,
    hooking_pass,
    hooking_pass_for,
    magnet_pull_out_path,
    pass_overshoot,
    takeoff_height,
    unhook_depth,
    unhooking_path,
)
from tetherland.mission.paths import segment_duration
from tetherland.models.hook import MagnetWhere, magnet_reach_margin
from tetherland.planning import Maneuver, Planner, PlanResult
from tetherland.planning.trajectory import Trajectory
from tetherland.rotations import rotation_from_z_and_yaw
from tetherland.state import RigidBodyState
from tetherland.surface import Surface

Z_W = np.array([0.0, 0.0, 1.0])
Z_W.setflags(write=False)
SLACK_MIN = 0.01
"""Least slack of the take-up and release points, whatever the surface asks [m]."""
LEG_SAMPLE_SPACING = 0.05
"""Spacing of the points at which a leg's clearance from a pipe is evaluated [m] (a
plane's distance is concave along a straight leg, so a leg's ends suffice)."""


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
    unhook_entry : (3,) array
        On the pass axis with the hook point ``mission.hooking.unhook_depth`` beyond the anchor:
        where the reverse (unhooking) pass begins
        (:func:`tetherland.mission.hooking.unhooking_path`).
    slack_out : (3,) array
        Inside the cable length (``mission.stretch.slack_out_distance``, or less where the frame
        needs it to clear the surface), on the line of the planned start elevation.
    stretch : (3,) array
        Just beyond the cable length: the pull that makes the cable taut (phase (c)).
    release_distance : float
        Distance of the attachment point from the anchor at the end of the release leg,
        along the cable: ``mission.hooking.release_slack`` inside the cable length, or less where
        the frame needs it to clear the surface (short cables on walls) [m].
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
    unhook_entry: FloatArray
    slack_out: FloatArray
    stretch: FloatArray
    release_distance: float
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
    leg_clearance_m : float
        Smallest clearance of the level vehicle from the surface along the other
        free-flight legs: approach, stretch, release and return [m].
    """

    start: RigidBodyState
    geometry: LandingGeometry
    landing: PlanResult
    takeoff: PlanResult
    waypoints: Waypoints
    clearance: HookingClearance
    leg_clearance_m: float

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


def _leg_points(surface: Surface, leg: list[FloatArray]) -> list[FloatArray]:
    """The points of a polyline at which its clearance is evaluated (see
    :data:`LEG_SAMPLE_SPACING`)."""
    if surface.kind != "pipe":
        return leg
    points = [leg[0]]
    for a, b in itertools.pairwise(leg):
        count = max(1, math.ceil(float(np.linalg.norm(b - a)) / LEG_SAMPLE_SPACING))
        points.extend(a + (b - a) * k / count for k in range(1, count + 1))
    return points


def _leg_clearance(
    scenario: Scenario, surface: Surface, leg: list[FloatArray], yaw: float, magnet: MagnetWhere
) -> VehicleClearance:
    """Smallest distances of the level vehicle and of its mechanism's parts (the magnet
    being where ``magnet`` says) from the surface along a polyline of centre-of-mass
    points [m]."""
    return functools.reduce(
        VehicleClearance.least,
        (level_clearance(scenario, surface, p, yaw, magnet) for p in _leg_points(surface, leg)),
    )


def _clear_radius(
    scenario: Scenario,
    geo: LandingGeometry,
    d_W: FloatArray,
    attachment_W: FloatArray,
    yaw: float,
    r_wanted: float,
    margin: float,
    r_max: float,
) -> float | None:
    """Distance r along the cable direction ``d_W`` for a waypoint p_A + r d - r_att: the
    wanted ``r_wanted`` if the level vehicle there keeps ``margin`` from the surface, else
    the smallest r up to ``r_max`` that does (bisection: the clearance grows along a
    direction pointing away from the surface), None if none does [m]. The vehicle has
    hooked: the magnet mechanism's magnet is on the plate, and its empty boom must not go
    behind the surface (:meth:`VehicleClearance.keeps`)."""
    length = r_max

    def clear(r: float) -> bool:
        p = geo.p_A + r * d_W - attachment_W
        return level_clearance(scenario, geo.surface, p, yaw, "held").keeps(margin)

    if clear(r_wanted):
        return r_wanted
    if not clear(length):
        return None
    lo, hi = r_wanted, length
    while hi - lo > 1e-4:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if clear(mid) else (mid, hi)
    return hi


LEG_MAGNET: dict[str, MagnetWhere] = {
    "approach": "clipped",
    "stretch": "held",
    "release": "held",
    "return": "hanging",
}
"""Where the magnet mechanism's magnet is on each of :func:`free_flight_legs`: the legs'
clearance checks include its boom, and on the approach the magnet clipped on it."""

HOOK_DROP_STEP = 0.01
"""Step of the hook drops :func:`working_hook_drop` tries [m]."""


def design_hint(scenario: Scenario) -> str:
    """The command that finds a design for ``scenario``'s vehicle and surface."""
    approach = (  # the magnet's eye sits on its boom's tip: no hook drop
        "tether.approach_direction"
        if scenario.mechanism.kind == "magnet"
        else "tether.approach_direction, tether.hook_drop"
    )
    return (
        f"`tetherland design {scenario.name}` (with the same --set values) finds a cable length, "
        f"attachment, anchor height and hooking approach ({approach}) that work"
    )


def working_hook_drop(scenario: Scenario, geo: LandingGeometry, first: float) -> float | None:
    """The shortest hook drop from ``first`` [m] up, in steps of :data:`HOOK_DROP_STEP`, whose
    hooking pass keeps ``mission.hooking.min_clearance`` with hook_drop + capture_radius <
    length (None: none does)."""
    t, cfg = scenario.tether, scenario.mission.hooking
    k = max(math.ceil(first / HOOK_DROP_STEP - 1e-9), 0)
    while (drop := round(k * HOOK_DROP_STEP, 6)) + t.capture_radius < t.length:
        trial = hooking_pass_for(
            geo, approach_A=t.approach_direction, hook_drop=drop,
            r_att_B=scenario.vehicle.cable_attachment, approach_distance=cfg.approach_distance,
            hook_overshoot=cfg.overshoot,
        )  # fmt: skip
        if check_pass(scenario, geo, trial).ok:
            return drop
        k += 1
    return None


def _check_magnet_reach(scenario: Scenario) -> None:
    """The magnet's unfolded face must reach beyond every part of the airframe along the
    approach direction (:func:`tetherland.models.hook.magnet_reach_margin`, the plant's
    collision shapes), or the frame meets the wall first: :class:`MissionError`."""
    m = scenario.mechanism
    if m.kind != "magnet":
        return
    margin = magnet_reach_margin(scenario)
    if margin <= 0.0:
        raise MissionError(
            f"mechanism.boom_length = {m.boom_length:g} m at boom_angle_deg = "
            f"{m.boom_angle_deg:g} reaches {-margin:g} m short of the vehicle's farthest "
            "part along tether.approach_direction: the magnet must meet the surface first"
        )


def pass_clearance_message(
    scenario: Scenario, geo: LandingGeometry, clearance: HookingClearance
) -> str:
    """One line for a hooking pass that would bring the frame within
    ``mission.hooking.min_clearance`` of the surface, naming what to change: the hook drop
    that restores the clearance for the capture disk and the bar, the approach along the
    surface's normal for the magnet (its eye sits on the boom's tip, so ``tether.hook_drop``
    plays no part), and otherwise ``tetherland design``."""
    t = scenario.tether
    slope = math.degrees(geo.surface.slope)
    passing = (
        f"the frame would pass {clearance.clearance_m * 100:.1f} cm from it while hooking "
        f"(needs >= {clearance.margin_m * 100:.0f} cm)"
    )
    if scenario.mechanism.kind == "magnet":
        normal = approach_at_elevation_A(math.pi / 2 - geo.surface.slope)  # the normal
        written = ",".join(f"{v:g}" for v in normal)
        along = np.asarray(t.approach_direction, float) / np.linalg.norm(t.approach_direction)
        fix = (
            f"approach along the surface's normal, --set 'tether.approach_direction=[{written}]', "
            f"or {design_hint(scenario)}"
            if float(along @ np.asarray(normal)) < 1.0 - 1e-6
            else design_hint(scenario)
        )
        return (
            f"tether.approach_direction = [{','.join(f'{v:g}' for v in t.approach_direction)}] "
            f"presses the magnet on this {slope:.1f} deg surface but {passing}: {fix}"
        )
    drop = working_hook_drop(scenario, geo, clearance.required_hook_drop_m)
    fix = (
        f"set tether.hook_drop={drop:g}"
        if drop is not None
        else f"no hook drop fits inside tether.length = {t.length:g} m (with "
        f"capture_radius {t.capture_radius:g} m); {design_hint(scenario)}"
    )
    return (
        f"tether.hook_drop = {t.hook_drop:g} m is too short for this {slope:.1f} deg "
        f"surface: {passing}: {fix}"
    )


def plan_mission(
    scenario: Scenario, start: RigidBodyState, planner: Planner | None = None
) -> MissionPlan:
    """Plan the mission of section 6.6 on the believed ``scenario`` from ``start``.

    Raises
    ------
    MissionError
        No verified landing or takeoff plan, a hooking pass that would hit the surface
        (the message names the ``tether.hook_drop`` the surface needs), or another
        free-flight leg that would pass closer to the surface than
        ``mission.hooking.min_clearance`` (the message names the leg).
    """
    cfg = scenario.mission
    v = scenario.vehicle
    _check_magnet_reach(scenario)
    geo = LandingGeometry.from_scenario(scenario)
    planner = planner or Planner()
    landing = planner.plan(scenario, Maneuver.LANDING)
    takeoff = planner.plan(scenario, Maneuver.TAKEOFF)
    for result in (landing, takeoff):
        if not result.success:
            raise MissionError(
                f"no {result.maneuver.value} plan: {result.message}; {design_hint(scenario)}"
            )
    R_WA = geo.R_WA
    hooking = hooking_pass(scenario, geo)
    yaw = hooking.yaw
    attachment_W = rotation_from_z_and_yaw(Z_W, yaw) @ np.asarray(v.cable_attachment, float)
    p_A = geo.p_A
    p_start = np.asarray(start.p_W, dtype=float)
    hook_start, hook_end = hooking.p_start_W, hooking.p_end_W
    clearance = check_pass(scenario, geo, hooking)
    if not clearance.ok:
        raise MissionError(pass_clearance_message(scenario, geo, clearance))
    length = scenario.tether.length
    phi0 = float(landing.require().output(0.0).phi[0])
    d0 = R_WA @ link_direction(phi0, 0.0)
    takeoff_traj = takeoff.require()
    d_T = R_WA @ link_direction(float(takeoff_traj.output(takeoff_traj.duration).phi[0]), 0.0)
    wn = scenario.controller.free_flight.position_frequency
    pull = scenario.planner.start_tension / (v.mass * wn * wn) + cfg.stretch.pull_margin
    # On short cables near walls the frame limits how far inside the cable length the
    # take-up and the release may go (the default distances would put it into the wall):
    # there they keep the clearance of the hooking pass's end (at least
    # mission.hooking.min_clearance) and stop at least SLACK_MIN short of the cable length.
    keep = max(clearance.clearance_m, cfg.hooking.min_clearance)
    radii = []
    for d_W, inside in ((d0, cfg.stretch.slack_out_distance), (d_T, cfg.hooking.release_slack)):
        wanted = length - inside
        r = _clear_radius(scenario, geo, d_W, attachment_W, yaw, wanted, keep, length - SLACK_MIN)
        if r is None:
            r = _clear_radius(
                scenario, geo, d_W, attachment_W, yaw, wanted, cfg.hooking.min_clearance,
                length - SLACK_MIN,
            )  # fmt: skip
        radii.append(r)
    r_slack, r_release = radii
    for r, what, d_W in ((r_slack, "cable take-up at the planned start", d0),
                         (r_release, "release at the planned takeoff end", d_T)):  # fmt: skip
        if r is None:
            p = p_A + (length - SLACK_MIN) * d_W - attachment_W
            far = level_clearance(scenario, geo.surface, p, yaw, "held")
            parts = (
                f"would bring the frame within mission.hooking.min_clearance = "
                f"{cfg.hooking.min_clearance * 100:.0f} cm of the surface"
                if far.frame_m < cfg.hooking.min_clearance
                else "would put the magnet's boom behind the surface, however far it folds "
                f"(mechanism.boom_fold_deg = {scenario.mechanism.boom_fold_deg:g})"
            )
            raise MissionError(
                f"the {what} {parts} anywhere more than {SLACK_MIN * 100:.0f} cm inside the "
                f"cable length {length:g} m; " + design_hint(scenario)
            )
    assert r_slack is not None and r_release is not None
    z_safe = max(float(hook_start[2]), float(p_start[2]) + takeoff_height(scenario))
    z_safe += cfg.flight.safe_height_margin
    waypoints = Waypoints(
        start=_frozen(p_start),
        hook_start=_frozen(hook_start),
        hook_end=_frozen(hook_end),
        unhook_entry=_frozen(hooking.entry(unhook_depth(scenario), pass_overshoot(scenario),
                                           beyond=scenario.mechanism.kind == "bar")),
        slack_out=_frozen(p_A + r_slack * d0 - attachment_W),
        stretch=_frozen(p_A + (length + pull) * d0 - attachment_W),
        release_distance=r_release,
        z_safe=z_safe,
        yaw=yaw,
        attachment_W=_frozen(attachment_W),
    )
    leg_clearance = _check_legs(scenario, geo, waypoints, d_T)
    _check_stretch_tension(scenario, d0)
    _check_duration(scenario, mission_time_bound(scenario, geo, waypoints, d_T, landing, takeoff))
    return MissionPlan(
        start=start, geometry=geo, landing=landing, takeoff=takeoff, waypoints=waypoints,
        clearance=clearance, leg_clearance_m=leg_clearance,
    )  # fmt: skip


def unhook_reach(
    scenario: Scenario, geo: LandingGeometry, wp: Waypoints
) -> tuple[FloatArray, float]:
    """Where the centre of mass may go while the cable is still hooked and must stay slack:
    the ball about the anchor less the attachment offset, of radius l less ``SLACK_MIN``
    (the ``reach`` of :func:`tetherland.mission.hooking.unhooking_path`) [m]."""
    return geo.p_A - wp.attachment_W, scenario.tether.length - SLACK_MIN


def take_up_path(
    scenario: Scenario, geo: LandingGeometry, wp: Waypoints
) -> list[tuple[FloatArray, float | None]]:
    """The take-up after the hooking pass up to the stretch (not included): centre-of-mass
    corners F_W [m] and their speeds [m/s] (None: the take-up's). The slack point, or with
    the bar the seating path (:func:`tetherland.mission.hooking.bar_seating_path`), or with
    the magnet its pull-out (:func:`tetherland.mission.hooking.magnet_pull_out_path`) and
    then the slack point. The path of :mod:`tetherland.mission.supervisor`."""
    kind = scenario.mechanism.kind
    if kind == "bar":
        return bar_seating_path(
            scenario, geo.p_A, geo.R_WA[:, 0], wp.hook_end, wp.stretch, wp.attachment_W
        )
    pull_out = magnet_pull_out_path(scenario, wp.hook_end, geo.R_WA) if kind == "magnet" else []
    return [*((c, None) for c in pull_out), (wp.slack_out, None)]


def free_flight_legs(
    scenario: Scenario, geo: LandingGeometry, wp: Waypoints, d_T_W: FloatArray
) -> dict[str, list[FloatArray]]:
    """The centre-of-mass polylines the supervisor flies in free flight, apart from the
    hooking pass (its own check) and the tethered phases (the plans), F_W [m].

    The release leg starts at its slack point, on the planned takeoff end direction
    ``d_T_W`` (the supervisor uses the estimated direction there), and is the unhooking
    pass from there (its last stretch, the reverse hooking pass, is also checked as part
    of the hooking pass). The magnet's stretch leg starts where its pull-out has drawn the
    boom's tip out of the magnet on the plate (from the pass's end to there the tip is at
    the plate by design, as at the pass's end). The paths are those of
    :mod:`tetherland.mission.supervisor`.
    """
    top = wp.start + takeoff_height(scenario) * Z_W
    over_hook = np.array([*wp.hook_start[:2], wp.z_safe])
    release = geo.p_A + wp.release_distance * d_T_W - wp.attachment_W
    take_up = [c for c, _ in take_up_path(scenario, geo, wp)]
    first = [] if scenario.mechanism.kind == "magnet" else [wp.hook_end]
    return {
        "approach": [top, np.array([*top[:2], wp.z_safe]), over_hook, wp.hook_start],
        "stretch": [*first, *take_up, wp.stretch],
        "release": unhooking_path(
            release, wp.unhook_entry, wp.hook_start, unhook_reach(scenario, geo, wp),
            back_off=scenario.mechanism.kind != "bar",
        ),
        "return": [wp.hook_start, over_hook, np.array([*wp.start[:2], wp.z_safe]), top],
    }


def rotor_tension_limit(scenario: Scenario, d_W: FloatArray) -> float:
    """Largest cable tension the rotors can hold with the cable along ``d_W`` [N].

    ``d_W`` is the unit direction from the anchor to the vehicle; the cable pulls the
    vehicle back along -d, so the thrust must be m g z_W + T d. With the total thrust
    |f| <= 4 f_max: T = -m g c + sqrt(F^2 - (m g)^2 (1 - c^2)), c = z_W . d; with the
    free-flight tilt limit theta (horizontal thrust <= tan(theta) x vertical thrust):
    T (|d_h| - tan(theta) c) <= tan(theta) m g.
    """
    v = scenario.vehicle
    w = v.mass * GRAVITY
    c = float(d_W @ Z_W)
    f_max = 4.0 * v.f_max
    limit = -w * c + math.sqrt(max(f_max * f_max - w * w * (1.0 - c * c), 0.0))
    tan = math.tan(math.radians(scenario.controller.free_flight.max_tilt_deg))
    lean = math.sqrt(max(1.0 - c * c, 0.0)) - tan * c
    if lean > 0.0:
        limit = min(limit, tan * w / lean)
    return limit


def _check_stretch_tension(scenario: Scenario, d0_W: FloatArray) -> None:
    """The supervisor's ``mission.stretch.tension_threshold`` is within what the rotors can pull
    along the planned start direction of the cable (else the hook counts as missed)."""
    threshold = scenario.mission.stretch.tension_threshold
    limit = rotor_tension_limit(scenario, d0_W)
    if threshold >= limit:
        raise MissionError(
            f"mission.stretch.tension_threshold = {threshold:g} N: the rotors can hold at most "
            f"{limit:.3g} N of tension along the cable at the planned start (4 x f_max = "
            f"{4 * scenario.vehicle.f_max:g} N, max_tilt_deg "
            f"{scenario.controller.free_flight.max_tilt_deg:g}); the hook would count as "
            f"missed: set mission.stretch.tension_threshold={math.floor(50 * limit) / 100:g}"
        )


def mission_time_bound(
    scenario: Scenario,
    geo: LandingGeometry,
    wp: Waypoints,
    d_T_W: FloatArray,
    landing: PlanResult,
    takeoff: PlanResult,
) -> float:
    """A lower bound on the nominal mission's duration [s].

    The planned landing and takeoff; the fixed holds (deploy, spin-up, the final hold on
    the pad, the ``settle_time`` pause after the climb, the approach, the hooking pass,
    the unhooking, the return and the landing on the pad); and the free-flight segments
    the supervisor flies rest to rest (:func:`tetherland.mission.paths.segment_duration`)
    at their speeds: the climb, the approach and the return at ``flight.cruise_speed``,
    the hooking pass, the unhooking and the descent onto the pad at ``hooking.speed``,
    the take-up before stretching at its fraction of the cruise speed. The stretch itself
    and the release's pull are left out (they end on the tension).
    """
    cfg = scenario.mission
    legs = free_flight_legs(scenario, geo, wp, d_T_W)
    fly, hook = cfg.flight, cfg.hooking
    top = wp.start + takeoff_height(scenario) * Z_W
    pad = wp.start - fly.pad_press_depth * Z_W
    take_up = cfg.stretch.take_up_speed_factor * fly.cruise_speed
    flown = [
        ([wp.start, top], fly.cruise_speed),
        (legs["approach"], fly.cruise_speed),
        ([wp.hook_start, wp.hook_end], hook.speed),
        *(
            ([a, b], speed or take_up)
            for (a, _), (b, speed) in itertools.pairwise(
                [(wp.hook_end, None), *take_up_path(scenario, geo, wp)]
            )
        ),
        (legs["release"], hook.speed),
        (legs["return"], fly.cruise_speed),
        ([top, pad], hook.speed),
    ]
    moving = sum(
        segment_duration(float(np.linalg.norm(b - a)), speed, fly.cruise_accel)
        for leg, speed in flown
        for a, b in itertools.pairwise(leg)
    )
    holds = cfg.deploy_time + cfg.spinup_time + cfg.done_hold_time + 6 * cfg.settle_time
    return landing.require().duration + takeoff.require().duration + holds + moving


def _check_duration(scenario: Scenario, bound: float) -> None:
    """The mission can end before ``mission.time_limit`` (else it would be cut off);
    ``bound`` from :func:`mission_time_bound` [s]."""
    cfg = scenario.mission
    if bound >= cfg.time_limit:
        raise MissionError(
            f"mission.time_limit = {cfg.time_limit:g} s is too short: the plans, "
            f"deploy_time {cfg.deploy_time:g} s and the flight legs take at least {bound:.0f} s; "
            f"set mission.time_limit={math.ceil(bound) + 1:d} (or shorten deploy_time)"
        )


def _check_legs(
    scenario: Scenario, geo: LandingGeometry, wp: Waypoints, d_T_W: FloatArray
) -> float:
    """Smallest clearance of the frame over :func:`free_flight_legs` [m]; raises
    :class:`MissionError` naming the first leg whose frame comes within
    ``mission.hooking.min_clearance`` of the surface or whose mechanism's parts (where the
    magnet is on the leg, :data:`LEG_MAGNET`) would go behind it
    (:data:`~tetherland.analysis.clearance.MECHANISM_MARGIN`)."""
    margin = scenario.mission.hooking.min_clearance
    smallest = math.inf
    for name, leg in free_flight_legs(scenario, geo, wp, d_T_W).items():
        clear = _leg_clearance(scenario, geo.surface, leg, wp.yaw, LEG_MAGNET[name])
        if clear.mechanism_m < MECHANISM_MARGIN - 1e-9:
            raise MissionError(
                f"the {name} leg would put the magnet's boom {-clear.mechanism_m * 100:.1f} cm "
                f"behind the surface; {design_hint(scenario)}"
            )
        c = clear.frame_m
        if c < margin - 1e-9:
            raise MissionError(
                f"the {name} leg would pass {c * 100:.1f} cm from the surface (needs >= "
                f"{margin * 100:.0f} cm, mission.hooking.min_clearance): move the start pad "
                f"(sim.start_position) or raise mission.flight.safe_height_margin; "
                + design_hint(scenario)
            )
        smallest = min(smallest, c)
    return smallest
