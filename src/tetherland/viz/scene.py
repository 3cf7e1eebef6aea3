"""The 3D scene in Foxglove primitives: the MuJoCo scene itself, the plans and the cable.

The static scene is read off the plant's MuJoCo model (every visible geom of the world and
of the vehicle, with its size, pose and material colour), so the viewer shows exactly the
surface, pipe, ground, anchor and vehicle that the physics simulates. Frames: ``world``
(F_W), ``body`` (true F_B at the centre of mass), ``body_estimated`` (the estimate) and
``anchor`` (F_A at p_A).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence

import matplotlib
import mujoco
import numpy as np
from foxglove.messages import (
    Color,
    CubePrimitive,
    CylinderPrimitive,
    LinePrimitive,
    LinePrimitiveLineType,
    Point3,
    Pose,
    Quaternion,
    SceneEntity,
    SceneUpdate,
    SpherePrimitive,
    Timestamp,
    Vector3,
)

from tetherland import GRAVITY
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.planning.trajectory import Trajectory

WORLD, BODY, BODY_ESTIMATED, ANCHOR = "world", "body", "body_estimated", "anchor"
"""Frame ids."""
SLACK_TENSION = 0.05
"""Below this tension the cable is drawn as slack (grey) [N]."""
_VISIBLE_GROUPS = (0, 1, 2)
_LUT = matplotlib.colormaps["plasma"](np.linspace(0.0, 1.0, 256))
_PLAN_COLORS = {"landing": (0.15, 0.6, 1.0, 1.0), "takeoff": (0.85, 0.3, 0.9, 1.0)}


def timestamp(t: float) -> Timestamp:
    """Foxglove timestamp of mission time ``t`` [s] (sim time from 0)."""
    ns = round(t * 1e9)
    return Timestamp(ns // 1_000_000_000, ns % 1_000_000_000)


def vector(v: Sequence[float]) -> Vector3:
    return Vector3(x=float(v[0]), y=float(v[1]), z=float(v[2]))


def quaternion(q_wxyz: Sequence[float]) -> Quaternion:
    """Foxglove quaternion (named x, y, z, w) of our scalar-first (w, x, y, z)."""
    return Quaternion(x=float(q_wxyz[1]), y=float(q_wxyz[2]), z=float(q_wxyz[3]),
                      w=float(q_wxyz[0]))  # fmt: skip


def color(rgba: Sequence[float], alpha: float | None = None) -> Color:
    a = float(rgba[3]) if alpha is None else alpha
    return Color(r=float(rgba[0]), g=float(rgba[1]), b=float(rgba[2]), a=a)


def tension_rgba(tension: float, scale: float) -> tuple[float, float, float, float]:
    """Colour of the cable at ``tension`` [N]: grey when slack, else the plasma map of
    tension / ``scale`` (dark blue at 0, yellow at ``scale`` and beyond)."""
    if not tension > SLACK_TENSION:  # also NaN
        return (0.6, 0.6, 0.6, 0.8)
    k = min(int(255.0 * tension / scale), 255)
    r, g, b, _ = _LUT[k]
    return (float(r), float(g), float(b), 1.0)


def _geom_primitives(model: mujoco.MjModel, geom: int, rgba: Sequence[float]) -> dict:
    """One MuJoCo geom as Foxglove primitives, in its body's frame."""
    pose = Pose(
        position=vector(model.geom_pos[geom]), orientation=quaternion(model.geom_quat[geom])
    )
    size = model.geom_size[geom]
    c = color(rgba)
    kind = int(model.geom_type[geom])
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        return {"cubes": [CubePrimitive(pose=pose, size=vector(2.0 * size), color=c)]}
    if kind == mujoco.mjtGeom.mjGEOM_PLANE:
        dims = (2.0 * size[0], 2.0 * size[1], 1e-3)
        return {"cubes": [CubePrimitive(pose=pose, size=vector(dims), color=c)]}
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return {"spheres": [SpherePrimitive(pose=pose, size=vector([2.0 * size[0]] * 3), color=c)]}
    if kind in (mujoco.mjtGeom.mjGEOM_CYLINDER, mujoco.mjtGeom.mjGEOM_CAPSULE):
        dims = (2.0 * size[0], 2.0 * size[0], 2.0 * size[1])
        return {"cylinders": [CylinderPrimitive(pose=pose, size=vector(dims), bottom_scale=1.0,
                                                top_scale=1.0, color=c)]}  # fmt: skip
    return {}


def _merge(parts: Iterable[dict]) -> dict:
    out: dict[str, list] = {}
    for part in parts:
        for key, items in part.items():
            out.setdefault(key, []).extend(items)
    return out


def _geom_rgba(model: mujoco.MjModel, geom: int) -> FloatArray:
    mat = int(model.geom_matid[geom])
    return model.mat_rgba[mat] if mat >= 0 else model.geom_rgba[geom]


def _body_entity(
    model: mujoco.MjModel, body: int, entity_id: str, frame: str, t: float, alpha: float | None
) -> SceneEntity:
    parts = []
    for g in range(model.ngeom):
        in_body = int(model.geom_bodyid[g]) == body or (
            body != 0 and int(model.body_rootid[model.geom_bodyid[g]]) == body
        )  # the body's welded children too (the vehicle's landers)
        if in_body and int(model.geom_group[g]) in _VISIBLE_GROUPS:
            rgba = _geom_rgba(model, g).copy()
            if alpha is not None:
                rgba[3] = alpha
            parts.append(_geom_primitives(model, g, rgba))
    return SceneEntity(timestamp=timestamp(t), frame_id=frame, id=entity_id,
                       frame_locked=frame != WORLD, **_merge(parts))  # fmt: skip


def planned_path_W(trajectory: Trajectory, r_att_B: FloatArray, n: int = 200) -> FloatArray:
    """Centre-of-mass path of a planned tethered trajectory (flatness: the link end minus
    R_WB r_att) [m], (n, 3)."""
    times = np.linspace(0.0, trajectory.duration, n)
    nominal = trajectory.flatness.evaluate_many(trajectory.sample(times).outputs(), check=False)
    return nominal["p_W"] - nominal["R_WB"] @ np.asarray(r_att_B, dtype=float)


def static_scene(
    model: mujoco.MjModel,
    geometry: LandingGeometry,
    plans: Sequence[tuple[str, Trajectory]],
    r_att_B: FloatArray,
    t: float = 0.0,
    path_W: Callable[[Trajectory], FloatArray] | None = None,
) -> SceneUpdate:
    """Surface or pipe, ground, anchor, landing point, planned paths and the vehicle models.

    Parameters
    ----------
    model : mujoco.MjModel
        The plant's model (:attr:`tetherland.sim.Plant.model`).
    geometry : LandingGeometry
        Anchor and landing point.
    plans : sequence of (name, Trajectory)
        Planned maneuvers drawn as their centre-of-mass path.
    r_att_B : (3,) array
        Cable attachment in F_B [m].
    t : float
        Mission time of the update [s].
    path_W : callable, optional
        ``path_W(trajectory)``: the path drawn for a plan (default:
        :func:`planned_path_W` with ``r_att_B``; a cache of it for a scene republished
        often).
    """
    path_W = path_W or (lambda trajectory: planned_path_W(trajectory, r_att_B))
    vehicle = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "vehicle")
    entities = [
        _body_entity(model, 0, "scene", WORLD, t, None),
        _body_entity(model, vehicle, "vehicle", BODY, t, None),
        _body_entity(model, vehicle, "vehicle_estimated", BODY_ESTIMATED, t, 0.25),
    ]
    level = quaternion([1.0, 0.0, 0.0, 0.0])
    marks = [
        SpherePrimitive(pose=Pose(position=vector(geometry.p_A), orientation=level),
                        size=vector([0.04] * 3), color=Color(r=0.9, g=0.2, b=0.1, a=1.0)),
        SpherePrimitive(pose=Pose(position=vector(geometry.p_L), orientation=level),
                        size=vector([0.03] * 3), color=Color(r=0.1, g=0.8, b=0.2, a=1.0)),
    ]  # fmt: skip
    entities.append(SceneEntity(timestamp=timestamp(t), frame_id=WORLD,
                                id="anchor_and_landing_point", spheres=marks))  # fmt: skip
    for name, trajectory in plans:
        path = path_W(trajectory)
        line = LinePrimitive(
            type=LinePrimitiveLineType.LineStrip, thickness=0.01,
            points=[Point3(x=float(x), y=float(y), z=float(z)) for x, y, z in path],
            color=color(_PLAN_COLORS.get(name, (1.0, 1.0, 1.0, 1.0))),
        )  # fmt: skip
        entities.append(SceneEntity(timestamp=timestamp(t), frame_id=WORLD, id=f"plan/{name}",
                                    lines=[line]))  # fmt: skip
    return SceneUpdate(entities=entities)


def cable_update(
    t: float, p_A: FloatArray, attachment_W: FloatArray, engaged: bool, tension: float, scale: float
) -> SceneUpdate:
    """The cable from the anchor to the attachment point, coloured by its tension; an
    entity without lines while the cable is not hooked."""
    lines = []
    if engaged:
        a, b = p_A, attachment_W
        lines.append(LinePrimitive(
            type=LinePrimitiveLineType.LineStrip, thickness=0.008,
            points=[Point3(x=float(a[0]), y=float(a[1]), z=float(a[2])),
                    Point3(x=float(b[0]), y=float(b[1]), z=float(b[2]))],
            color=color(tension_rgba(tension, scale)),
        ))  # fmt: skip
    return SceneUpdate(entities=[SceneEntity(timestamp=timestamp(t), frame_id=WORLD, id="cable",
                                             lines=lines)])  # fmt: skip


def tension_scale(mass: float) -> float:
    """Tension at the top of the cable's colour map: the vehicle's weight m g [N]."""
    return mass * GRAVITY


__all__ = [
    "ANCHOR",
    "BODY",
    "BODY_ESTIMATED",
    "WORLD",
    "cable_update",
    "planned_path_W",
    "static_scene",
    "tension_rgba",
    "tension_scale",
    "timestamp",
]
