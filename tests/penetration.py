"""Test helper: no part of the vehicle goes behind any surface over a whole run.

Two measures of the plant's truth, both from the run's log, nothing the robot believed:

- MuJoCo's: the log's ``penetration`` column, the deepest contact distance of any vehicle
  geom into anything (landing surface, ground, anchor geometry), its peak over every
  physics step;
- the geometry's: the vehicle's collision shape
  (:func:`tetherland.analysis.clearance.vehicle_distance`, the airframe the plant
  simulates) at every logged pose against the landing surface (the ticks above its
  simulated patch, which is all the plant has of it) and the ground plane.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tetherland.analysis.clearance import surface_distance, vehicle_distance
from tetherland.config import Scenario
from tetherland.geometry import LandingGeometry
from tetherland.rotations import quat_to_rotmat_many
from tetherland.sim import SimLog
from tetherland.sim.mjcf import SceneLayout
from tetherland.surface import Surface

BEHIND_LIMIT = 0.002
"""The most any part of the vehicle may go behind a surface [m]."""
NEAR = 0.5
"""Only poses whose centre of mass is within this of a surface are checked against it
(the vehicle reaches less than 0.4 m from its centre) [m]."""


@dataclass(frozen=True)
class Deepest:
    """The deepest a run's vehicle went behind a surface, by one measure.

    Attributes
    ----------
    depth_m : float
        How far behind (>= 0; 0 when never) [m].
    t : float or None
        When [s] (None when never).
    where : str
        What was measured (``mujoco``, ``surface``, ``ground``).
    """

    depth_m: float
    t: float | None
    where: str


def deepest_behind(log: SimLog, truth: Scenario) -> list[Deepest]:
    """The deepest penetration of the run by MuJoCo's contacts and by the geometry of the
    logged poses against the landing surface and the ground."""
    t = log["t"]
    out = []
    pen = np.nan_to_num(np.asarray(log["penetration"], dtype=float))
    k = int(np.argmax(pen)) if len(pen) else 0
    out.append(Deepest(float(pen[k]) if len(pen) else 0.0,
                       float(t[k]) if len(pen) and pen[k] > 0 else None, "mujoco"))  # fmt: skip
    geo = LandingGeometry.from_scenario(truth)
    surf = geo.surface
    ground_z = SceneLayout.from_scenario(truth).ground_z
    ground = Surface(origin=np.array([0.0, 0.0, ground_z]), R_WS=np.eye(3))
    p = np.asarray(log["p_W"], dtype=float)
    R = quat_to_rotmat_many(np.asarray(log["q_WB"], dtype=float))
    d = p - surf.origin
    extent = truth.surface.extent
    over = np.abs(d @ surf.x_S) <= extent
    if surf.kind != "pipe":
        over &= np.abs(d @ surf.y_S) <= extent
    for where, shape, rows in (
        ("surface", surf, over & (surface_distance(surf, p) < NEAR)),
        ("ground", ground, surface_distance(ground, p) < NEAR),
    ):
        depth, when = 0.0, None
        for i in np.flatnonzero(rows):
            behind = -vehicle_distance(truth.vehicle, shape, p[i], R[i])
            if behind > depth:
                depth, when = behind, float(t[i])
        out.append(Deepest(depth, when, where))
    return out


def assert_nothing_behind_surfaces(
    log: SimLog, truth: Scenario, limit: float = BEHIND_LIMIT
) -> list[Deepest]:
    """Assert that no part of the vehicle went more than ``limit`` behind any surface in
    the run, by every measure of :func:`deepest_behind`; returns the measures."""
    found = deepest_behind(log, truth)
    for m in found:
        assert m.depth_m <= limit, (
            f"a part of the vehicle went {m.depth_m * 1e3:.2f} mm behind a surface "
            f"({m.where}) at t = {m.t} s (limit {limit * 1e3:g} mm)"
        )
    return found
