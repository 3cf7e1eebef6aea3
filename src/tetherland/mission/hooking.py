"""The hooking pass of a design and its clearance from the surface.

The pass is the one the mission supervisor flies (:func:`tetherland.mission.plan_mission`
puts its ends into the waypoints): the vehicle level with heading x_A,
the hook point moving straight along the approach direction n from ``approach_distance``
before the anchor to ``overshoot`` beyond it (``[mission.hooking]``).

Hook model assumed here: the hook point is the cable attachment point moved by
``hook_drop`` along n (:func:`tetherland.models.hook.hook_offset`, the one statement of it,
which the plant's hook model :mod:`tetherland.sim.hook` uses too).

The clearance is that of the plant's collision shape, computed by
:func:`tetherland.analysis.clearance.hooking_clearance`.

The unhooking pass (:func:`unhooking_path`) is the hooking pass in reverse, but no deeper
than it needs: the cable is released when the hook point crosses the capture plane back
(along -n, within the capture radius), so the pass begins on its axis with the hook point
only ``mission.hooking.unhook_depth`` beyond the plane (:meth:`HookingPass.entry`), not at the
pass's end ``overshoot`` beyond it. From the release point the vehicle first backs
off along -n to that depth (away from the surface: the approach runs toward it), then
moves across to the axis at that depth and out along -n. The frame so stays
``overshoot - unhook_depth`` farther from the surface than at the end of the hooking
pass, a margin for the belief errors (slope, anchor) and the release transient that the
pass's planned clearance alone does not cover.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland.analysis.clearance import HookingClearance, hooking_clearance
from tetherland.config import Scenario
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.mission.paths import ZVShaper
from tetherland.models.hook import (
    bar_hook_offset,
    bar_line_length,
    hook_offset,
    magnet_boom,
    swing_period,
    swing_period_magnet,
)
from tetherland.rotations import rotation_from_z_and_yaw

_Z_W = np.array([0.0, 0.0, 1.0])
SHORTEST_LEG = 0.5
"""Shortest free-flight leg of the mission with nothing swinging under the vehicle [s]."""
PIPE_SAMPLES = 9
"""Points along the pass at which a pipe's clearance is evaluated (a plane's is linear
along the straight pass, so its ends suffice)."""


@dataclass(frozen=True)
class HookingPass:
    """The straight hooking pass in F_W.

    Attributes
    ----------
    p_start_W, p_end_W : (3,) arrays
        Centre of mass at the start and the end of the pass [m].
    n_W : (3,) array
        Unit approach direction [-].
    yaw : float
        Heading of the level vehicle (x_B along x_A) [rad].
    """

    p_start_W: FloatArray
    p_end_W: FloatArray
    n_W: FloatArray
    yaw: float

    def entry(self, depth: float, overshoot: float, beyond: bool = False) -> FloatArray:
        """Centre of mass on the pass axis with the hook point ``depth`` beyond the capture
        plane, for a pass that ends ``overshoot`` beyond it (``depth`` is clipped to
        ``overshoot``, never beyond the pass's end, unless ``beyond``) [m]."""
        return self.p_end_W - (overshoot - (depth if beyond else min(depth, overshoot))) * self.n_W

    def points(self, count: int) -> FloatArray:
        """``count`` centre-of-mass points evenly along the pass, (count, 3) [m]."""
        s = np.linspace(0.0, 1.0, count)[:, None]
        return (1.0 - s) * self.p_start_W + s * self.p_end_W


def hooking_pass(scenario: Scenario, geometry: LandingGeometry | None = None) -> HookingPass:
    """The hooking pass of ``scenario`` (its tether, vehicle and mission settings)."""
    t, cfg = scenario.tether, scenario.mission
    geo = geometry or LandingGeometry.from_scenario(scenario)
    return hooking_pass_for(
        geo,
        approach_A=t.approach_direction,
        hook_drop=t.hook_drop,
        r_att_B=scenario.vehicle.cable_attachment,
        approach_distance=cfg.hooking.approach_distance,
        hook_overshoot=pass_overshoot(scenario),
        offset_W=scenario_hook_offset(scenario, geo),
    )


def scenario_hook_offset(scenario: Scenario, geometry: LandingGeometry) -> FloatArray:
    """Hook point minus attachment point of ``scenario``'s mechanism, level flight [m]:
    ``tether.hook_drop`` along n for the capture disk, the hanging hook beside the bar
    (:func:`tetherland.models.hook.bar_hook_offset`) for the bar, the cable's eye on the
    clipped magnet at the unfolded boom's tip (:func:`tetherland.models.hook.magnet_boom`,
    the geometry the plant builds) for the magnet: the boom stays on its stop in a nominal
    pass (the position loop yields to the magnet's push on the plate long before the
    boom's preload does), and folds only when pushed harder."""
    t, m = scenario.tether, scenario.mechanism
    if m.kind == "magnet":  # the eye on the unfolded boom's tip
        return geometry.R_WA @ magnet_boom(scenario).offset_B
    if m.kind == "bar":
        line = bar_line_length(t.length, m)
        return bar_hook_offset(geometry.R_WA[:, 0], line, m.hook_shank, m.pass_offset)
    n_W = geometry.R_WA @ np.asarray(t.approach_direction, dtype=float)
    return hook_offset(n_W / np.linalg.norm(n_W), t.hook_drop)


def hooking_pass_for(
    geometry: LandingGeometry,
    *,
    approach_A: ArrayLike,
    hook_drop: float,
    r_att_B: ArrayLike,
    approach_distance: float,
    hook_overshoot: float,
    offset_W: FloatArray | None = None,
) -> HookingPass:
    """The hooking pass for explicit tether and mission values.

    Parameters
    ----------
    approach_A : (3,) array
        Approach direction in F_A (any length, not zero) [-].
    hook_drop : float
        [m].
    r_att_B : (3,) array
        Cable attachment in F_B [m].
    approach_distance, hook_overshoot : float
        Hook-point distance before and beyond the anchor where the pass starts and ends [m].
    offset_W : (3,) array, optional
        Hook point minus attachment point, F_W, replacing ``hook_drop`` n (the bar
        mechanism, :func:`scenario_hook_offset`) [m].
    """
    R_WA = geometry.R_WA
    n_W = R_WA @ np.asarray(approach_A, dtype=float)
    n_W = n_W / np.linalg.norm(n_W)
    yaw = math.atan2(R_WA[1, 0], R_WA[0, 0])
    r_att_W = rotation_from_z_and_yaw(_Z_W, yaw) @ np.asarray(r_att_B, dtype=float)
    offset = hook_offset(n_W, hook_drop) if offset_W is None else np.asarray(offset_W)
    shift = offset + r_att_W
    return HookingPass(
        p_start_W=geometry.p_A - approach_distance * n_W - shift,
        p_end_W=geometry.p_A + hook_overshoot * n_W - shift,
        n_W=n_W,
        yaw=yaw,
    )


def unhooking_path(
    p_from_W: ArrayLike,
    entry_W: ArrayLike,
    hook_start_W: ArrayLike,
    reach: tuple[ArrayLike, float] | None = None,
    back_off: bool = True,
) -> list[FloatArray]:
    """Centre-of-mass corners of the unhooking pass from ``p_from_W`` (the release point),
    F_W [m].

    ``entry_W`` is the axis point where the reverse pass begins (:meth:`HookingPass.entry`),
    ``hook_start_W`` the start of the hooking pass; the axis runs from ``hook_start_W`` to
    ``entry_W`` along the approach direction n. If the release point lies deeper along n
    than the entry, the first corner is the release point backed off along -n towards the
    entry's depth; then the entry and the hooking start. No point of the path lies deeper
    along n than the deeper of the release point and the entry.

    ``reach`` = (c, R): the back-off stops where the centre of mass would leave the ball of
    radius R about c (the cable still hooked must stay slack: c is the anchor less the
    attachment offset, R the cable length less a margin). Along a vertical pass, backing
    off straight up from a release point beside the anchor would pull the cable taut; the
    segment from the corner to the entry stays in the ball when both ends are in it.

    ``back_off = False`` (the bar mechanism): no back-off corner, straight to the entry.
    Climbing on the landing side while the hook still sits on the bar would lift it by
    the line draped over the bar and catch it again; flown straight back over the bar,
    the line slides back and the hook drops out of its crook.
    """
    p0 = np.asarray(p_from_W, dtype=float)
    entry = np.asarray(entry_W, dtype=float)
    start = np.asarray(hook_start_W, dtype=float)
    axis = entry - start
    n_W = axis / np.linalg.norm(axis)
    excess = float(n_W @ (p0 - entry)) if back_off else 0.0
    if excess > 0.0 and reach is not None:
        c, R = np.asarray(reach[0], dtype=float), float(reach[1])
        # largest s in [0, excess] with |p0 - s n - c| <= R: s^2 - 2 b s + (|w|^2 - R^2) <= 0
        w = p0 - c
        b = float(n_W @ w)
        disc = b * b - (float(w @ w) - R * R)
        s_max = b + math.sqrt(disc) if disc >= 0.0 else 0.0
        excess = min(excess, max(s_max, 0.0))
    corners = [p0 - excess * n_W] if excess > 0.0 else []
    return [*corners, entry.copy(), start.copy()]


def magnet_pull_out_path(scenario: Scenario, hook_end_W: FloatArray,
                         R_WA: FloatArray) -> list[FloatArray]:  # fmt: skip
    """Centre-of-mass corners after the magnet's hooking pass, from its end ``hook_end_W``
    (the magnet switched on, held by the plate), F_W [m]: straight back along -n to
    where the magnet's eye is ``press_depth`` plus half the cable's slack behind the
    unfolded boom's tip, which pulls the magnet out of its clip along its axis (moved
    sideways instead, the clip would drag the held magnet along the plate). The slack
    d_max = sqrt(l^2 - L^2 sin^2 beta) - L cos beta is how far the vehicle can back off
    along -n from the eye on the tip before the cable (length l) comes taut."""
    m = scenario.mechanism
    boom = magnet_boom(scenario)
    L, beta = boom.length, boom.angle
    slack = math.sqrt(scenario.tether.length**2 - (L * math.sin(beta)) ** 2) - L * math.cos(beta)
    n_W = R_WA @ boom.n_B
    return [np.asarray(hook_end_W, dtype=float) - (m.press_depth + 0.5 * slack) * n_W]


DROP_CLEARANCE = 0.05
"""Horizontal clearance of the empty boom's tip from the surface at the drop point [m]."""


def magnet_drop_point(scenario: Scenario, geometry: LandingGeometry,
                      p_att_W: FloatArray) -> FloatArray:  # fmt: skip
    """Attachment point from which the robot lets go of the magnet held at p_A, F_W [m]:
    out from p_A, horizontally along the slack point ``p_att_W``'s side, by the boom's
    reach to the magnet's face plus :data:`DROP_CLEARANCE` (at the slack point the empty
    boom's tip grazed the wall, and every touch folded it and rocked the vehicle), and
    above p_A with the cable at 95 % of its length (if it reaches), so that the released
    magnet falls little before the cable takes it into a swing."""
    m = scenario.mechanism
    boom = magnet_boom(scenario)
    p_A = geometry.p_A
    d = np.asarray(p_att_W, dtype=float) - p_A
    e = np.array([d[0], d[1], 0.0])
    e /= max(float(np.linalg.norm(e)), 1e-9)
    out = boom.length * math.cos(boom.angle) + m.magnet_thickness + DROP_CLEARANCE
    reach = 0.95 * scenario.tether.length
    up = math.sqrt(max(reach * reach - out * out, 0.0))
    return p_A + out * e + np.array([0.0, 0.0, up])


DROP_ARC_STEP_DEG = 10.0
"""Largest turn about p_A between the waypoints of the arc to the drop point [deg]."""


def magnet_drop_path(scenario: Scenario, geometry: LandingGeometry,
                     p_att_W: FloatArray) -> list[FloatArray]:  # fmt: skip
    """Attachment points from the slack point ``p_att_W`` to the drop point
    (:func:`magnet_drop_point`), F_W [m]: straight away from p_A until the cable is at
    95 % of its length (if it is not), then up along that sphere about p_A, in the
    vertical plane through p_A and the slack point, to the drop point, a waypoint at least
    every :data:`DROP_ARC_STEP_DEG`. Of all paths that keep the cable from going taut this
    keeps the vehicle, and its empty boom, farthest out at each height. Flown straight,
    the chord passed nearer the surface: on an overhang, whose surface comes nearer with
    height, the boom's tip dragged over the wall and the plate for 0.9 s (overhang93
    campaign draw 2255857163) and the rotor fault monitor took its torque for a lost
    rotor."""
    drop = magnet_drop_point(scenario, geometry, p_att_W)
    p_A = geometry.p_A
    r = 0.95 * scenario.tether.length
    d = np.asarray(p_att_W, dtype=float) - p_A
    h = math.hypot(d[0], d[1])
    e = np.array([d[0], d[1], 0.0]) / max(h, 1e-9)  # as magnet_drop_point's
    z = np.array([0.0, 0.0, 1.0])
    points = []
    dist = float(np.linalg.norm(d))
    if dist < r:
        points.append(p_A + d * (r / max(dist, 1e-9)))  # radially out to the sphere
    start = math.atan2(float(d[2]), h)
    end = math.atan2(float(drop[2] - p_A[2]), float((drop - p_A) @ e))
    n = max(1, math.ceil(abs(end - start) / math.radians(DROP_ARC_STEP_DEG)))
    for k in range(1, n):
        a = start + (end - start) * k / n
        points.append(p_A + r * (math.cos(a) * e + math.sin(a) * z))
    points.append(drop)
    return points


def check_pass(
    scenario: Scenario, geometry: LandingGeometry, hooking: HookingPass
) -> HookingClearance:
    """Clearance of the level vehicle (``scenario``'s collision shape) from the surface of
    ``geometry`` along the hooking pass, against ``mission.hooking.min_clearance``, with the
    hook drop that would restore it."""
    count = PIPE_SAMPLES if geometry.surface.kind == "pipe" else 2
    points = hooking.points(count)
    margin = scenario.mission.hooking.min_clearance
    return hooking_clearance(scenario, geometry.surface, points, hooking.yaw, margin, hooking.n_W)


def pass_clearance(scenario: Scenario, geometry: LandingGeometry, hooking: HookingPass) -> float:
    """Smallest distance of the level vehicle from the surface along the hooking pass [m]."""
    return check_pass(scenario, geometry, hooking).clearance_m


def shortest_leg(scenario: Scenario) -> float:
    """Shortest free-flight leg of the mission [s]: 0.5 s, or with a hook hanging on a line
    (the bar mechanism) ``mechanism.swing_periods`` of its swing period
    (:func:`tetherland.models.hook.swing_period`): a rest-to-rest leg (9th-order
    smoothstep) that long leaves the hanging hook almost still, so that it passes beside
    the bar where the plan puts it."""
    m, t = scenario.mechanism, scenario.tether
    if m.kind == "magnet":
        return max(SHORTEST_LEG,
                   m.swing_periods * swing_period_magnet(t.length, m.magnet_thickness))
    if m.kind != "bar":
        return SHORTEST_LEG
    line = bar_line_length(t.length, m)
    return max(SHORTEST_LEG, m.swing_periods * swing_period(line, m.hook_shank))


def take_up_legs(scenario: Scenario) -> tuple[float, ZVShaper | None]:
    """Shortest leg [s] and shaper of the take-up's legs after the hooking pass (the
    bar's level move, seat climb, swing chords and stretch; the disk's and the magnet's
    take-up, nothing hanging free (the magnet clipped on its boom): :data:`SHORTEST_LEG`,
    unshaped).

    With the bar every take-up leg is the rest-to-rest smoothstep of the speed limits
    (at least :data:`SHORTEST_LEG`) convolved with the zero-vibration shaper at the hook's
    believed swing period P (:func:`swing_shaper`): a pendulum of period P driven by the
    move is left with no swing, whatever the leg's duration, and one of period P_true
    with |cos(pi P / (2 P_true))| of the unshaped move's (:meth:`ZVShaper.residual_ratio`).
    Experiment (branch i22-takeup-mid): the unshaped part at least one period P (a leg at
    least 1.5 P), slower chords than the speed limits give: with 0.5 s the 60 deg
    campaign draws 00005 and 00008 lost the seated hook (docs/mechanism.md).
    The robot does not see whether the hook hangs free beside the bar (the level move;
    a hook not seated) or sits in its crook, so every leg is shaped for the free hook.
    A leg so lasts its speed-limited duration plus P/2 (1.1 s for the pilot's 1.2 m
    cable); the unshaped leg of ``mechanism.swing_periods`` = 2 periods it replaces
    leaves 11 % of its horizontal length swinging (the smoothstep's velocity spectrum
    at 2 cycles per leg, :func:`~tetherland.mission.paths.smoothstep_residual`), and
    has its first zero only at 2.6 periods.
    The bar's unhooking flies the same legs (the supervisor's climb away from the bar,
    the flight over it, and the reverse pass under it): the hook hangs free or on the
    bar there too, and unshaped they had to last 3-4 periods to leave it still."""
    shaper = swing_shaper(scenario) if scenario.mechanism.kind == "bar" else None
    return (SHORTEST_LEG if shaper is None else max(SHORTEST_LEG, shaper.period)), shaper


def swing_shaper(scenario: Scenario) -> ZVShaper | None:
    """The zero-vibration shaper of the free-flight moves (:class:`ZVShaper`): with a
    hook hanging on a line (the bar mechanism) at its believed swing period
    (:func:`tetherland.models.hook.swing_period`), so that no move leaves it swinging;
    None otherwise."""
    m, t = scenario.mechanism, scenario.tether
    if m.kind == "magnet":  # the released magnet hanging on the cable
        return ZVShaper(swing_period_magnet(t.length, m.magnet_thickness))
    if m.kind != "bar":
        return None
    line = bar_line_length(t.length, m)
    return ZVShaper(swing_period(line, m.hook_shank))


def takeoff_height(scenario: Scenario) -> float:
    """Height of the takeoff point above the start pad [m]: ``mission.flight.takeoff_height``,
    and with a hook hanging on a line (the bar mechanism) at least the hook's depth below
    the pad's centre of mass plus ``mechanism.lift_margin``: the hook leaves the ground
    during the climb, not while the vehicle hovers with it dragging (which sets it
    swinging)."""
    h = scenario.mission.flight.takeoff_height
    m, t = scenario.mechanism, scenario.tether
    if m.kind != "bar":
        return h
    line = bar_line_length(t.length, m)
    hang = line + m.hook_shank - scenario.vehicle.cable_attachment[2] - scenario.vehicle.h_R
    return max(h, hang + m.lift_margin)


def lift_off_band(scenario: Scenario) -> tuple[float, float] | None:
    """Heights above the start pad [m] between which the takeoff climbs at
    ``mechanism.lift_speed``: ``mechanism.lift_band`` around the climb at which the
    hanging line comes taut and lifts the hook off the ground (the bar mechanism; None
    otherwise). Snatched off the ground at the cruise climb (0.7 m/s) the hook bounced on
    the line and that energy went into a swing of up to 30 cm."""
    m, t = scenario.mechanism, scenario.tether
    if m.kind != "bar" or m.lift_band <= 0.0:
        return None
    line = bar_line_length(t.length, m)
    hang = line + m.hook_shank - scenario.vehicle.cable_attachment[2] - scenario.vehicle.h_R
    top = takeoff_height(scenario)
    lo, hi = max(0.0, hang - m.lift_band), min(top, hang + m.lift_band)
    return (lo, hi) if hi > lo else None


def pass_overshoot(scenario: Scenario) -> float:
    """Hook-point distance beyond the anchor where the hooking pass ends [m]:
    ``mission.hooking.overshoot``, or ``mechanism.pass_depth + pass_margin`` for the bar
    (the crown that far below the believed bar's axis: the tips pass under a bar up to
    ``pass_margin`` lower than believed, the shank then lying against it; a bar where
    believed meets the line above the eye), or
    ``mechanism.press_depth`` for the magnet (its face pressed on the plate, the boom
    folding by about that much)."""
    if scenario.mechanism.kind == "bar":
        return scenario.mechanism.pass_depth + scenario.mechanism.pass_margin
    if scenario.mechanism.kind == "magnet":
        return scenario.mechanism.press_depth
    return scenario.mission.hooking.overshoot


def unhook_depth(scenario: Scenario) -> float:
    """Depth of the hook point beyond the anchor where the unhooking pass begins [m]:
    ``mission.hooking.unhook_depth``, or ``mechanism.release_depth`` for the bar (flown back
    over the bar with that much slack, the line slides back and the hook drops out of
    its crook; with a few centimetres it stays seated and is lifted into the bar again)."""
    if scenario.mechanism.kind == "bar":
        return scenario.mechanism.release_depth
    return scenario.mission.hooking.unhook_depth


def bar_seating_path(
    scenario: Scenario, p_A_W: FloatArray, x_A_W: FloatArray, hook_end_W: FloatArray,
    stretch_W: FloatArray, attachment_W: FloatArray,
) -> list[tuple[FloatArray, float | None]]:  # fmt: skip
    """The bar mechanism's take-up after the hooking pass, up to (not including) the
    stretch, as planned: centre-of-mass corners F_W [m] with their speeds [m/s] (None:
    the take-up's). The climb (:func:`bar_climb_path`), then the swing from its top
    (:func:`bar_swing_path`); the supervisor swings from where the climb left the
    vehicle instead (a hook seated early holds it lower)."""
    path = bar_climb_path(scenario, x_A_W, hook_end_W)
    return path + bar_swing_path(scenario, p_A_W, path[-1][0], stretch_W, attachment_W)


def bar_climb_path(
    scenario: Scenario, x_A_W: FloatArray, hook_end_W: FloatArray
) -> list[tuple[FloatArray, float | None]]:
    """The bar's take-up after the hooking pass, its first two legs: corners F_W [m] and
    speeds [m/s] (None: the take-up's).

    1. Level to the pass's mirror across the bar (2 ``pass_offset`` along the horizontal
       part of ``x_A_W``): the same distance from the bar, the line is not pulled and the
       hook's shank (a bar ``pass_margin`` lower than believed) or the line just above its
       eye (the bar where believed) comes to lie against the bar, the arms under it.
    2. Seat: climb ``pass_depth + pass_margin`` (the pass's depth) at ``lift_speed``. The
       crook reaches the bar's bottom after ``hook_radius + bar_radius`` less than the
       crown's true depth under the bar (``pass_depth`` to ``pass_depth + 2
       pass_margin``); from there the seated hook holds the line, and the line the
       vehicle: the climb ends where the hook seats, up to ``pass_depth + pass_margin -
       hook_radius - bar_radius`` higher for the bar where believed, and the line just
       taut over a seated hook. Rising arms (``hook_arm_rise_deg``) seat the bar lower,
       in the arm-tip corner (``MechanismConfig.bar_seat``): the climb is
       longer by the seat's drop. Climbing only ``pass_depth`` left the hook unseated,
       ``pass_margin`` under the bar (pipe60, the line taut only on the stretch, with a
       31 N snatch, and the hook slipped).
    """
    m = scenario.mechanism
    x = np.array([x_A_W[0], x_A_W[1], 0.0])
    mirror = np.asarray(hook_end_W, float) + 2.0 * m.pass_offset * x / np.linalg.norm(x)
    # the seat's drop below the flat arm's (0 for flat arms; rising arms seat the bar lower)
    climb = m.pass_depth + m.pass_margin + (m.hook_radius + m.bar_radius - m.bar_seat[1])
    seat = mirror + np.array([0.0, 0.0, climb])
    return [(mirror, None), (seat, m.lift_speed)]


def bar_swing_path(
    scenario: Scenario, p_A_W: FloatArray, seat_W: FloatArray, stretch_W: FloatArray,
    attachment_W: FloatArray,
) -> list[tuple[FloatArray, float | None]]:  # fmt: skip
    """The bar's take-up from the seat (the top of the climb, or where the seated hook
    held the vehicle) to the direction of the stretch: corners F_W [m] (the take-up's
    speed, None).

    3. Swing down around the anchor at the radius where the crook just touches the bar
       (the seat's distance from p_A less ``hook_radius + bar_radius``), to the
       direction of the stretch point: the line stays nearly taut and rolls the seated
       hook over the bar. Descending straight from the mirror slackened the line and
       the hook dropped off the bar's side (slope50, seeds 0-3). Swinging at the
       planned seat's radius when a hook seated early held the vehicle lower pulled the
       line taut in the swing (slope 20 deg, the bar 1.7 cm lower than believed). The
       arc is flown as chords whose sagitta is at most a third of ``hook_tip_length``,
       so that the hook drops at most that much from its crook.

    The stretch then goes straight out along that direction (no slack point inside
    the cable length: moving in let a seated hook slide off when pulled again).
    """
    m = scenario.mechanism
    a0 = np.asarray(seat_W, float) + attachment_W - p_A_W
    a1 = np.asarray(stretch_W, float) + attachment_W - p_A_W
    r = float(np.linalg.norm(a0)) - (m.hook_radius + m.bar_radius)
    u0, u1 = a0 / np.linalg.norm(a0), a1 / np.linalg.norm(a1)
    cos_ang = float(np.clip(u0 @ u1, -1.0, 1.0))
    ang = math.acos(cos_ang)
    path: list[tuple[FloatArray, float | None]] = []
    if ang < 1e-9:
        return path
    w = u1 - cos_ang * u0
    w /= np.linalg.norm(w)
    chord = 2.0 * math.acos(1.0 - m.hook_tip_length / (3.0 * r))  # angle of one chord
    n = max(1, math.ceil(ang / chord))
    for k in range(1, n + 1):
        th = ang * k / n
        path.append((p_A_W + r * (math.cos(th) * u0 + math.sin(th) * w) - attachment_W, None))
    return path
