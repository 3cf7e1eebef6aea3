"""Clearance of the level-flying vehicle from the landing surface (hooking pass check).

While hooking, the vehicle flies level with the hook hanging ``hook_drop`` under the cable
attachment point, and lowers the hook onto the anchor. On a steep surface the uphill side
of the frame comes close to the surface: with the hook at the anchor, the rotor guards at
horizontal distance R from the centre meet a surface that rises R tan(beta). The mission
checks this before it flies and reports the hook drop the slope needs instead of crashing.

The vehicle's collision shape is the one the plant simulates
(:mod:`tetherland.models.airframe`);
the frame is sampled on the rims of the rotor guards (5 degree steps, under 0.3 mm error)
and the corners of the hub.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland.config import Scenario
from tetherland.geometry import FloatArray
from tetherland.models.airframe import (
    HUB_HALF_SIZE,
    PROP_HALF_THICKNESS,
    PROP_HEIGHT,
    PROP_RADIUS_FRACTION,
    lander_centres_B,
)
from tetherland.models.quadrotor import RotorLayout
from tetherland.rotations import rotation_from_z_and_yaw
from tetherland.surface import Surface

_N_RIM = 72
_RIM = np.column_stack(
    (
        np.cos(np.linspace(0.0, 2.0 * math.pi, _N_RIM, endpoint=False)),
        np.sin(np.linspace(0.0, 2.0 * math.pi, _N_RIM, endpoint=False)),
        np.zeros(_N_RIM),
    )
)


def surface_distance(surface: Surface, points_W: ArrayLike) -> FloatArray:
    """Signed distance of points from the surface, positive outside [m].

    Planes: height along z_S. Pipes: distance from the pipe axis (parallel to x_S, a
    radius below the top line through ``surface.origin``) minus the radius.
    """
    p = np.atleast_2d(np.asarray(points_W, dtype=float)) - surface.origin
    if surface.kind != "pipe":
        return p @ surface.z_S
    r = p + surface.pipe_radius * surface.z_S
    radial = r - np.outer(r @ surface.x_S, surface.x_S)
    return np.linalg.norm(radial, axis=1) - surface.pipe_radius


def level_vehicle_distance(
    scenario: Scenario, surface: Surface, p_W: ArrayLike, yaw: float
) -> float:
    """Smallest signed distance [m] of the level vehicle's collision shape from the surface.

    The shape is the one the plant simulates (:mod:`tetherland.models.airframe`): rotor
    guards (disks of radius PROP_RADIUS_FRACTION arm_length, PROP_HEIGHT above the rotors),
    the hub box and the four lander spheres, with the vehicle level at centre of mass
    ``p_W`` [m] and heading ``yaw`` [rad].
    """
    v = scenario.vehicle
    R = rotation_from_z_and_yaw((0.0, 0.0, 1.0), yaw)
    rotors = RotorLayout.from_config(v).positions_B
    r_prop = PROP_RADIUS_FRACTION * v.arm_length
    guards = [
        r_i + [0.0, 0.0, PROP_HEIGHT + dz] + r_prop * _RIM
        for r_i in rotors
        for dz in (-PROP_HALF_THICKNESS, PROP_HALF_THICKNESS)
    ]
    hx, hy, hz = HUB_HALF_SIZE
    signs = (-1.0, 1.0)
    hub = np.array([[sx * hx, sy * hy, sz * hz] for sx in signs for sy in signs for sz in signs])
    frame_B = np.vstack([*guards, hub])
    r = v.lander_radius
    landers_B = lander_centres_B(v.lander_half_width, v.h_R, r)
    p = np.asarray(p_W, dtype=float)
    frame = surface_distance(surface, p + frame_B @ R.T).min()
    landers = surface_distance(surface, p + landers_B @ R.T).min() - r
    return float(min(frame, landers))


@dataclass(frozen=True)
class HookingClearance:
    """Smallest distance of the level vehicle from the surface along the hooking pass.

    Attributes
    ----------
    clearance_m : float
        Smallest signed distance [m] at the ends of the pass (it is linear in between for
        a plane).
    required_hook_drop_m : float
        Hook drop [m] that gives ``margin_m`` of clearance: exact for a plane (a longer
        drop dh moves the vehicle back along the approach direction n, away from the plane
        by dh (-n . z_S)); for a pipe an estimate by the same rule.
    margin_m : float
        Clearance asked for [m].
    """

    clearance_m: float
    required_hook_drop_m: float
    margin_m: float

    @property
    def ok(self) -> bool:
        return self.clearance_m >= self.margin_m - 1e-9


def hooking_clearance(
    scenario: Scenario,
    surface: Surface,
    pass_W: ArrayLike,
    yaw: float,
    margin: float,
    approach_W: ArrayLike = (0.0, 0.0, -1.0),
) -> HookingClearance:
    """Clearance of the hooking pass whose centre-of-mass end points are ``pass_W``.

    Parameters
    ----------
    scenario : Scenario
        Vehicle and tether (hook drop).
    surface : Surface
        The surface the vehicle flies over.
    pass_W : (k, 3) array
        Centre-of-mass points of the pass (its ends; the pass is straight) [m].
    yaw : float
        Heading of the vehicle during the pass [rad].
    margin : float
        Clearance the pass must keep [m].
    approach_W : (3,) array
        Unit approach direction n: the hook leads the vehicle by ``hook_drop`` along n, so
        a longer hook drop moves the vehicle back by the same length along -n.
    """
    clearance = min(
        level_vehicle_distance(scenario, surface, p, yaw)
        for p in np.atleast_2d(np.asarray(pass_W, dtype=float))
    )
    # a longer drop dh moves the vehicle by -dh n: away from a plane by dh (-n . z_S)
    away = max(-float(np.dot(np.asarray(approach_W, dtype=float), surface.z_S)), 1e-3)
    needed = scenario.tether.hook_drop + max(0.0, margin - clearance) / away
    return HookingClearance(clearance_m=clearance, required_hook_drop_m=needed, margin_m=margin)
