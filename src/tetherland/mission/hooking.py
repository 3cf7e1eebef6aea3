"""The hooking pass of a design and its clearance from the surface.

The pass is the one the mission supervisor flies (:func:`tetherland.mission.plan_mission`
puts its ends into the waypoints): the vehicle level with heading x_A,
the hook point moving straight along the approach direction n from ``approach_distance``
before the anchor to ``hook_overshoot`` beyond it (``mission`` section).

Hook model assumed here: the hook point is the cable attachment point moved by
``hook_drop`` along n, leading the vehicle in the direction it moves. For the default
approach n = -z_W this is the hook hanging under the vehicle; for other directions the
hook is held out along the approach direction (a hook on a short stiff arm), which lets
the vehicle hook an anchor on a wall or an overhang from the side or from below.
:func:`hook_offset` is the one place that states it; the plant's hook model
(:mod:`tetherland.sim.hook`) uses the same offset.

The clearance is that of the plant's collision shape, computed by
:func:`tetherland.analysis.clearance.hooking_clearance`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland.analysis.clearance import HookingClearance, hooking_clearance
from tetherland.config import Scenario
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.rotations import rotation_from_z_and_yaw

_Z_W = np.array([0.0, 0.0, 1.0])
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

    def points(self, count: int) -> FloatArray:
        """``count`` centre-of-mass points evenly along the pass, (count, 3) [m]."""
        s = np.linspace(0.0, 1.0, count)[:, None]
        return (1.0 - s) * self.p_start_W + s * self.p_end_W


def hook_offset(n_W: FloatArray, hook_drop: float) -> FloatArray:
    """Hook point minus attachment point, hook_drop n [m] (the assumed hook model)."""
    return hook_drop * n_W


def hooking_pass(scenario: Scenario, geometry: LandingGeometry | None = None) -> HookingPass:
    """The hooking pass of ``scenario`` (its tether, vehicle and mission settings)."""
    t, cfg = scenario.tether, scenario.mission
    return hooking_pass_for(
        geometry or LandingGeometry.from_scenario(scenario),
        approach_A=t.approach_direction,
        hook_drop=t.hook_drop,
        r_att_B=scenario.vehicle.cable_attachment,
        approach_distance=cfg.approach_distance,
        hook_overshoot=cfg.hook_overshoot,
    )


def hooking_pass_for(
    geometry: LandingGeometry,
    *,
    approach_A: ArrayLike,
    hook_drop: float,
    r_att_B: ArrayLike,
    approach_distance: float,
    hook_overshoot: float,
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
    """
    R_WA = geometry.R_WA
    n_W = R_WA @ np.asarray(approach_A, dtype=float)
    n_W = n_W / np.linalg.norm(n_W)
    yaw = math.atan2(R_WA[1, 0], R_WA[0, 0])
    r_att_W = rotation_from_z_and_yaw(_Z_W, yaw) @ np.asarray(r_att_B, dtype=float)
    shift = hook_offset(n_W, hook_drop) + r_att_W
    return HookingPass(
        p_start_W=geometry.p_A - approach_distance * n_W - shift,
        p_end_W=geometry.p_A + hook_overshoot * n_W - shift,
        n_W=n_W,
        yaw=yaw,
    )


def check_pass(
    scenario: Scenario, geometry: LandingGeometry, hooking: HookingPass
) -> HookingClearance:
    """Clearance of the level vehicle (``scenario``'s collision shape) from the surface of
    ``geometry`` along the hooking pass, against ``mission.hooking_clearance``, with the
    hook drop that would restore it."""
    count = PIPE_SAMPLES if geometry.surface.kind == "pipe" else 2
    points = hooking.points(count)
    margin = scenario.mission.hooking_clearance
    return hooking_clearance(scenario, geometry.surface, points, hooking.yaw, margin, hooking.n_W)


def pass_clearance(scenario: Scenario, geometry: LandingGeometry, hooking: HookingPass) -> float:
    """Smallest distance of the level vehicle from the surface along the hooking pass [m]."""
    return check_pass(scenario, geometry, hooking).clearance_m
