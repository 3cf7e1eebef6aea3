"""MJCF model of the scene, generated from a scenario (docs/theory.md section 9).

The scene: a quadrotor (one rigid body with a free joint, mass and principal inertia from
``[vehicle]``, four lander spheres whose lowest points form the landers plane h_R below
the centre of mass), four rotor sites with thrust actuators (force along z_B, yaw drag
torque sigma_i c_tau per newton), the landing surface (a tilted box for a plane, a tilted
cylinder for a pipe), a horizontal ground plane for the start pad, the anchor site, and
the cable as a spatial tendon from the anchor to the attachment site r_att, limited to
[0, l]. Sensors (in ``sensordata`` order, see :data:`SENSOR_LAYOUT`): IMU accelerometer
and gyro at the centre of mass, cable limit force and length, lander touch forces and a
touch sensor around the frame (crash detection).

Names are fixed (``vehicle``, ``attachment``, ``cable``, ...): the plant, the renderer and
tests find elements by these names.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from tetherland import GRAVITY
from tetherland.config import Scenario
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.models.airframe import (
    HUB_HALF_SIZE,
    PROP_HALF_THICKNESS,
    PROP_HEIGHT,
    PROP_RADIUS_FRACTION,
)
from tetherland.models.quadrotor import RotorLayout
from tetherland.rotations import rotmat_to_quat

SURFACE_HALF_THICKNESS = 0.05
"""Half thickness of the box that carries a planar surface [m]."""
START_CLEARANCE = 1.0
"""Default horizontal distance of the start pad beyond the foot of the surface patch [m]."""


SENSOR_LAYOUT: tuple[tuple[str, int], ...] = (
    ("accelerometer", 3),
    ("gyro", 3),
    ("cable_force", 1),
    ("cable_length", 1),
    ("lander0_touch", 1),
    ("lander1_touch", 1),
    ("lander2_touch", 1),
    ("lander3_touch", 1),
    ("frame_touch", 1),
)
"""Sensors in ``sensordata`` order: (name, dimension)."""


def _sensor_slices() -> dict[str, slice]:
    out, i = {}, 0
    for name, dim in SENSOR_LAYOUT:
        out[name] = slice(i, i + dim)
        i += dim
    return out


SENSOR_SLICES: Mapping[str, slice] = MappingProxyType(_sensor_slices())
"""Slice of each sensor in ``sensordata``."""


@dataclass(frozen=True)
class SceneLayout:
    """Where things are in the scene built from a scenario.

    Attributes
    ----------
    geometry : LandingGeometry
        Anchor, surface frame and landing point (section 6.4.2).
    rotors : RotorLayout
        Rotor positions, spins and coefficients.
    ground_z : float
        Height of the ground plane [m].
    start_position : (3,) array
        Centre of the landers plane on the start pad [m].
    approach_W : (3,) unit array
        Hook approach direction (capture disk normal) in F_W.
    prop_radius : float
        Radius of the rotor guards [m].
    """

    geometry: LandingGeometry
    rotors: RotorLayout
    ground_z: float
    start_position: FloatArray
    approach_W: FloatArray
    prop_radius: float

    @classmethod
    def from_scenario(cls, scenario: Scenario) -> SceneLayout:
        geom = LandingGeometry.from_scenario(scenario)
        surf = geom.surface
        extent = scenario.surface.extent
        foot_top = surf.origin + extent * surf.x_S  # downhill end of the top face / top line
        if surf.kind == "pipe":
            R = scenario.surface.pipe_radius
            axis_low = foot_top - R * surf.z_S
            lowest = float(axis_low[2]) - R * math.sqrt(max(0.0, 1.0 - surf.x_S[2] ** 2))
            beyond = R
        else:
            lowest = float(foot_top[2])
            beyond = 0.0
        ground_z = lowest if scenario.sim.ground_z is None else scenario.sim.ground_z
        if scenario.sim.start_position is not None:
            start = np.asarray(scenario.sim.start_position, dtype=float)
        else:
            x_A = geom.R_WA[:, 0]
            start = foot_top + (START_CLEARANCE + beyond) * x_A
            start = np.array([start[0], start[1], ground_z])
        n = np.asarray(scenario.tether.approach_direction, dtype=float)
        approach_W = geom.R_WA @ (n / np.linalg.norm(n))
        return cls(
            geometry=geom,
            rotors=RotorLayout.from_config(scenario.vehicle),
            ground_z=float(ground_z),
            start_position=start,
            approach_W=approach_W,
            prop_radius=PROP_RADIUS_FRACTION * scenario.vehicle.arm_length,
        )


def _fmt(values: FloatArray | tuple[float, ...] | list[float]) -> str:
    return " ".join(f"{float(v):.12g}" for v in np.ravel(values))


def _quat_of_columns(x: FloatArray, y: FloatArray, z: FloatArray) -> str:
    return _fmt(rotmat_to_quat(np.column_stack((x, y, z))))


def _quat_z_to(axis: FloatArray) -> str:
    """Quaternion rotating local z onto ``axis`` (for cylinders and disks)."""
    a = axis / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, a)
    x /= np.linalg.norm(x)
    return _quat_of_columns(x, np.cross(a, x), a)


def _sub(parent: ET.Element, tag: str, **attrs: str) -> ET.Element:
    return ET.SubElement(parent, tag, {k.rstrip("_"): v for k, v in attrs.items()})


def build_mjcf(scenario: Scenario, layout: SceneLayout | None = None) -> str:
    """MJCF text of the scene for ``scenario`` (compile with ``MjModel.from_xml_string``).

    The cable tendon is created limited (engaged); the plant disengages it at reset, as
    the hook model requires.
    """
    layout = SceneLayout.from_scenario(scenario) if layout is None else layout
    v, sim, tether = scenario.vehicle, scenario.sim, scenario.tether
    geom = layout.geometry
    surf = geom.surface
    mu = scenario.surface.friction
    contact_solref = _fmt((sim.contact_timeconst, sim.contact_dampratio))

    root = ET.Element("mujoco", model=f"tetherland_{scenario.name}")
    _sub(root, "compiler", angle="radian", autolimits="true")
    option = _sub(
        root,
        "option",
        timestep=f"{sim.timestep:.12g}",
        integrator=sim.integrator,
        cone="elliptic",
        impratio=f"{sim.impratio:.12g}",
        jacobian="dense",
        solver="Newton",
        gravity=_fmt((0.0, 0.0, -GRAVITY)),
    )
    # A diverging simulation must fail loudly, not silently restart from qpos0.
    _sub(option, "flag", autoreset="disable")
    visual = _sub(root, "visual")
    _sub(visual, "global", offwidth="1920", offheight="1080")
    _sub(visual, "quality", shadowsize="1024")
    _sub(visual, "map", znear="0.01")

    asset = _sub(root, "asset")
    _sub(
        asset,
        "texture",
        name="grid",
        type="2d",
        builtin="checker",
        width="512",
        height="512",
        rgb1=".32 .36 .30",
        rgb2=".27 .31 .25",
    )
    _sub(asset, "material", name="ground", texture="grid", texrepeat="8 8", reflectance="0.05")
    _sub(
        asset,
        "texture",
        name="sky",
        type="skybox",
        builtin="gradient",
        width="256",
        height="256",
        rgb1=".55 .7 .9",
        rgb2=".95 .95 1",
    )
    _sub(asset, "material", name="surface", rgba=".62 .55 .45 1")
    _sub(asset, "material", name="frame", rgba=".15 .15 .18 1")
    _sub(asset, "material", name="prop", rgba=".85 .85 .9 .45")

    default = _sub(root, "default")
    vis = _sub(default, "default", class_="visual")
    _sub(vis, "geom", contype="0", conaffinity="0", group="1", mass="0")
    col = _sub(default, "default", class_="collision")
    _sub(col, "geom", group="3", mass="0", condim="3")

    world = _sub(root, "worldbody")
    _sub(
        world,
        "light",
        name="sun",
        directional="true",
        pos="0 0 6",
        dir="0.3 0.4 -1",
        castshadow="true",
        diffuse=".8 .8 .8",
    )
    env_contact = {"priority": "1", "condim": "3", "solref": contact_solref}
    _sub(
        world,
        "geom",
        name="ground",
        type="plane",
        size="12 12 0.1",
        pos=_fmt((0, 0, layout.ground_z)),
        material="ground",
        friction="1.0 0.005 0.0001",
        **env_contact,
    )
    friction = f"{mu:.12g} 0.005 0.0001"
    if surf.kind == "pipe":
        R = scenario.surface.pipe_radius
        centre = surf.origin - R * surf.z_S
        _sub(
            world,
            "geom",
            name="surface",
            type="cylinder",
            size=_fmt((R, scenario.surface.extent)),
            pos=_fmt(centre),
            quat=_quat_of_columns(surf.y_S, surf.z_S, surf.x_S),
            material="surface",
            friction=friction,
            **env_contact,
        )
    else:
        centre = surf.origin - SURFACE_HALF_THICKNESS * surf.z_S
        e = scenario.surface.extent
        _sub(
            world,
            "geom",
            name="surface",
            type="box",
            size=_fmt((e, e, SURFACE_HALF_THICKNESS)),
            pos=_fmt(centre),
            quat=_quat_of_columns(surf.x_S, surf.y_S, surf.z_S),
            material="surface",
            friction=friction,
            **env_contact,
        )

    # Anchor: the cable end, a short horizontal bar along y_A and the capture disk.
    p_A = geom.p_A
    _sub(world, "site", name="anchor", pos=_fmt(p_A), size="0.02", rgba=".9 .2 .1 1")
    _sub(
        world,
        "geom",
        name="anchor_bar",
        class_="visual",
        type="capsule",
        size="0.006",
        fromto=_fmt(np.concatenate((p_A - 0.08 * geom.R_WA[:, 1], p_A + 0.08 * geom.R_WA[:, 1]))),
        rgba=".9 .2 .1 1",
    )
    _sub(
        world,
        "geom",
        name="capture_disk",
        class_="visual",
        type="cylinder",
        size=_fmt((tether.capture_radius, 0.001)),
        pos=_fmt(p_A),
        quat=_quat_z_to(layout.approach_W),
        rgba=".9 .6 .1 .25",
        group="2",
    )

    # The vehicle, at the start pad; the plant sets the initial state.
    start_com = layout.start_position + np.array([0.0, 0.0, v.h_R])
    body = _sub(world, "body", name="vehicle", pos=_fmt(start_com))
    _sub(body, "freejoint", name="vehicle_free")
    _sub(body, "inertial", pos="0 0 0", mass=f"{v.mass:.12g}", diaginertia=_fmt(v.inertia))
    _sub(body, "site", name="imu", pos="0 0 0", size="0.01", group="4")
    _sub(
        body,
        "site",
        name="attachment",
        pos=_fmt(v.cable_attachment),
        size="0.008",
        rgba=".9 .2 .1 1",
    )
    _sub(
        body,
        "geom",
        name="hub",
        class_="collision",
        type="box",
        size=_fmt(HUB_HALF_SIZE),
        material="frame",
        group="1",
    )
    _sub(
        body,
        "site",
        name="frame_zone",
        type="box",
        group="4",
        size=_fmt((v.arm_length + layout.prop_radius, v.arm_length + layout.prop_radius, 0.04)),
    )
    w, r, h = v.lander_half_width, v.lander_radius, v.h_R
    for i, (sx, sy) in enumerate(((1, 1), (-1, 1), (-1, -1), (1, -1))):
        tip = np.array([sx * w, sy * w, -(h - r)])
        _sub(
            body,
            "geom",
            name=f"lander{i}",
            class_="collision",
            type="sphere",
            size=f"{r:.12g}",
            pos=_fmt(tip),
            rgba=".1 .1 .1 1",
            group="1",
        )
        _sub(
            body,
            "geom",
            name=f"leg{i}",
            class_="visual",
            type="capsule",
            size=f"{0.35 * r:.12g}",
            fromto=_fmt(np.concatenate((np.array([0.5 * sx * w, 0.5 * sy * w, -0.02]), tip))),
            material="frame",
        )
        _sub(
            body,
            "site",
            name=f"lander{i}_zone",
            type="sphere",
            size=f"{1.5 * r:.12g}",
            pos=_fmt(tip),
            group="4",
        )
    for i, r_i in enumerate(layout.rotors.positions_B):
        _sub(body, "site", name=f"rotor{i}", pos=_fmt(r_i), size="0.01", group="4")
        _sub(
            body,
            "geom",
            name=f"arm{i}",
            class_="visual",
            type="capsule",
            size="0.008",
            fromto=_fmt(np.concatenate((np.zeros(3), r_i))),
            material="frame",
        )
        _sub(
            body,
            "geom",
            name=f"prop{i}",
            class_="collision",
            type="cylinder",
            size=_fmt((layout.prop_radius, PROP_HALF_THICKNESS)),
            pos=_fmt(r_i + np.array([0, 0, PROP_HEIGHT])),
            material="prop",
            group="1",
        )

    tendon = _sub(root, "tendon")
    cable = _sub(
        tendon,
        "spatial",
        name="cable",
        limited="true",
        range=_fmt((0.0, tether.length)),
        width="0.004",
        rgba=".95 .85 .2 1",
        solreflimit=_fmt((sim.cable_timeconst, sim.cable_dampratio)),
    )
    _sub(cable, "site", site="anchor")
    _sub(cable, "site", site="attachment")

    act = _sub(root, "actuator")
    c_tau = layout.rotors.drag_coefficient
    for i, sigma in enumerate(layout.rotors.spins):
        # ctrl = rotor thrust f_i [N]: force f_i along the site z (= z_B) at the rotor, and
        # the drag torque sigma_i c_tau f_i about z_B.
        _sub(
            act,
            "general",
            name=f"rotor{i}",
            site=f"rotor{i}",
            gear=_fmt((0, 0, 1, 0, 0, sigma * c_tau)),
            ctrlrange=_fmt((0.0, v.f_max)),
        )

    sensor = _sub(root, "sensor")
    _sub(sensor, "accelerometer", name="accelerometer", site="imu")
    _sub(sensor, "gyro", name="gyro", site="imu")
    _sub(sensor, "tendonlimitfrc", name="cable_force", tendon="cable")
    _sub(sensor, "tendonpos", name="cable_length", tendon="cable")
    for i in range(4):
        _sub(sensor, "touch", name=f"lander{i}_touch", site=f"lander{i}_zone")
    _sub(sensor, "touch", name="frame_touch", site="frame_zone")

    ET.indent(root)
    return ET.tostring(root, encoding="unicode")
