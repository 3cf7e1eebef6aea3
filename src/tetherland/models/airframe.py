"""The airframe's collision shape: landers, hub box and rotor guards.

The one statement of the vehicle's shape, shared by the MuJoCo model builder
(:mod:`tetherland.sim.mjcf`), the clearance checks (:mod:`tetherland.analysis.clearance`)
and the robot's contact rules (:mod:`tetherland.mission.contact`, the contact-free
method), so that what the planner checks and the robot believes is what the plant
simulates. Positions in F_B (FLU: x forward, y left, z up the thrust axis), sizes in
metres.
"""

from __future__ import annotations

import numpy as np

from tetherland.geometry import FloatArray

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


__all__ = [
    "HUB_HALF_SIZE",
    "LANDER_CORNERS",
    "PROP_HALF_THICKNESS",
    "PROP_HEIGHT",
    "PROP_RADIUS_FRACTION",
    "lander_centres_B",
    "lander_tips_B",
]
