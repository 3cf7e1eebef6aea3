"""MJCF model of the scene, generated from a scenario (docs/theory.md section 9).

The scene: a quadrotor (one rigid body with a free joint, mass and principal inertia from
``[vehicle]``, four lander spheres whose lowest points form the landers plane h_R below
the centre of mass), four rotor sites with thrust actuators (force along z_B, yaw drag
torque sigma_i c_tau per newton), the landing surface (a tilted box for a plane, a tilted
cylinder for a pipe), a horizontal ground plane for the start pad, the anchor site, and
the cable (docs/tether.md), by ``tether.cable_model``:

- ideal: the spatial tendon ``cable`` from the anchor to the attachment site r_att,
  limited to [0, l] (a unilateral constraint at l);
- elastic: the same tendon without a limit, pulled by the actuator ``cable`` whose control
  the plant sets to the unilateral spring-damper force each step;
- chain: ``segments`` links hanging from the anchor (:func:`add_chain`) and the inactive
  connect ``hook`` to the attachment site; the tendon stays, hidden, to measure the
  anchor-attachment distance.

Every part of the vehicle collides (:data:`FRAME_PARTS` and the landers, the shapes of
:class:`tetherland.models.airframe.Airframe`): with the environment (ground, surface and
whatever else the world holds with the default ``contype``), never with each other
(:data:`VEHICLE_CONTYPE`, :data:`VEHICLE_CONAFFINITY`).

Sensors (in ``sensordata`` order, see :data:`SENSOR_LAYOUT`): IMU accelerometer and gyro
at the centre of mass, cable tension at the attachment (``tendonlimitfrc``,
``actuatorfrc`` or a user sensor the plant writes) and length, lander touch forces, the
contact force of each lander with the landing surface and with the ground (``contact``
sensors filtered by partner geom: what a lander touches, for the judge;
:data:`CONTACT_PARTNERS`), the number of contacts of the other parts (``frame_contacts``:
the landers sit in a child body ``landers`` welded to the vehicle, so that the body
``vehicle`` holds exactly :data:`FRAME_PARTS`) and the depth of the deepest contact of
the whole vehicle (``vehicle_depth``). The plant reads them at every physics step; at a
step with a frame contact (a crash) it sums each part's normal forces from MuJoCo's
contact list.

Names are fixed (``vehicle``, ``attachment``, ``cable``, ...): the plant, the renderer and
tests find elements by these names.

:func:`build_mjcf` runs the named builders of :data:`SCENE_BUILDERS` in order (options and
assets, ground and surface, anchor, vehicle, cable, actuators, sensors), each adding its
part to one :class:`SceneXml`; the vehicle's shape comes from
:mod:`tetherland.models.airframe`.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
from numpy.typing import ArrayLike

from tetherland import GRAVITY
from tetherland.config import CableModel, Scenario
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.models.airframe import (
    LANDER_CORNERS,
    PROP_RADIUS_FRACTION,
    Airframe,
)
from tetherland.models.hook import BOOM_RADIUS
from tetherland.models.quadrotor import RotorLayout
from tetherland.rotations import rotmat_to_quat
from tetherland.state import RigidBodyState

SURFACE_HALF_THICKNESS = 0.05
"""Half thickness of the box that carries a planar surface [m]."""
START_CLEARANCE = 1.0
"""Default horizontal distance of the start pad beyond the foot of the surface patch [m]."""


CABLE_GROUP_VISIBLE, CABLE_GROUP_HIDDEN = 0, 5
"""Tendon and geom groups of the engaged (drawn) and disengaged (hidden) cable."""
CHAIN_RADIUS = 0.002
"""Radius of the drawn chain links (visual only: the links do not collide) [m]."""
CHAIN_DAMPING_TIME = 0.2
"""Time constant of the chain's joint damping on the links' own inertia [s]: air drag and
internal friction damp a thin line's transverse vibration within about a second."""
CHAIN_W_DT = 0.5
"""Highest angular frequency times the time step allowed for a link's swing about its
joint under the largest tension (the armature of :func:`chain_spec`) [-]."""

CONTACT_PARTNERS: tuple[str, ...] = ("surface", "ground")
"""Geoms whose contact force with each lander has its own sensor ``lander<i>_<partner>``:
the force of the first contact of the pair in its contact frame (normal, tangent 1,
tangent 2) [N]; a lander sphere meets the box, cylinder or plane at one point."""

FRAME_PARTS: tuple[str, ...] = (
    "hub", "mount", *(f"arm{i}" for i in range(4)), *(f"leg{i}" for i in range(4)),
    *(f"prop{i}" for i in range(4)),
)  # fmt: skip
"""The vehicle's colliding geoms other than the landers, in the order of the plant's part
codes (the log's ``frame_part``): the hub, the cable's mount, the arms, the legs and the
rotor guards. A contact force on any of them is a crash."""

VEHICLE_CONTYPE, VEHICLE_CONAFFINITY = 2, 1
"""Collision bits of every vehicle geom: it collides with geoms whose ``contype`` has bit
0 set (the world's: ground, surface, anchor; MuJoCo's default 1) and with no other
vehicle geom (2 & 1 = 0)."""

SENSOR_LAYOUT: tuple[tuple[str, int], ...] = (
    ("accelerometer", 3),
    ("gyro", 3),
    ("cable_force", 1),
    ("cable_length", 1),
    ("lander0_touch", 1),
    ("lander1_touch", 1),
    ("lander2_touch", 1),
    ("lander3_touch", 1),
    *((f"lander{i}_{partner}", 3) for partner in CONTACT_PARTNERS for i in range(4)),
    ("frame_contacts", 1),
    ("vehicle_depth", 1),
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

    def start_state(self, h_R: float) -> RigidBodyState:
        """At rest on the start pad, the centre of mass ``h_R`` [m] above it, level, x_B
        along x_A (the downhill horizontal): the plant's start (``Plant.start_state``)."""
        R = heading_rotation([0.0, 0.0, 1.0], self.geometry.R_WA[:, 0])
        p = self.start_position + np.array([0.0, 0.0, h_R])
        return RigidBodyState.at_rest(p, rotmat_to_quat(R))


def heading_rotation(z_B: ArrayLike, x_hint: ArrayLike) -> FloatArray:
    """R_WB with third column ``z_B`` and x_B the projection of ``x_hint`` orthogonal to it."""
    z = np.asarray(z_B, dtype=float)
    z = z / np.linalg.norm(z)
    x = np.asarray(x_hint, dtype=float) - (z @ np.asarray(x_hint, dtype=float)) * z
    x /= np.linalg.norm(x)
    return np.column_stack((x, np.cross(z, x), z))


@dataclass(frozen=True)
class ChainSpec:
    """The massive cable as a chain of rigid links with ball joints (docs/tether.md).

    Attributes
    ----------
    segments : int
        Number of links N.
    link_length : float
        l_s = l/N [m].
    link_mass : float
        rho l_s [kg].
    armature : float
        Rotor-like inertia added to each ball joint so that a link swinging about its joint
        under the largest tension stays resolvable by the time step [kg m^2].
    joint_damping : float
        Viscous damping of each ball joint [N m s/rad].
    """

    segments: int
    link_length: float
    link_mass: float
    armature: float
    joint_damping: float = 0.0

    @property
    def total_mass(self) -> float:
        """Mass of the cable [kg]."""
        return self.segments * self.link_mass


def chain_armature(
    tension_max: float, link_length: float, link_mass: float, timestep: float
) -> float:
    """Ball-joint armature a that keeps w dt <= :data:`CHAIN_W_DT` for every link [kg m^2].

    A link of length l_s pulled straight by tension T swings about its joint with
    w^2 = T l_s / (I + a), I = m_s l_s^2 / 3. Real 1 mm lines are so light (0.6 g/m) that
    w dt reaches 1-2 at 1 ms and the explicit chain diverges; the armature slows these
    swings to what the step resolves and changes nothing in statics:
    a = max(0, T_max l_s dt^2 / (w dt)_max^2 - I).
    """
    inertia = link_mass * link_length**2 / 3.0
    return max(0.0, tension_max * link_length * timestep**2 / CHAIN_W_DT**2 - inertia)


def chain_design_tension(scenario: Scenario) -> float:
    """Tension the chain's armature is designed for: the vehicle's full thrust plus its
    weight [N] (the plant raises the armature above it while snap loads last)."""
    v = scenario.vehicle
    return 4.0 * v.f_max + v.mass * GRAVITY


def chain_spec(scenario: Scenario) -> ChainSpec:
    """The chain of ``scenario.tether`` (segments >= 1), its armature designed for
    :func:`chain_design_tension`."""
    t = scenario.tether
    n = t.segments
    if n < 1:
        raise ValueError("chain_spec needs tether.segments >= 1")
    l_s = t.length / n
    m_s = t.mass_per_length * l_s
    a = chain_armature(chain_design_tension(scenario), l_s, m_s, scenario.sim.timestep)
    damping = m_s * l_s * l_s / 3.0 / CHAIN_DAMPING_TIME
    return ChainSpec(n, l_s, m_s, a, damping)


def hook_timeconst(scenario: Scenario) -> float:
    """Time constant of the chain's hook connection [s]: ``sim.cable_time_constant``, or for
    an elastic line at least 1/sqrt(k/m), so that a cable snapping taut stops the vehicle
    no faster than the line's own spring would (snap load about v sqrt(k m))."""
    sim, t = scenario.sim, scenario.tether
    tau = max(sim.cable_time_constant, 2.0 * sim.timestep)  # MuJoCo's floor: two steps
    k = t.stiffness
    return tau if k is None else max(tau, math.sqrt(scenario.vehicle.mass / k))


def add_chain(
    world: ET.Element,
    root: ET.Element,
    p_A: FloatArray,
    spec: ChainSpec,
    *,
    solref: str,
    end_site: str = "attachment",
) -> None:
    """Add the chain hanging straight down from ``p_A`` and its hook connection.

    Bodies ``cable_link0`` (jointed to the world at p_A) to ``cable_link{N-1}``, each a
    ball joint at its start and its length along its local x; site ``cable_end`` at the
    far end of the last link (the hook). Equality ``hook`` (a connect, inactive) holds
    ``cable_end`` at ``end_site`` when the cable is engaged. The links do not collide;
    each link's inertia about its axis equals its transverse inertia (see the body).
    """
    l_s, m_s = spec.link_length, spec.link_mass
    i_t = m_s * l_s * l_s / 12.0
    # About its own axis a link gets its transverse inertia: a line's own (m r^2/2, 1e-9
    # of it) would make the twist of the ball joints unresolvable at any usable step.
    i_a = i_t
    parent = world
    for i in range(spec.segments):
        attrs = {"pos": _fmt(p_A), "quat": _fmt((math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0))}
        if i > 0:
            attrs = {"pos": _fmt((l_s, 0.0, 0.0))}
        body = _sub(parent, "body", name=f"cable_link{i}", **attrs)
        _sub(
            body,
            "joint",
            name=f"cable_joint{i}",
            type="ball",
            armature=f"{spec.armature:.12g}",
            damping=f"{spec.joint_damping:.12g}",
        )
        _sub(
            body,
            "inertial",
            pos=_fmt((0.5 * l_s, 0.0, 0.0)),
            mass=f"{m_s:.12g}",
            diaginertia=_fmt((i_a, i_t, i_t)),
        )
        _sub(
            body,
            "geom",
            name=f"cable_link{i}",
            type="capsule",
            fromto=_fmt((0.0, 0.0, 0.0, l_s, 0.0, 0.0)),
            size=f"{CHAIN_RADIUS:.12g}",
            contype="0",
            conaffinity="0",
            mass="0",
            group=str(CABLE_GROUP_HIDDEN),
            rgba=".95 .85 .2 1",
        )
        parent = body
    _sub(parent, "site", name="cable_end", pos=_fmt((l_s, 0.0, 0.0)), size="0.006", group="4")
    equality = root.find("equality")
    if equality is None:
        equality = _sub(root, "equality")
    _sub(
        equality,
        "connect",
        name="hook",
        site1="cable_end",
        site2=end_site,
        active="false",
        solref=solref,
        solimp="0.99 0.999 0.001",
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


@dataclass
class SceneXml:
    """The MJCF document of a scene while the builders of :data:`SCENE_BUILDERS` fill it.

    Attributes
    ----------
    scenario : Scenario
        What the scene is built for (the plant's truth).
    layout : SceneLayout
        Where things are.
    root : Element
        The ``mujoco`` element.
    vehicle : Element or None
        The vehicle's body, once :func:`add_vehicle` has added it (the place for anything
        the vehicle carries).
    """

    scenario: Scenario
    layout: SceneLayout
    root: ET.Element
    vehicle: ET.Element | None = None

    @classmethod
    def start(cls, scenario: Scenario, layout: SceneLayout) -> SceneXml:
        """An empty document for ``scenario``."""
        return cls(scenario, layout, ET.Element("mujoco", model=f"tetherland_{scenario.name}"))

    def section(self, tag: str) -> ET.Element:
        """The top-level element ``tag`` (``worldbody``, ``equality``, ``tendon``,
        ``actuator``, ``sensor``, ...), appended to the document the first time."""
        found = self.root.find(tag)
        return found if found is not None else _sub(self.root, tag)

    @property
    def world(self) -> ET.Element:
        """The ``worldbody``."""
        return self.section("worldbody")

    @property
    def contact_solref(self) -> str:
        """``solref`` of every contact with the environment (ground, surface)."""
        sim = self.scenario.sim
        return _fmt((sim.contact_time_constant, sim.contact_damping_ratio))

    def text(self) -> str:
        """The MJCF text (compile with ``MjModel.from_xml_string``)."""
        ET.indent(self.root)
        return ET.tostring(self.root, encoding="unicode")


def add_options_and_assets(scene: SceneXml) -> None:
    """Compiler and physics options (time step, integrator, solver, gravity), the visual
    settings, textures and materials, and the default classes ``visual`` (drawn only) and
    ``collision`` (the vehicle's massless contact geometry: :data:`VEHICLE_CONTYPE`,
    :data:`VEHICLE_CONAFFINITY`)."""
    sim = scene.scenario.sim
    root = scene.root
    _sub(root, "compiler", angle="radian", autolimits="true")
    option = _sub(
        root,
        "option",
        timestep=f"{sim.timestep:.12g}",
        integrator=sim.integrator,
        cone="elliptic",
        impratio=f"{sim.impratio:.12g}",
        # the bar's hanging line: sparse (the same equations; a contact on a line link
        # has Jacobian entries only on the link's ancestors' dofs, docs/mechanism.md)
        jacobian="sparse" if scene.scenario.mechanism.kind == "bar" else "dense",
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
    _sub(col, "geom", group="3", mass="0", condim="3", contype=str(VEHICLE_CONTYPE),
         conaffinity=str(VEHICLE_CONAFFINITY))  # fmt: skip


def add_ground_and_surface(scene: SceneXml) -> None:
    """The light, the horizontal ground plane (the start pad) and the landing surface: a
    tilted box whose top face is P_S, or a cylinder whose top line lies on P_S (a pipe)."""
    world = scene.world
    surf = scene.layout.geometry.surface
    cfg = scene.scenario.surface
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
    env_contact = {"priority": "1", "condim": "3", "solref": scene.contact_solref}
    _sub(
        world,
        "geom",
        name="ground",
        type="plane",
        size="12 12 0.1",
        pos=_fmt((0, 0, scene.layout.ground_z)),
        material="ground",
        friction="1.0 0.005 0.0001",
        **env_contact,
    )
    friction = f"{cfg.friction:.12g} 0.005 0.0001"
    if surf.kind == "pipe":
        R = cfg.pipe_radius
        shape = {
            "type": "cylinder",
            "size": _fmt((R, cfg.extent)),
            "pos": _fmt(surf.origin - R * surf.z_S),
            "quat": _quat_of_columns(surf.y_S, surf.z_S, surf.x_S),
        }
    else:
        e = cfg.extent
        shape = {
            "type": "box",
            "size": _fmt((e, e, SURFACE_HALF_THICKNESS)),
            "pos": _fmt(surf.origin - SURFACE_HALF_THICKNESS * surf.z_S),
            "quat": _quat_of_columns(surf.x_S, surf.y_S, surf.z_S),
        }
    _sub(world, "geom", name="surface", **shape, material="surface", friction=friction,
         **env_contact)  # fmt: skip


def add_anchor(scene: SceneXml) -> None:
    """The anchoring mechanism at p_A: the site ``anchor`` (the cable's end), a short bar
    along y_A and the capture disk (normal: the approach direction; drawn only)."""
    world = scene.world
    geom = scene.layout.geometry
    p_A = geom.p_A
    _sub(world, "site", name="anchor", pos=_fmt(p_A), size="0.02", rgba=".9 .2 .1 1")
    if scene.scenario.mechanism.kind == "bar":
        add_anchoring_cable(scene)
        return
    if scene.scenario.mechanism.kind == "magnet":
        add_steel_plate(scene)
        return
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
        size=_fmt((scene.scenario.tether.capture_radius, 0.001)),
        pos=_fmt(p_A),
        quat=_quat_z_to(scene.layout.approach_W),
        rgba=".9 .6 .1 .25",
        group="2",
    )


LINE_CONTYPE, LINE_CONAFFINITY = 2, 0
"""Contact bits of the hanging line and the hook: they touch the environment (whose
conaffinity gets bit 2, :func:`add_hanging_line`), never the vehicle or each other."""
ENV_CONAFFINITY = 3
"""Conaffinity of the ground, the surface and the anchoring mechanism with the bar."""


def add_anchoring_cable(scene: SceneXml) -> None:
    """The bar mechanism's anchoring cable: the capsule ``anchor_bar`` of length
    ``mechanism.bar_length`` along y_A with its axis through p_A, and the posts ``post0``
    and ``post1`` from its ends down to the surface along -z_S (collision geoms of the
    world, ``mechanism.bar_friction``; contact time constant two physics steps)."""
    m = scene.scenario.mechanism
    geo = scene.layout.geometry
    p_A, y_A, z_S = geo.p_A, geo.R_WA[:, 1], geo.surface.R_WS[:, 2]
    half = 0.5 * m.bar_length * y_A
    sim = scene.scenario.sim
    env = {
        "priority": "1",
        "condim": "3",
        # as stiff as the step allows (MuJoCo's floor: two steps): a 1.5 mm line hitting a
        # post at 0.5 m/s sinks about v tau into it
        "solref": _fmt((2.0 * sim.timestep, sim.contact_damping_ratio)),
        "friction": f"{m.bar_friction:.12g} 0.005 0.0001",
        "conaffinity": str(ENV_CONAFFINITY),
        "rgba": ".9 .2 .1 1",
        "group": "1",
    }
    _sub(scene.world, "geom", name="anchor_bar", type="capsule", size=f"{m.bar_radius:.12g}",
         fromto=_fmt(np.concatenate((p_A - half, p_A + half))), **env)  # fmt: skip
    post_r = 1.5 * m.bar_radius
    for i, sign in enumerate((-1.0, 1.0)):
        top = p_A + sign * half
        foot = top - m.standoff * z_S
        _sub(scene.world, "geom", name=f"post{i}", type="capsule", size=f"{post_r:.12g}",
             fromto=_fmt(np.concatenate((top, foot))), **env)  # fmt: skip


MAGNET_SHELL_BIT = 16
"""Contact bit of the magnet's shell: the ground and the surface get it in their
conaffinity (:func:`add_magnet`); the plate does not."""
EPM_RANGE = 0.001
"""Gap between the magnet's face and the plate at which the EPM's pull has fallen to
zero, linearly from its full force on contact (an EPM loses most of its force within a
millimetre of air; :mod:`tetherland.sim.epm`) [m]."""
BOOM_MASS = 0.01
"""Mass of the folding boom (a 4 mm carbon tube and its hinge) [kg]."""
SOCKET_MASS = 0.001
"""Mass of the clip's socket on the boom's tip [kg]."""
GIMBAL_STIFFNESS = 0.2
"""Centring spring of the socket's gimbal [N m/rad]: the clipped magnet's weight, 7.5 mm
ahead of it, tilts it 0.01 rad; the plate's push on one edge of a pressed face turns it
flat. At 0.05 N m/rad the magnet pressed on overhang93's plate turned so far that a
corner went 6 mm into the plate."""
GIMBAL_DAMPING = 1e-4
"""Damping of the socket's gimbal [N m s/rad]."""
GIMBAL_ARMATURE = 1e-6
"""Armature of the socket's gimbal (alone after the clip let go, the 1 g socket on a
0.2 N m/rad spring swings at w dt = 0.45 at 1 ms) [kg m^2]."""


def magnet_contact(scenario: Scenario) -> dict[str, str]:
    """``solref``/``solimp`` of the magnet's face on the plate: time constant two physics
    steps (MuJoCo's floor), impedance 0.999 throughout. Held by a force f, the face sinks
    r = f (1 - d) A tau^2 (d the impedance, A the inverse inertia at the contact, tau the
    time constant, critical damping): 0.02 mm for 150 N on a 30 g face lying flat; on
    one edge (A about 120/kg: the magnet turns about it) 0.07 mm, where at d = 0.99 a
    rocking magnet's edge went 3.6 mm into the plate."""
    tau = 2.0 * scenario.sim.timestep
    return {"solref": _fmt((tau, 1.0)), "solimp": "0.999 0.999 0.001"}


def add_steel_plate(scene: SceneXml) -> None:
    """The magnet mechanism's anchor: the steel plate ``plate``, a square box of
    ``mechanism.plate_size`` and ``plate_thickness`` on the surface under p_A (its top face
    ``magnet_thickness`` below p_A, the cable's eye on the held magnet). It collides with
    the vehicle as the surface does; the magnet's face touches only it (the explicit
    contact pair of :func:`add_magnet`)."""
    m = scene.scenario.mechanism
    geo = scene.layout.geometry
    R_WS = geo.surface.R_WS
    centre = geo.p_A - (m.magnet_thickness + 0.5 * m.plate_thickness) * R_WS[:, 2]
    half = 0.5 * m.plate_size
    _sub(scene.world, "geom", name="plate", type="box",
         size=_fmt((half, half, 0.5 * m.plate_thickness)), pos=_fmt(centre),
         quat=_quat_of_columns(R_WS[:, 0], R_WS[:, 1], R_WS[:, 2]), priority="1", condim="3",
         solref=scene.contact_solref, friction=f"{m.magnet_friction:.12g} 0.005 0.0001",
         rgba=".55 .58 .62 1", group="1")  # fmt: skip


def add_boom(scene: SceneXml) -> None:
    """The magnet mechanism's folding boom on the vehicle
    (:class:`tetherland.models.hook.MagnetBoom`): the body ``boom`` hinged at the cable
    attachment point about n x w (joint ``boom_hinge``, the spring ``boom_stiffness``
    holding it on its stop 0 with ``boom_preload``, ``boom_damping``, folding up to
    ``boom_fold_deg``), a capsule to
    the site ``boom_tip`` at the cable's eye of the clipped magnet (the vehicle's contact
    class: it touches the environment, not the vehicle)."""
    from tetherland.models.hook import magnet_boom

    sc = scene.scenario
    m = sc.mechanism
    boom = magnet_boom(sc)
    assert scene.vehicle is not None
    body = _sub(scene.vehicle, "body", name="boom", pos=_fmt(boom.hinge_B))
    _sub(body, "joint", name="boom_hinge", type="hinge", axis=_fmt(boom.axis_B),
         range=_fmt((0.0, math.radians(m.boom_fold_deg))), limited="true",
         stiffness=f"{m.boom_stiffness:.12g}", damping=f"{m.boom_damping:.12g}",
         springref=f"{-m.boom_preload / m.boom_stiffness:.12g}")  # fmt: skip
    tip = boom.offset_B
    L = boom.length
    i_t = BOOM_MASS * L * L / 12.0
    _sub(body, "inertial", pos=_fmt(0.5 * tip), mass=f"{BOOM_MASS:.12g}",
         diaginertia=_fmt((i_t, i_t, i_t)))  # fmt: skip
    _sub(body, "geom", name="boom", class_="collision", type="capsule",
         size=f"{BOOM_RADIUS:.12g}", fromto=_fmt(np.concatenate((np.zeros(3), tip))),
         material="frame", group="1")  # fmt: skip
    # the socket the magnet is clipped into: on a spring-centred gimbal at the tip (a ball
    # joint), so a magnet pressed on the plate by a folded boom turns flat on it
    socket = _sub(body, "body", name="socket", pos=_fmt(tip), quat=_quat_z_to(boom.n_B))
    _sub(socket, "joint", name="gimbal", type="ball", stiffness=f"{GIMBAL_STIFFNESS:.12g}",
         damping=f"{GIMBAL_DAMPING:.12g}", armature=f"{GIMBAL_ARMATURE:.12g}")
    _sub(socket, "inertial", pos="0 0 0", mass=f"{SOCKET_MASS:.12g}",
         diaginertia=_fmt((1e-8, 1e-8, 1e-8)))  # fmt: skip
    _sub(socket, "site", name="boom_tip", pos="0 0 0", size="0.005", group="4")


def add_magnet(scene: SceneXml) -> None:
    """The magnet: the free body ``magnet`` (a box of half side ``magnet_radius`` and
    ``magnet_thickness`` along its local z, the approach direction when clipped; mass
    ``magnet_mass``) placed on the boom's tip at qpos0, the weld ``clip`` holding it there
    (the plant lets it go when pulled harder than ``clip_force``), the site ``magnet_eye``
    on its back (the cable's end, the hook point) and ``magnet_face``.

    Two geoms of one shape: ``magnet_face`` on the body ``magnet`` touches only the plate
    (an explicit contact pair, stiff: :func:`magnet_contact`), ``magnet_shell`` on the
    jointless child body ``magnet_shell`` touches the ground and the surface (contact bit
    :data:`MAGNET_SHELL_BIT`), not the plate or the vehicle. The EPM's pull is the plant's
    force on the face (:mod:`tetherland.sim.epm`): the plate's, never the wall's."""
    from tetherland.models.hook import magnet_boom

    sc = scene.scenario
    m = sc.mechanism
    boom = magnet_boom(sc)
    start_com = scene.layout.start_position + np.array([0.0, 0.0, sc.vehicle.h_R])
    # qpos0: the vehicle at its XML pose (F_B = F_W), the magnet on the boom's tip
    centre = start_com + boom.eye_B + 0.5 * m.magnet_thickness * boom.n_B
    body = _sub(scene.world, "body", name="magnet", pos=_fmt(centre), quat=_quat_z_to(boom.n_B))
    _sub(body, "freejoint", name="magnet_free")
    a, h = m.magnet_radius, 0.5 * m.magnet_thickness
    mass = m.magnet_mass
    _sub(body, "inertial", pos="0 0 0", mass=f"{mass:.12g}",
         diaginertia=_fmt((mass * (a * a + h * h) / 3.0, mass * (a * a + h * h) / 3.0,
                           2.0 * mass * a * a / 3.0)))  # fmt: skip
    size = _fmt((a, a, h))
    friction = f"{m.magnet_friction:.12g} 0.005 0.0001"
    _sub(body, "geom", name="magnet_face", type="box", size=size, contype="0", conaffinity="0",
         mass="0", rgba=".3 .3 .35 1", group="1")  # fmt: skip
    shell = _sub(body, "body", name="magnet_shell")
    # (priority over the ground's and the surface's: its contacts as stiff as the plate's,
    # a released magnet swinging into the rock sank 2 mm into it at their 5 ms)
    _sub(shell, "geom", name="magnet_shell", type="box", size=size,
         contype=str(MAGNET_SHELL_BIT), conaffinity="0", condim="3", mass="0", priority="2",
         friction=friction, rgba=".3 .3 .35 0", group="3", **magnet_contact(sc))  # fmt: skip
    _sub(body, "site", name="magnet_eye", pos=_fmt((0.0, 0.0, -h)), size="0.005", group="4")
    _sub(body, "site", name="magnet_face", pos=_fmt((0.0, 0.0, h)), size="0.005", group="4")
    contact = scene.section("contact")
    # the face touches the plate (no margin: MuJoCo 4 finds a pair's contacts within
    # margin + gap and makes them push below the margin); the EPM's pull is not MuJoCo's
    # adhesion on these contacts but the plant's force on the face (tetherland.sim.epm),
    # which falls with each part's gap and acts through the face only
    _sub(contact, "pair", name="magnet_plate", geom1="magnet_face", geom2="plate", condim="3",
         friction=f"{m.magnet_friction:.12g} {m.magnet_friction:.12g} 0.005 0.0001 0.0001",
         **magnet_contact(sc))  # fmt: skip
    equality = scene.section("equality")
    _sub(equality, "weld", name="clip", body1="magnet", body2="socket", active="true",
         solref=_fmt((2.0 * sc.sim.timestep, 1.0)), solimp="0.99 0.999 0.001")
    for name in ("ground", "surface"):
        g = scene.world.find(f"geom[@name='{name}']")
        if g is not None:
            g.set("conaffinity", str(1 | MAGNET_SHELL_BIT))


@dataclass(frozen=True)
class LineSpec:
    """The bar mechanism's hanging line (docs/mechanism.md).

    Attributes
    ----------
    segments : int
        Number of links N.
    link_length : float
        Line length over N [m].
    link_mass : float
        line density times the link length [kg].
    radius : float
        Capsule radius of the links [m].
    joint_damping : float
        Viscous damping of each ball joint [N m s/rad].
    """

    segments: int
    link_length: float
    link_mass: float
    radius: float
    joint_damping: float

    @property
    def line_length(self) -> float:
        """Length of the line [m]."""
        return self.segments * self.link_length


def line_spec(scenario: Scenario) -> LineSpec:
    """The hanging line of ``scenario.mechanism`` (the bar), its length from
    :func:`tetherland.models.hook.bar_line_length`."""
    from tetherland.models.hook import bar_line_length

    m = scenario.mechanism
    length = bar_line_length(scenario.tether.length, m)
    n = m.line_segments
    l_s = length / n
    m_s = m.line_density * l_s
    return LineSpec(n, l_s, m_s, m.line_radius, m_s * l_s * l_s / 3.0 / CHAIN_DAMPING_TIME)


def add_hanging_line(scene: SceneXml) -> None:
    """The bar mechanism's hanging line and hook, on the vehicle's body.

    Bodies ``line_link0`` (ball-jointed to the vehicle at the attachment point) to
    ``line_link{N-1}``, each a capsule along its local x, then the body ``hook``
    (ball-jointed at its eye): the shank along its local x, three arms at 120 deg at the
    crown (falling ``mechanism.arm_fall`` to their ends) and a tip pointing back up from
    each arm's end, capsules of
    ``mechanism.hook_radius``, mass ``mechanism.hook_mass`` spread over them by length.
    At qpos0 the line hangs straight down from the level vehicle. Site ``line_root`` at
    the first joint carries the force sensor ``line_force`` (the line's pull on the
    vehicle); site ``hook_eye`` and ``hook_crown`` mark the hook. The line and the hook
    touch the environment only (:data:`LINE_CONTYPE`).
    """
    scenario = scene.scenario
    m = scenario.mechanism
    spec = line_spec(scenario)
    assert scene.vehicle is not None
    l_s, m_s = spec.link_length, spec.link_mass
    i_t = m_s * l_s * l_s / 12.0
    col = {"contype": str(LINE_CONTYPE), "conaffinity": str(LINE_CONAFFINITY), "condim": "3",
           "group": "1", "rgba": ".95 .85 .2 1"}  # fmt: skip
    parent = scene.vehicle
    attrs = {"pos": _fmt(scenario.vehicle.cable_attachment),
             "quat": _fmt((math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0))}  # fmt: skip
    for i in range(spec.segments):
        body = _sub(parent, "body", name=f"line_link{i}", **attrs)
        _sub(body, "joint", name=f"line_joint{i}", type="ball",
             damping=f"{spec.joint_damping:.12g}")  # fmt: skip
        _sub(body, "inertial", pos=_fmt((0.5 * l_s, 0.0, 0.0)), mass=f"{m_s:.12g}",
             diaginertia=_fmt((i_t, i_t, i_t)))  # fmt: skip
        _sub(body, "geom", name=f"line_link{i}", type="capsule",
             fromto=_fmt((0.0, 0.0, 0.0, l_s, 0.0, 0.0)), size=f"{spec.radius:.12g}",
             mass="0", **col)  # fmt: skip
        if i == 0:
            _sub(body, "site", name="line_root", pos="0 0 0", size="0.004", group="4")
        parent = body
        attrs = {"pos": _fmt((l_s, 0.0, 0.0))}
    hook = _sub(parent, "body", name="hook", **attrs)
    # armature: the hook's own inertia about its eye again (m s^2), so that its swing about
    # the eye stays resolvable against the stiff contacts of the mechanism
    _sub(hook, "joint", name="hook_joint", type="ball", damping=f"{spec.joint_damping:.12g}",
         armature=f"{m.hook_mass * m.hook_shank**2:.12g}")  # fmt: skip
    s, r, tip = m.hook_shank, m.hook_reach, m.hook_tip_length
    lean = math.radians(m.hook_tip_angle_deg)
    fall = m.arm_fall  # each arm falls from the crown to its tip (0: flat arms)
    pieces = [((0.0, 0.0, 0.0), (s, 0.0, 0.0))]
    for k in range(3):
        a = 2.0 * math.pi * k / 3.0
        c, si = math.cos(a), math.sin(a)
        end = (s + fall, r * c, r * si)
        out = r + tip * math.sin(lean)
        pieces.append(((s, 0.0, 0.0), end))
        pieces.append((end, (s + fall - tip * math.cos(lean), out * c, out * si)))
    total = sum(math.dist(a, b) for a, b in pieces)
    for j, (a, b) in enumerate(pieces):
        _sub(hook, "geom", name=f"hook{j}", type="capsule", fromto=_fmt((*a, *b)),
             size=f"{m.hook_radius:.12g}",
             mass=f"{m.hook_mass * math.dist(a, b) / total:.12g}",
             **{**col, "rgba": ".7 .7 .75 1"})  # fmt: skip
    _sub(hook, "site", name="hook_eye", pos="0 0 0", size="0.004", group="4")
    _sub(hook, "site", name="hook_crown", pos=_fmt((s, 0.0, 0.0)), size="0.004", group="4")
    # the environment touches the line (bit 2 of its conaffinity)
    for name in ("ground", "surface"):
        g = scene.world.find(f"geom[@name='{name}']")
        if g is not None:
            g.set("conaffinity", str(ENV_CONAFFINITY))


def add_vehicle(scene: SceneXml) -> None:
    """The vehicle at the start pad (the plant sets the initial state): one rigid body with
    a free joint, mass and principal inertia, the IMU and cable attachment sites, the hub,
    the cable's mount (a small sphere on the attachment point), the landers and legs
    (:func:`add_landers`) and the rotors (:func:`add_rotors`), every shape from
    :class:`~tetherland.models.airframe.Airframe`."""
    v = scene.scenario.vehicle
    frame = Airframe.of(v)
    start_com = scene.layout.start_position + np.array([0.0, 0.0, v.h_R])
    body = _sub(scene.world, "body", name="vehicle", pos=_fmt(start_com))
    scene.vehicle = body
    _sub(body, "freejoint", name="vehicle_free")
    mech = scene.scenario.mechanism
    com = np.zeros(3)
    carried = 0.0
    if mech.kind == "magnet":
        # vehicle.mass is the whole flying robot, its boom and magnet included; the frame
        # is balanced (a counterweight) for the boom and MAGNET_BALANCE of the magnet's
        # moment about the centre of mass
        from tetherland.models.hook import MAGNET_BALANCE, magnet_boom, magnet_centre_B

        boom = magnet_boom(scene.scenario)
        carried = BOOM_MASS + mech.magnet_mass
        magnet_B = magnet_centre_B(scene.scenario)
        moment = (BOOM_MASS * 0.5 * (boom.hinge_B + boom.eye_B)
                  + MAGNET_BALANCE * mech.magnet_mass * magnet_B)  # fmt: skip
        com = -moment / (v.mass - carried)
        # and vehicle.inertia is the whole robot's: the frame's is less the boom's and the
        # clipped magnet's (points at their centres) and its own offset's
        inertia = np.diag(np.asarray(v.inertia, dtype=float))
        for mass, r in ((BOOM_MASS, 0.5 * (boom.hinge_B + boom.eye_B)),
                        (mech.magnet_mass, magnet_B),
                        (v.mass - carried, com)):  # fmt: skip
            inertia -= mass * (float(r @ r) * np.eye(3) - np.outer(r, r))
        # (the principal moments only: the frame alone cannot also cancel the boom's
        # product of inertia and stay a physical body; the whole keeps J_xz of 2e-3)
        _sub(body, "inertial", pos=_fmt(com), mass=f"{v.mass - carried:.12g}",
             diaginertia=_fmt(np.diag(inertia)))  # fmt: skip
    else:
        _sub(body, "inertial", pos=_fmt(com), mass=f"{v.mass - carried:.12g}",
             diaginertia=_fmt(v.inertia))  # fmt: skip
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
        size=_fmt(frame.hub_half_size),
        material="frame",
        group="1",
    )
    _sub(
        body,
        "geom",
        name="mount",
        class_="collision",
        type="sphere",
        size=f"{frame.mount_radius:.12g}",
        pos=_fmt(frame.mount_B),
        rgba=".9 .2 .1 1",
        group="1",
    )
    add_landers(scene, body)
    add_rotors(scene, body)
    if scene.scenario.mechanism.kind == "magnet":
        add_boom(scene)


def add_landers(scene: SceneXml, body: ET.Element) -> None:
    """The four lander spheres ``lander{i}`` (lowest points on the landers plane,
    :func:`tetherland.models.airframe.lander_centres_B`) and the touch zones
    ``lander{i}_zone`` of the touch sensors in the massless child body ``landers`` (welded
    to the vehicle: the contact sensors tell the landers' contacts from the other parts'
    by body), and their legs ``leg{i}`` (capsules from under the hub to the lander's
    centre) on the vehicle; all collide."""
    v = scene.scenario.vehicle
    frame = Airframe.of(v)
    r = frame.lander_radius
    feet = _sub(body, "body", name="landers")
    for i, tip in enumerate(frame.lander_centres_B):
        _sub(
            feet,
            "geom",
            name=f"lander{i}",
            class_="collision",
            type="sphere",
            size=f"{r:.12g}",
            pos=_fmt(tip),
            rgba=".1 .1 .1 1",
            group="1",
        )
        leg = frame.capsule(f"leg{i}")
        _sub(
            body,
            "geom",
            name=leg.name,
            class_="collision",
            type="capsule",
            size=f"{leg.radius:.12g}",
            fromto=_fmt(np.concatenate((leg.a_B, leg.b_B))),
            material="frame",
            group="1",
        )
        _sub(
            feet,
            "site",
            name=f"lander{i}_zone",
            type="sphere",
            size=f"{1.5 * r:.12g}",
            pos=_fmt(tip),
            group="4",
        )


def add_rotors(scene: SceneXml, body: ET.Element) -> None:
    """Per rotor: the site ``rotor{i}`` its thrust acts at, the arm ``arm{i}`` (a capsule
    from the centre of mass to the rotor) and the rotor guard ``prop{i}``, both colliding."""
    layout = scene.layout
    frame = Airframe.of(scene.scenario.vehicle)
    for i, r_i in enumerate(layout.rotors.positions_B):
        _sub(body, "site", name=f"rotor{i}", pos=_fmt(r_i), size="0.01", group="4")
        arm = frame.capsule(f"arm{i}")
        _sub(
            body,
            "geom",
            name=arm.name,
            class_="collision",
            type="capsule",
            size=f"{arm.radius:.12g}",
            fromto=_fmt(np.concatenate((arm.a_B, arm.b_B))),
            material="frame",
            group="1",
        )
        _sub(
            body,
            "geom",
            name=f"prop{i}",
            class_="collision",
            type="cylinder",
            size=_fmt((frame.guard_radius, frame.guard_half_thickness)),
            pos=_fmt(frame.guard_centres_B[i]),
            material="prop",
            group="1",
        )


def add_cable(scene: SceneXml) -> None:
    """The cable by ``tether.cable_model``: the chain's links and hook connection
    (:func:`add_chain`) and the spatial tendon ``cable`` from the anchor to the attachment
    (limited to [0, l] for the ideal cable, hidden under the chain's links)."""
    scenario = scene.scenario
    sim, tether = scenario.sim, scenario.tether
    if scenario.mechanism.kind == "bar":
        add_hanging_line(scene)
        # the tendon only measures the anchor-attachment distance
        cable = _sub(scene.section("tendon"), "spatial", name="cable", width="0.004",
                     rgba=".95 .85 .2 1", group=str(CABLE_GROUP_HIDDEN))  # fmt: skip
        _sub(cable, "site", site="anchor")
        _sub(cable, "site", site="attachment")
        return
    if scenario.mechanism.kind == "magnet":
        add_magnet(scene)
        # the elastic cable from the magnet's eye to the attachment (always tied)
        cable = _sub(scene.section("tendon"), "spatial", name="cable", width="0.002",
                     rgba=".95 .85 .2 1")  # fmt: skip
        _sub(cable, "site", site="magnet_eye")
        _sub(cable, "site", site="attachment")
        return
    cable_model = tether.cable_model
    if cable_model == CableModel.CHAIN:
        add_chain(
            scene.world,
            scene.root,
            scene.layout.geometry.p_A,
            chain_spec(scenario),
            solref=_fmt((hook_timeconst(scenario), sim.cable_damping_ratio)),
        )
    cable_attrs = {"width": "0.004", "rgba": ".95 .85 .2 1"}
    if cable_model == CableModel.IDEAL:
        cable_attrs.update(
            limited="true",
            range=_fmt((0.0, tether.length)),
            solreflimit=_fmt((sim.cable_time_constant, sim.cable_damping_ratio)),
        )
    elif cable_model == CableModel.CHAIN:
        cable_attrs["group"] = str(CABLE_GROUP_HIDDEN)  # the links are drawn instead
    cable = _sub(scene.section("tendon"), "spatial", name="cable", **cable_attrs)
    _sub(cable, "site", site="anchor")
    _sub(cable, "site", site="attachment")


def add_actuators(scene: SceneXml) -> None:
    """The rotor thrusts ``rotor{i}`` and, for the elastic cable, its tension ``cable``."""
    act = scene.section("actuator")
    v = scene.scenario.vehicle
    rotors = scene.layout.rotors
    c_tau = rotors.drag_coefficient
    for i, sigma in enumerate(rotors.spins):
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
    bar = scene.scenario.mechanism.kind == "bar"
    if scene.scenario.tether.cable_model == CableModel.ELASTIC and not bar:
        # ctrl = cable tension f_L >= 0 [N], set by the plant each step; gear -1 shortens.
        _sub(act, "general", name="cable", tendon="cable", gear="-1", ctrllimited="false")


def add_sensors(scene: SceneXml) -> None:
    """The sensors of :data:`SENSOR_LAYOUT`, in that order."""
    sensor = scene.section("sensor")
    _sub(sensor, "accelerometer", name="accelerometer", site="imu")
    _sub(sensor, "gyro", name="gyro", site="imu")
    cable_model = scene.scenario.tether.cable_model
    if scene.scenario.mechanism.kind == "bar":  # written by the plant: |line_force|
        _sub(sensor, "user", name="cable_force", dim="1", needstage="acc", datatype="real")
    elif cable_model == CableModel.IDEAL:
        _sub(sensor, "tendonlimitfrc", name="cable_force", tendon="cable")
    elif cable_model == CableModel.ELASTIC:
        _sub(sensor, "actuatorfrc", name="cable_force", actuator="cable")
    else:  # written by the plant from the hook connection's constraint force
        _sub(sensor, "user", name="cable_force", dim="1", needstage="acc", datatype="real")
    _sub(sensor, "tendonpos", name="cable_length", tendon="cable")
    for i in range(len(LANDER_CORNERS)):
        _sub(sensor, "touch", name=f"lander{i}_touch", site=f"lander{i}_zone")
    for partner in CONTACT_PARTNERS:
        for i in range(4):
            _sub(sensor, "contact", name=f"lander{i}_{partner}", geom1=f"lander{i}",
                 geom2=partner, num="1", data="force", reduce="none")  # fmt: skip
    # how many contacts the body ``vehicle`` (every part but the landers) has, and the
    # deepest contact of the vehicle's subtree (0 when none)
    _sub(sensor, "contact", name="frame_contacts", body1="vehicle", num="1", data="found",
         reduce="none")  # fmt: skip
    _sub(sensor, "contact", name="vehicle_depth", subtree1="vehicle", num="1", data="dist",
         reduce="mindist")  # fmt: skip


def add_mechanism_sensors(scene: SceneXml) -> None:
    """After :data:`SENSOR_LAYOUT`, for the bar mechanism: ``line_force`` (force sensor at
    ``line_root``: the line's pull on the vehicle, 3) and ``hook_bar`` (contacts of the line
    and the hook with the anchoring cable: number found, net force in F_W, 4); for the
    magnet: ``magnet_plate`` (contacts of the magnet's face with the plate: number found,
    net force in F_W, 4), the plant's truth of the catch."""
    if scene.scenario.mechanism.kind == "magnet":
        _sub(scene.section("sensor"), "contact", name="magnet_plate", geom1="magnet_face",
             geom2="plate", data="found force", reduce="netforce")  # fmt: skip
        return
    if scene.scenario.mechanism.kind != "bar":
        return
    sensor = scene.section("sensor")
    _sub(sensor, "force", name="line_force", site="line_root")
    _sub(sensor, "contact", name="hook_bar", subtree1="line_link0", geom2="anchor_bar",
         data="found force", reduce="netforce")  # fmt: skip


MECHANISM_SENSORS: tuple[tuple[str, int], ...] = (("line_force", 3), ("hook_bar", 4))
"""The bar mechanism's sensors after :data:`SENSOR_LAYOUT`: (name, dimension)."""


SCENE_BUILDERS: tuple[Callable[[SceneXml], None], ...] = (
    add_options_and_assets,
    add_ground_and_surface,
    add_anchor,
    add_vehicle,
    add_cable,
    add_actuators,
    add_sensors,
    add_mechanism_sensors,
)
"""The scene, builder by builder, in document order. A new part of the scene (say a
mechanism at the anchor or on the vehicle) is one more builder here: it finds the world
(:attr:`SceneXml.world`), the vehicle's body (:attr:`SceneXml.vehicle`) and the top-level
sections (:meth:`SceneXml.section`) on the :class:`SceneXml` it is given."""


def build_mjcf(scenario: Scenario, layout: SceneLayout | None = None) -> str:
    """MJCF text of the scene for ``scenario`` (compile with ``MjModel.from_xml_string``):
    :data:`SCENE_BUILDERS` one after the other.

    The cable tendon is created limited (engaged); the plant disengages it at reset, as
    the hook model requires.
    """
    scene = SceneXml.start(scenario, SceneLayout.from_scenario(scenario) if layout is None
                           else layout)  # fmt: skip
    for build in SCENE_BUILDERS:
        build(scene)
    return scene.text()
