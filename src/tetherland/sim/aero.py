"""The ``[aero]`` model of one scene: the compiled scene's surfaces as packed shapes.

The shapes are read from the compiled MuJoCo model, so the rotors feel exactly the
surfaces the landers touch: every collision geom of the world body that is a plane (the
ground and start pad), a box (a planar surface) or a cylinder (a pipe).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from tetherland import GRAVITY
from tetherland.config import Scenario
from tetherland.models.aero import AeroModel, ShapeKind, disk_samples, pack_shape, rotor_disks
from tetherland.rotations import quat_to_rotmat

_KINDS = {
    int(mujoco.mjtGeom.mjGEOM_PLANE): ShapeKind.PLANE,
    int(mujoco.mjtGeom.mjGEOM_BOX): ShapeKind.BOX,
    int(mujoco.mjtGeom.mjGEOM_CYLINDER): ShapeKind.CYLINDER,
}


def scene_shapes(model: mujoco.MjModel) -> np.ndarray:
    """The world body's colliding planes, boxes and cylinders, packed, (n, SHAPE_WIDTH)."""
    rows = []
    for g in range(model.ngeom):
        if model.geom_bodyid[g] != 0 or not (model.geom_contype[g] or model.geom_conaffinity[g]):
            continue
        kind = _KINDS.get(int(model.geom_type[g]))
        if kind is None:
            continue
        size = model.geom_size[g]
        if kind is ShapeKind.CYLINDER:
            size = (size[0], size[1], 0.0)
        R_WL = quat_to_rotmat(model.geom_quat[g])
        rows.append(pack_shape(kind, model.geom_pos[g], R_WL, size))
    return np.array(rows).reshape(-1, 16)


def aero_model(scenario: Scenario, model: mujoco.MjModel) -> AeroModel | None:
    """The aero model of ``scenario`` in the compiled scene ``model``, or None when
    ``[aero]`` switches every effect off."""
    a, v = scenario.aero, scenario.vehicle
    if not a.active:
        return None
    centres, radius = rotor_disks(v, a.rotor_radius)
    return AeroModel(
        rotor_centres_B=centres,
        radius=radius,
        samples=disk_samples(a.disk_rings, a.disk_sectors),
        shapes=scene_shapes(model),
        ground_effect=a.ground_effect,
        wall_effect=a.wall_effect,
        z_min_ratio=a.min_distance_ratio,
        ceiling_coefficient=a.ceiling_coefficient,
        wall_coefficient=a.wall_coefficient,
        drag=(float(a.rotor_drag[0]), float(a.rotor_drag[1])),
        hover_speed=math.sqrt(v.mass * GRAVITY / (4.0 * v.thrust_coefficient)),
        thrust_coefficient=v.thrust_coefficient,
    )
