"""The airframe's collision shape: landers, legs, hub box, arms, rotor guards and the
cable's mount.

The one statement of the vehicle's shape, shared by the MuJoCo model builder
(:mod:`tetherland.sim.mjcf`), the clearance checks (:mod:`tetherland.analysis.clearance`)
and the robot's contact rules (:mod:`tetherland.mission.contact`, the contact-free
method), so that what the planner checks and the robot believes is what the plant
simulates. Positions in F_B (FLU: x forward, y left, z up the thrust axis), sizes in
metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tetherland.config import VehicleConfig
from tetherland.geometry import FloatArray
from tetherland.models.quadrotor import RotorLayout

LANDER_CORNERS: tuple[tuple[float, float], ...] = (
    (1.0, 1.0),
    (-1.0, 1.0),
    (-1.0, -1.0),
    (1.0, -1.0),
)
"""Signs (x, y) of the four landers in F_B, lander 0 to 3: front left, then
counter-clockwise seen from above (the order of the plant's ``lander{i}`` geoms and
touch sensors)."""
PROP_RADIUS_FRACTION = 0.4
"""Rotor-guard disk radius as a fraction of the arm length [-]."""
HUB_HALF_SIZE = (0.06, 0.06, 0.025)
"""Half extents of the central hub box [m]."""
PROP_HEIGHT = 0.02
"""Height of the rotor-guard disks above the rotor centres [m]."""
PROP_HALF_THICKNESS = 0.004
"""Half thickness of a rotor-guard disk [m]."""
ARM_RADIUS = 0.008
"""Radius of the arms, capsules from the centre of mass to each rotor centre [m]."""
LEG_RADIUS_FRACTION = 0.35
"""Radius of a leg as a fraction of the lander radius [-]."""
LEG_ROOT_FRACTION = 0.5
"""Horizontal position of a leg's root as a fraction of its lander's (x, y) [-]."""
LEG_ROOT_Z = -0.02
"""Height of the legs' roots in F_B (under the hub) [m]."""
MOUNT_RADIUS = 0.008
"""Radius of the cable's mount, a sphere centred on the attachment point r_att [m]."""


def lander_centres_B(half_width: float, h_R: float, radius: float) -> FloatArray:
    """(4, 3) centres of the spherical lander tips in F_B [m], in :data:`LANDER_CORNERS`
    order: (+-w, +-w, -(h_R - r)) for the half-width w [m], the height h_R [m] of the
    centre of mass above the landers plane (the tips' lowest points) and the tip radius
    r [m]."""
    z = -(h_R - radius)
    return np.array([[sx * half_width, sy * half_width, z] for sx, sy in LANDER_CORNERS])


def lander_tips_B(half_width: float, h_R: float) -> FloatArray:
    """(4, 3) lowest points of the landers in F_B [m], (+-w, +-w, -h_R), in
    :data:`LANDER_CORNERS` order: the landers plane h_R [m] below the centre of mass."""
    return lander_centres_B(half_width, h_R, 0.0)


def leg_segments_B(half_width: float, h_R: float, radius: float) -> FloatArray:
    """(4, 2, 3) legs in F_B [m], in :data:`LANDER_CORNERS` order: from the root
    (:data:`LEG_ROOT_FRACTION` of the lander's (x, y), at :data:`LEG_ROOT_Z`) to the
    lander's centre (:func:`lander_centres_B`); capsules of radius
    :data:`LEG_RADIUS_FRACTION` times the lander radius, so the lander sphere covers the
    leg's end."""
    tips = lander_centres_B(half_width, h_R, radius)
    roots = np.column_stack((LEG_ROOT_FRACTION * tips[:, :2], np.full(len(tips), LEG_ROOT_Z)))
    return np.stack((roots, tips), axis=1)


@dataclass(frozen=True)
class Capsule:
    """A segment swept by a sphere, in F_B.

    Attributes
    ----------
    name : str
        The plant's geom name (``arm0``, ``leg2``, ...).
    a_B, b_B : (3,) array
        End points [m].
    radius : float
        [m].
    """

    name: str
    a_B: FloatArray
    b_B: FloatArray
    radius: float


@dataclass(frozen=True)
class Airframe:
    """Every collision shape of a vehicle, in F_B [m]: what the plant simulates
    (:mod:`tetherland.sim.mjcf`) and the clearance checks measure
    (:mod:`tetherland.analysis.clearance`).

    Attributes
    ----------
    lander_centres_B : (4, 3) array
        Lander sphere centres (:func:`lander_centres_B`).
    lander_radius : float
    capsules : tuple of Capsule
        The legs ``leg0``-``leg3`` (:func:`leg_segments_B`) and the arms ``arm0``-``arm3``
        (centre of mass to rotor centre, :data:`ARM_RADIUS`).
    guard_centres_B : (4, 3) array
        Centres of the rotor-guard disks (:data:`PROP_HEIGHT` above the rotor centres).
    guard_radius, guard_half_thickness : float
        Disk radius (:data:`PROP_RADIUS_FRACTION` of the arm length) and half thickness.
    hub_half_size : (3,) tuple
        The hub box, centred on the centre of mass (:data:`HUB_HALF_SIZE`).
    mount_B : (3,) array
        Centre of the cable's mount sphere: the attachment point r_att.
    mount_radius : float
        :data:`MOUNT_RADIUS`.
    """

    lander_centres_B: FloatArray
    lander_radius: float
    capsules: tuple[Capsule, ...]
    guard_centres_B: FloatArray
    guard_radius: float
    guard_half_thickness: float
    hub_half_size: tuple[float, float, float]
    mount_B: FloatArray
    mount_radius: float

    @classmethod
    def of(cls, vehicle: VehicleConfig) -> Airframe:
        """The airframe of ``vehicle`` (its arm length, rotor layout, landers, r_att)."""
        r = vehicle.lander_radius
        rotors = RotorLayout.from_config(vehicle).positions_B
        legs = leg_segments_B(vehicle.lander_half_width, vehicle.h_R, r)
        capsules = tuple(
            Capsule(f"leg{i}", a, b, LEG_RADIUS_FRACTION * r) for i, (a, b) in enumerate(legs)
        ) + tuple(Capsule(f"arm{i}", np.zeros(3), r_i, ARM_RADIUS) for i, r_i in enumerate(rotors))
        return cls(
            lander_centres_B=lander_centres_B(vehicle.lander_half_width, vehicle.h_R, r),
            lander_radius=r,
            capsules=capsules,
            guard_centres_B=rotors + np.array([0.0, 0.0, PROP_HEIGHT]),
            guard_radius=PROP_RADIUS_FRACTION * vehicle.arm_length,
            guard_half_thickness=PROP_HALF_THICKNESS,
            hub_half_size=HUB_HALF_SIZE,
            mount_B=np.asarray(vehicle.cable_attachment, dtype=float),
            mount_radius=MOUNT_RADIUS,
        )

    def capsule(self, name: str) -> Capsule:
        """The capsule ``name`` (``leg0``, ``arm3``, ...)."""
        for c in self.capsules:
            if c.name == name:
                return c
        raise KeyError(f"no capsule '{name}' (have: {', '.join(c.name for c in self.capsules)})")


__all__ = [
    "ARM_RADIUS",
    "HUB_HALF_SIZE",
    "LANDER_CORNERS",
    "LEG_RADIUS_FRACTION",
    "LEG_ROOT_FRACTION",
    "LEG_ROOT_Z",
    "MOUNT_RADIUS",
    "PROP_HALF_THICKNESS",
    "PROP_HEIGHT",
    "PROP_RADIUS_FRACTION",
    "Airframe",
    "Capsule",
    "lander_centres_B",
    "lander_tips_B",
    "leg_segments_B",
]
