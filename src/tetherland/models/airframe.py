"""The airframe's collision shape beyond the landers: hub box and rotor guards.

Shared by the MuJoCo model builder (:mod:`tetherland.sim.mjcf`) and the clearance checks
(:mod:`tetherland.analysis.clearance`), so that what the planner checks is what the plant
simulates. Positions in F_B, sizes in metres.
"""

from __future__ import annotations

PROP_RADIUS_FRACTION = 0.4
"""Rotor-guard disk radius as a fraction of the arm length [-]."""
HUB_HALF_SIZE = (0.06, 0.06, 0.025)
"""Half extents of the central hub box [m]."""
PROP_HEIGHT = 0.02
"""Height of the rotor-guard disks above the rotor centres [m]."""
PROP_HALF_THICKNESS = 0.004
"""Half thickness of a rotor-guard disk [m]."""

__all__ = ["HUB_HALF_SIZE", "PROP_HALF_THICKNESS", "PROP_HEIGHT", "PROP_RADIUS_FRACTION"]
