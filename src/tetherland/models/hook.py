"""The hook model: where the vehicle's hook point is relative to its cable attachment.

Assumed model: the hook point is the cable attachment point moved by ``hook_drop`` along
the approach direction n, leading the vehicle in the direction it moves. For the default
approach n = -z_W this is the hook hanging under the vehicle; for other directions the
hook is held out along the approach direction (a hook on a short stiff arm), which lets
the vehicle hook an anchor on a wall or an overhang from the side or from below.

:func:`hook_offset` is the one statement of it: the plant's hook (:mod:`tetherland.sim.hook`)
and the robot's hooking pass, clearance check and design search
(:mod:`tetherland.mission.hooking`) all use it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np

from tetherland import GRAVITY
from tetherland.geometry import FloatArray

if TYPE_CHECKING:
    from tetherland.config import Scenario
    from tetherland.config.mechanism import MechanismConfig


def hook_offset(n_W: FloatArray, hook_drop: float) -> FloatArray:
    """Hook point minus attachment point, hook_drop n [m], for the unit approach direction
    ``n_W`` (F_W) and the hook drop [m]."""
    return hook_drop * n_W


def bar_line_length(tether_length: float, mechanism: MechanismConfig) -> float:
    """Length of the hanging line of the bar mechanism, attachment to the hook's eye [m].

    Caught, the bar rests in the crook at ``MechanismConfig.bar_seat``, the line pulling the eye
    straight away from the bar's axis: the line is shorter than ``tether_length`` by the
    eye's distance from the bar's axis, so that the anchor p_A (the bar's axis) to the
    attachment is l when taut. Flat arms: ``hook_shank - hook_radius - bar_radius``.
    """
    m = mechanism
    if m.hook_arm_rise_deg == 0.0:
        return tether_length - (m.hook_shank - m.hook_radius - m.bar_radius)
    u, z = m.bar_seat
    return tether_length - math.hypot(u, m.hook_shank - z)


def bar_hanging_weight(tether_length: float, mechanism: MechanismConfig) -> float:
    """Weight of the bar mechanism's hanging line and hook, g (hook_mass + line_density
    times :func:`bar_line_length`): the pull of the line hanging free on the attachment
    point, straight down [N]."""
    m = mechanism
    line = bar_line_length(tether_length, m)
    return GRAVITY * (m.hook_mass + m.line_density * line)


def bar_hook_offset(x_A_W: FloatArray, line_length: float, hook_shank: float,
                    pass_offset: float) -> FloatArray:  # fmt: skip
    """The bar mechanism's counterpart of :func:`hook_offset`: the vector v such that the
    attachment point p_A + s n - v puts the hanging hook's crown ``pass_offset`` from the
    bar's axis, on the side away from the landing point (-x_A, ``x_A_W`` in F_W), at depth
    s along the pass (n = -z_W) [m].

    The hook hangs ``line_length + hook_shank`` straight below the attachment (at rest),
    so v = -(line_length + hook_shank) z_W + pass_offset x_A (horizontal part of x_A).
    """
    x = np.array([x_A_W[0], x_A_W[1], 0.0])
    x /= np.linalg.norm(x)
    return np.array([0.0, 0.0, -(line_length + hook_shank)]) + pass_offset * x


def bar_near_distance(mechanism: MechanismConfig) -> float:
    """Farthest the hook's crown can be from the bar's axis with a part of the hook still
    touching the bar: the tips' reach from the shank (``outer_reach``) plus a tip's length
    (the crown to a tip's end) and the arms' fall (hook_reach tan(hook_arm_rise_deg))
    plus the two radii [m]. The plant's catch rule and the judge's hooking
    classification both use it."""
    m = mechanism
    return (m.outer_reach + m.hook_tip_length + m.arm_fall + m.hook_radius
            + m.bar_radius)


def swing_period(line_length: float, hook_shank: float) -> float:
    """Swing period 2 pi sqrt(L/g) of a hook hanging on a line, L the line plus half the
    shank (the hook's mass dominates the line's) [s]."""
    return 2.0 * math.pi * math.sqrt((line_length + 0.5 * hook_shank) / GRAVITY)


BOOM_RADIUS = 0.004
"""Radius of the magnet mechanism's boom (a 4 mm carbon tube), the plant's capsule and the
plan's clearance checks [m]."""


@dataclass(frozen=True)
class MagnetBoom:
    """The magnet mechanism's folding boom and its magnet, unfolded, in F_B [m]: the one
    statement of its geometry, which the plant's bodies (:mod:`tetherland.sim.mjcf`), the
    hooking pass (:func:`tetherland.mission.hooking.scenario_hook_offset`) and the
    configuration's reach check (:func:`magnet_reach_margin`) all use.

    The hinge sits at the cable attachment point r_att; the boom runs ``boom_length`` at
    ``boom_angle_deg`` from the approach direction n_B, up toward z_B (unit w_B), to the
    cable's eye on the back of the magnet; the magnet's axis is n_B, its face
    ``magnet_thickness`` beyond the eye. A push along -n on the face turns the boom about
    ``axis_B`` = n_B x w_B (it folds up, the face moving back along -n).

    Attributes
    ----------
    hinge_B, eye_B, face_B : (3,) array
        Hinge, the cable's eye (the back of the magnet, the hook point) and the face's
        centre [m].
    n_B, w_B, axis_B : (3,) array
        Approach direction, the boom's tilt direction and the hinge axis (unit) [-].
    length : float
        Boom length [m].
    angle : float
        Boom angle from n_B [rad].
    """

    hinge_B: FloatArray
    eye_B: FloatArray
    face_B: FloatArray
    n_B: FloatArray
    w_B: FloatArray
    axis_B: FloatArray
    length: float
    angle: float

    @classmethod
    def of(cls, r_att_B: FloatArray, n_B: FloatArray, boom_length: float,
           boom_angle_deg: float, magnet_thickness: float) -> MagnetBoom:  # fmt: skip
        """The boom for the attachment point ``r_att_B``, the approach direction ``n_B``
        (F_B, any length) and the mechanism's sizes [m, -, m, deg, m]."""
        n = np.asarray(n_B, dtype=float)
        n = n / np.linalg.norm(n)
        z = np.array([0.0, 0.0, 1.0])
        w = z - (z @ n) * n
        if float(np.linalg.norm(w)) < 1e-6:  # approach along z_B: tilt toward x_B
            w = np.array([1.0, 0.0, 0.0]) - n[0] * n
        w /= np.linalg.norm(w)
        a = math.radians(boom_angle_deg)
        hinge = np.asarray(r_att_B, dtype=float)
        eye = hinge + boom_length * (math.cos(a) * n + math.sin(a) * w)
        return cls(hinge, eye, eye + magnet_thickness * n, n, w, np.cross(n, w),
                   float(boom_length), a)  # fmt: skip

    @property
    def offset_B(self) -> FloatArray:
        """The hook point (the eye) minus the attachment point, F_B [m]."""
        return self.eye_B - self.hinge_B


def magnet_fold(boom_length: float, boom_angle: float, press: float) -> tuple[float, float]:
    """The boom's fold theta and the tip's rise delta along w when its tip is pushed back
    by ``press`` along -n: L cos(beta) - L cos(beta + theta) = press, delta =
    L (sin(beta + theta) - sin(beta)) [m, rad, m -> rad, m]."""
    c = math.cos(boom_angle) - press / boom_length
    theta = math.acos(max(-1.0, min(1.0, c))) - boom_angle
    return theta, boom_length * (math.sin(boom_angle + theta) - math.sin(boom_angle))


def magnet_boom(scenario: Scenario) -> MagnetBoom:
    """The boom of ``scenario``'s magnet mechanism, built for the hooking pass's level
    attitude with x_B along x_A (so n_B is ``tether.approach_direction`` in F_A)."""
    m = scenario.mechanism
    return MagnetBoom.of(np.asarray(scenario.vehicle.cable_attachment, dtype=float),
                         np.asarray(scenario.tether.approach_direction, dtype=float),
                         m.boom_length, m.boom_angle_deg, m.magnet_thickness)  # fmt: skip


def magnet_reach_margin(scenario: Scenario) -> float:
    """How far the unfolded magnet's face reaches beyond the farthest part of the vehicle
    along the approach direction (the airframe of :mod:`tetherland.models.airframe`, the
    plant's collision shapes), from the centre of mass [m]: > 0 means the magnet meets a
    surface ahead of the vehicle before any part of it does."""
    from tetherland.models.airframe import Airframe

    boom = magnet_boom(scenario)
    n = boom.n_B
    f = Airframe.of(scenario.vehicle)
    reach = [float(np.max(f.lander_centres_B @ n)) + f.lander_radius]
    for c in f.capsules:
        reach.append(max(float(c.a_B @ n), float(c.b_B @ n)) + c.radius)
    # a guard disk (axis z_B): its rim's support along n plus its half thickness
    n_xy = math.hypot(n[0], n[1])
    reach.append(float(np.max(f.guard_centres_B @ n)) + f.guard_radius * n_xy
                 + f.guard_half_thickness * abs(n[2]))  # fmt: skip
    reach.append(float(np.abs(n) @ np.asarray(f.hub_half_size)))
    reach.append(float(f.mount_B @ n) + f.mount_radius)
    # the magnet's face is flat across n: its centre is as far along n as it reaches
    return float(boom.face_B @ n) - max(reach)


def swing_period_magnet(cable_length: float, magnet_thickness: float) -> float:
    """Swing period 2 pi sqrt(L/g) of the released magnet hanging on the cable, L the
    cable to the eye plus half the magnet's thickness (its centre of mass) [s]."""
    return 2.0 * math.pi * math.sqrt((cable_length + 0.5 * magnet_thickness) / GRAVITY)


MAGNET_BALANCE = 0.75
"""Fraction of the clipped magnet's moment about the centre of mass that the frame's
counterweight balances (a design fact of the vehicle the plant builds,
:mod:`tetherland.sim.mjcf`, and the robot's belief of its own mass distribution,
:func:`magnet_load`): the rest is a steady torque on the approach (0.022 N m for the
defaults), the balanced part one after the magnet has left the boom (0.065 N m) [-]."""

MagnetWhere = Literal["clipped", "held", "hanging"]
"""Where the magnet is, for :func:`magnet_load`: on the boom's clip, held on the plate at
the anchor (the vehicle flies without it), or hanging on the cable under the vehicle."""


def magnet_centre_B(scenario: Scenario) -> FloatArray:
    """Centre of the clipped magnet in F_B, the eye plus half its thickness along the
    approach direction [m]."""
    boom = magnet_boom(scenario)
    return boom.eye_B + 0.5 * scenario.mechanism.magnet_thickness * boom.n_B


def magnet_load(scenario: Scenario, where: MagnetWhere) -> tuple[float, FloatArray]:
    """The weight the vehicle carries and where it acts, with the magnet ``where`` is.

    ``vehicle.mass`` M is the whole robot, boom and magnet (mass m, centre r_m in F_B)
    included; the frame is balanced for the boom and :data:`MAGNET_BALANCE` (beta) of the
    magnet's moment about the body origin (the rotors' centre, where the controllers put
    the centre of mass). So the centre of mass c is, from the body origin,

    - clipped: c = (1 - beta) m r_m / M, weight M g;
    - held on the plate: c = -beta m r_m / (M - m), weight (M - m) g;
    - hanging: the frame's as held, plus the magnet's weight pulling at the cable's
      attachment r_att (its mean pull, the swing averaged out): c = (m r_att -
      beta m r_m) / M, weight M g.

    The rotors hold the weight's moment about the origin, m_c g c x z_W (z_W in F_B): the
    torque a controller that assumes c = 0 must add (:mod:`tetherland.control.switching`).

    Parameters
    ----------
    scenario : Scenario
        The believed scenario (``mechanism.kind = "magnet"``).
    where : {"clipped", "held", "hanging"}
        Where the magnet is.

    Returns
    -------
    mass : float
        Mass whose weight the vehicle carries [kg].
    c_B : (3,) array
        Point where that weight acts, F_B from the body origin [m].
    """
    M = scenario.vehicle.mass
    m = scenario.mechanism.magnet_mass
    moment = m * magnet_centre_B(scenario)  # kg m
    if where == "clipped":
        return M, (1.0 - MAGNET_BALANCE) * moment / M
    if where == "held":
        return M - m, -MAGNET_BALANCE * moment / (M - m)
    if where == "hanging":
        r_att = np.asarray(scenario.vehicle.cable_attachment, dtype=float)
        return M, (m * r_att - MAGNET_BALANCE * moment) / M
    raise ValueError(f"unknown magnet position {where!r} (clipped, held, hanging)")


def weight_torque_B(mass: float, c_B: FloatArray, R_WB: FloatArray) -> FloatArray:
    """Torque about the body origin that holds the weight ``mass`` g acting at ``c_B``
    (F_B) at attitude ``R_WB``: mass g c_B x z_W, z_W in F_B the third row of R_WB,
    F_B [N m]."""
    R = np.asarray(R_WB, dtype=float)
    return mass * GRAVITY * np.cross(np.asarray(c_B, dtype=float), R[2])
