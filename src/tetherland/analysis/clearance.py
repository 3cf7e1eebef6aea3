"""Clearance of the level-flying vehicle from the landing surface (hooking pass check).

While hooking, the vehicle flies level with the hook hanging ``hook_drop`` under the cable
attachment point, and lowers the hook onto the anchor. On a steep surface the uphill side
of the frame comes close to the surface: with the hook at the anchor, the rotor guards at
horizontal distance R from the centre meet a surface that rises R tan(beta). The mission
checks this before it flies and reports the hook drop the slope needs instead of crashing.

The vehicle's collision shape is the one the plant simulates
(:class:`tetherland.models.airframe.Airframe`): the rotor guards, sampled on their rims
(5 degree steps, under 0.3 mm error), the corners of the hub, the lander and mount spheres
and the leg and arm capsules (exact against a plane or a pipe). With the magnet mechanism
the checks of the free-flight legs add its boom (:func:`mechanism_distance`): the plant's
capsule from the hinge to the tip, as far as it can fold, and while the magnet is clipped
on it the magnet.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland.config import Scenario, VehicleConfig
from tetherland.geometry import FloatArray
from tetherland.models.airframe import Airframe
from tetherland.models.hook import BOOM_RADIUS, MagnetWhere, magnet_boom
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


def segment_distance(surface: Surface, a_W: ArrayLike, b_W: ArrayLike) -> FloatArray:
    """Signed distance of segments a-b from the surface, positive outside [m].

    Planes: the nearer end. Pipes: the segment's least distance from the pipe axis minus
    the radius (exact: the radial offset from the axis is affine along the segment).
    """
    a = np.atleast_2d(np.asarray(a_W, dtype=float))
    b = np.atleast_2d(np.asarray(b_W, dtype=float))
    if surface.kind != "pipe":
        return np.minimum(surface_distance(surface, a), surface_distance(surface, b))
    axis = surface.origin - surface.pipe_radius * surface.z_S
    x = surface.x_S
    ra = (a - axis) - np.outer((a - axis) @ x, x)
    rb = (b - axis) - np.outer((b - axis) @ x, x)
    d = rb - ra
    dd = np.einsum("ij,ij->i", d, d)
    s = np.clip(-np.einsum("ij,ij->i", ra, d) / np.where(dd > 0.0, dd, 1.0), 0.0, 1.0)
    return np.linalg.norm(ra + s[:, None] * d, axis=1) - surface.pipe_radius


@dataclass(frozen=True)
class _Shape:
    """A vehicle's collision shape as arrays in F_B, for many distance queries."""

    points_B: FloatArray  # guard rims (both faces), then hub corners
    n_guard: int  # rows of points_B on the guard rims
    spheres_B: FloatArray  # four landers, then the mount
    sphere_radii: FloatArray
    a_B: FloatArray  # capsules (legs, arms): ends and radii
    b_B: FloatArray
    capsule_radii: FloatArray
    capsule_names: tuple[str, ...]


@functools.lru_cache(maxsize=64)
def _shape(vehicle: VehicleConfig) -> _Shape:
    frame = Airframe.of(vehicle)
    guards = [
        c + [0.0, 0.0, dz] + frame.guard_radius * _RIM
        for c in frame.guard_centres_B
        for dz in (-frame.guard_half_thickness, frame.guard_half_thickness)
    ]
    hx, hy, hz = frame.hub_half_size
    signs = (-1.0, 1.0)
    hub = np.array([[sx * hx, sy * hy, sz * hz] for sx in signs for sy in signs for sz in signs])
    n = len(frame.lander_centres_B)
    return _Shape(
        points_B=np.vstack([*guards, hub]),
        n_guard=sum(len(g) for g in guards),
        spheres_B=np.vstack((frame.lander_centres_B, frame.mount_B)),
        sphere_radii=np.array([frame.lander_radius] * n + [frame.mount_radius]),
        a_B=np.array([c.a_B for c in frame.capsules]),
        b_B=np.array([c.b_B for c in frame.capsules]),
        capsule_radii=np.array([c.radius for c in frame.capsules]),
        capsule_names=tuple(c.name for c in frame.capsules),
    )


def _distances(
    vehicle: VehicleConfig, surface: Surface, p_W: ArrayLike, R_WB: ArrayLike
) -> tuple[_Shape, FloatArray, FloatArray, FloatArray]:
    """The shape and the signed distances of its points, spheres and capsules [m]."""
    shape = _shape(vehicle)
    R = np.asarray(R_WB, dtype=float)
    p = np.asarray(p_W, dtype=float)
    d_points = surface_distance(surface, p + shape.points_B @ R.T)
    d_spheres = surface_distance(surface, p + shape.spheres_B @ R.T) - shape.sphere_radii
    d_caps = (
        segment_distance(surface, p + shape.a_B @ R.T, p + shape.b_B @ R.T) - shape.capsule_radii
    )
    return shape, d_points, d_spheres, d_caps


def part_distances(
    vehicle: VehicleConfig, surface: Surface, p_W: ArrayLike, R_WB: ArrayLike
) -> dict[str, float]:
    """Smallest signed distance [m] of each part of the vehicle's collision shape from
    the surface, the vehicle's centre of mass at ``p_W`` [m] with attitude ``R_WB``.

    Keys: ``landers`` (the four spheres), ``guards`` (rims of the rotor guards), ``hub``
    (its corners), ``mount``, and each capsule by the plant's geom name (``leg0`` ...
    ``leg3``, ``arm0`` ... ``arm3``).
    """
    shape, d_points, d_spheres, d_caps = _distances(vehicle, surface, p_W, R_WB)
    out = {
        "landers": float(d_spheres[:-1].min()),
        "guards": float(d_points[: shape.n_guard].min()),
        "hub": float(d_points[shape.n_guard :].min()),
        "mount": float(d_spheres[-1]),
    }
    out.update({name: float(d) for name, d in zip(shape.capsule_names, d_caps, strict=True)})
    return out


def vehicle_distance(
    vehicle: VehicleConfig, surface: Surface, p_W: ArrayLike, R_WB: ArrayLike
) -> float:
    """Smallest signed distance [m] of the vehicle's whole collision shape from the surface
    (the least of :func:`part_distances`)."""
    _, d_points, d_spheres, d_caps = _distances(vehicle, surface, p_W, R_WB)
    return float(min(d_points.min(), d_spheres.min(), d_caps.min()))


def mechanism_distance(
    scenario: Scenario, surface: Surface, p_W: ArrayLike, R_WB: ArrayLike, magnet: MagnetWhere
) -> float:
    """Smallest signed distance [m] of the mechanism's parts carried on the vehicle from the
    surface, the vehicle's centre of mass at ``p_W`` [m] with attitude ``R_WB``; ``inf``
    for mechanisms that carry none (the capture disk's point hook, the bar's hanging line,
    which is no rigid part of the vehicle).

    The magnet mechanism: its boom (:class:`tetherland.models.hook.MagnetBoom`, the plant's
    capsule of radius :data:`~tetherland.models.hook.BOOM_RADIUS` from the hinge to the
    tip). With ``magnet = "clipped"`` the boom unfolded and the magnet on its tip, as the
    cylinder about its axis that holds its square face turned any way about it (the
    socket's gimbal turns it), radius ``magnet_radius`` sqrt(2), sampled on its face's and
    back's rims. ``"held"`` and ``"hanging"``: the empty boom, which folds when the surface
    pushes its tip (up to ``boom_fold_deg``, against a spring of ``boom_preload``), so its
    distance is the largest over its folds (every 5 deg of the range, the tip then within
    0.3 mm of the arc): negative only when no fold keeps it out, the boom then on its
    stop. :func:`boom_distance` gives it at one fold.
    """
    if scenario.mechanism.kind != "magnet":
        return math.inf
    if magnet == "clipped":
        boom = boom_distance(scenario, surface, p_W, R_WB, 0.0)
        rims = np.asarray(p_W, float) + _magnet_rims_B(scenario) @ np.asarray(R_WB, float).T
        return min(boom, float(surface_distance(surface, rims).min()))
    fold = math.radians(scenario.mechanism.boom_fold_deg)
    count = max(1, math.ceil(fold / math.radians(_FOLD_STEP_DEG)))
    return max(
        boom_distance(scenario, surface, p_W, R_WB, fold * k / count) for k in range(count + 1)
    )


_FOLD_STEP_DEG = 5.0


def boom_distance(
    scenario: Scenario, surface: Surface, p_W: ArrayLike, R_WB: ArrayLike, fold: float
) -> float:
    """Signed distance [m] of the magnet mechanism's boom folded by ``fold`` [rad] (0:
    unfolded, on its stop) from the surface: the capsule from the hinge to the tip
    hinge + L (cos(a + fold) n_B + sin(a + fold) w_B), L ``boom_length``, a
    ``boom_angle_deg`` (:func:`tetherland.models.hook.magnet_fold`'s geometry)."""
    boom = magnet_boom(scenario)
    R = np.asarray(R_WB, dtype=float)
    p = np.asarray(p_W, dtype=float)
    a = boom.angle + fold
    tip_B = boom.hinge_B + boom.length * (math.cos(a) * boom.n_B + math.sin(a) * boom.w_B)
    return float(segment_distance(surface, p + R @ boom.hinge_B, p + R @ tip_B)[0]) - BOOM_RADIUS


def _magnet_rims_B(scenario: Scenario) -> FloatArray:
    """Points on the rims of the clipped magnet's bounding cylinder (back at the eye, face
    ``magnet_thickness`` beyond along n_B), F_B [m]."""
    m = scenario.mechanism
    boom = magnet_boom(scenario)
    a = math.sqrt(2.0) * m.magnet_radius
    ring = a * (_RIM[:, :1] * boom.axis_B + _RIM[:, 1:2] * boom.w_B)
    return np.vstack((boom.eye_B + ring, boom.face_B + ring))


def level_vehicle_distance(
    scenario: Scenario, surface: Surface, p_W: ArrayLike, yaw: float
) -> float:
    """Smallest signed distance [m] of the level vehicle's collision shape from the surface.

    The shape is the one the plant simulates (:class:`tetherland.models.airframe.Airframe`:
    rotor guards, hub, landers, legs, arms and the cable's mount, :func:`part_distances`),
    with the vehicle level at centre of mass ``p_W`` [m] and heading ``yaw`` [rad].
    """
    R = rotation_from_z_and_yaw((0.0, 0.0, 1.0), yaw)
    return vehicle_distance(scenario.vehicle, surface, p_W, R)


MECHANISM_MARGIN = 0.0
"""Least distance the plan keeps between the mechanism's parts on the vehicle and the
surface (:func:`mechanism_distance`) [m]: the empty boom folds out of the surface's way
when its tip is pushed harder than its preload (0.5 N for the defaults), so a plan may
bring it to the surface, but not where even its folds would not keep it out; the frame
keeps ``mission.hooking.min_clearance``."""


@dataclass(frozen=True)
class VehicleClearance:
    """Smallest signed distances of the level vehicle's parts from the surface [m].

    Attributes
    ----------
    frame_m : float
        The airframe's collision shape (:func:`level_vehicle_distance`).
    mechanism_m : float
        The mechanism's parts on the vehicle (:func:`mechanism_distance`; ``inf``: none).
    """

    frame_m: float
    mechanism_m: float

    def keeps(self, margin: float) -> bool:
        """The frame at least ``margin`` [m] from the surface, the mechanism's parts at
        least :data:`MECHANISM_MARGIN`."""
        return self.frame_m >= margin - 1e-9 and self.mechanism_m >= MECHANISM_MARGIN - 1e-9

    def least(self, other: VehicleClearance) -> VehicleClearance:
        """The smaller of each distance of the two."""
        return VehicleClearance(
            min(self.frame_m, other.frame_m), min(self.mechanism_m, other.mechanism_m)
        )


def level_clearance(
    scenario: Scenario, surface: Surface, p_W: ArrayLike, yaw: float, magnet: MagnetWhere
) -> VehicleClearance:
    """The level vehicle's clearance (:func:`level_vehicle_distance`) and its mechanism's,
    the magnet mechanism's magnet being where ``magnet`` says (:func:`mechanism_distance`),
    at centre of mass ``p_W`` [m] and heading ``yaw`` [rad]."""
    R = rotation_from_z_and_yaw((0.0, 0.0, 1.0), yaw)
    return VehicleClearance(
        vehicle_distance(scenario.vehicle, surface, p_W, R),
        mechanism_distance(scenario, surface, p_W, R, magnet),
    )


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
