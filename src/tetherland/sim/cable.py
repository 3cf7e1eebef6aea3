"""The cable in the plant: ideal, massless elastic, or a massive chain (docs/tether.md).

Each model implements :class:`Cable`: it advances MuJoCo by one step with its force
included (:meth:`Cable.advance`), recomputes the state without stepping
(:meth:`Cable.forward`), and engages or releases (:meth:`Cable.set_engaged`). Every model
leaves the tension at the vehicle's attachment point in the ``cable_force`` sensor slot,
evaluated at the start of the last step like the other sensors.

- :class:`IdealCable`: the limited tendon of the chapter, a unilateral constraint at l.
- :class:`ElasticCable`: massless, f_L = max(0, k x + c x') while taut (x = L - l > 0),
  0 while slack, with k = EA/l and c = 2 zeta sqrt(k m). The force is computed from the
  tendon length and velocity between ``mj_step1`` and ``mj_step2`` and applied by a
  tendon actuator: exact at the step's start state, like every force of the
  semi-implicit Euler step (the scenario checks sqrt(k/m) dt for stability).
- :class:`ChainCable`: ``segments`` rigid links with ball joints from the anchor, the
  last link's end held at the attachment point by a connect equality when engaged. The
  elongation of the line is quasi-static (its axial modes are kHz): a Kelvin-Voigt
  element k s + c s' = f_L, integrated implicitly with the tension of the last step,
  lengthens the last link. Disengaged, the chain is parked hanging from the anchor,
  inactive and hidden; engaging lays it at rest from the anchor to the attachment point,
  in its hanging equilibrium.
"""

from __future__ import annotations

import functools
import math
from typing import Protocol, runtime_checkable

import mujoco
import numpy as np

from tetherland.config import CableModel, Scenario
from tetherland.geometry import FloatArray
from tetherland.models.hook import bar_near_distance
from tetherland.rotations import quat_to_rotmat, rotmat_to_quat
from tetherland.sim.epm import cell_offsets, epm_pull_into
from tetherland.sim.line_drag import line_drag_into, link_drag_factor
from tetherland.sim.mjcf import (
    CABLE_GROUP_HIDDEN,
    CABLE_GROUP_VISIBLE,
    EPM_RANGE,
    SENSOR_SLICES,
    chain_armature,
    chain_spec,
    hook_timeconst,
)

_Z = np.array([0.0, 0.0, 1.0])
ARMATURE_DECAY = 0.99
"""Per-step decay of the tension the chain's armature is held for (0.1 s at 1 ms) [-]."""


def set_cable_visible(model: mujoco.MjModel, visible: bool) -> None:
    """Draw the cable (engaged) or hide it (disengaged); physics unaffected.

    Hidden means moved to group 5, which MuJoCo's renderers do not draw by default (a
    transparent element would still cast a shadow). The ideal and elastic cables are the
    tendon ``cable``; the chain is its link geoms (its tendon stays hidden).
    """
    group = CABLE_GROUP_VISIBLE if visible else CABLE_GROUP_HIDDEN
    first = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "cable_link0")
    if first < 0:
        cable = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, "cable")
        model.tendon_group[cable] = group
        return
    i = 0
    while (g := mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"cable_link{i}")) >= 0:
        model.geom_group[g] = group
        i += 1


@runtime_checkable
class Cable(Protocol):
    """The cable role of the plant (one implementation per :class:`CableModel`)."""

    kind: CableModel

    @property
    def engaged(self) -> bool: ...

    def advance(self) -> None:
        """One physics step (``mj_step``) with the cable force included."""
        ...

    def forward(self) -> None:
        """Recompute kinematics, forces and sensors at the current state (no step)."""
        ...

    def set_engaged(self, engaged: bool) -> None:
        """Attach the cable to the anchor (True) or release it (False), now."""
        ...

    def follow_vehicle(self) -> None:
        """The vehicle was moved by hand: keep the engaged cable attached to it."""
        ...


class IdealCable:
    """Inextensible massless cable: the tendon ``cable`` limited to [0, l]."""

    kind = CableModel.IDEAL

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        self._model = model
        self._tendon = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, "cable")
        self._engaged = False
        self.advance = functools.partial(mujoco.mj_step, model, data)
        self.forward = functools.partial(mujoco.mj_forward, model, data)

    @property
    def engaged(self) -> bool:
        return self._engaged

    def set_engaged(self, engaged: bool) -> None:
        # Disengaged, the limit is off: no constraint row, zero force.
        self._engaged = bool(engaged)
        self._model.tendon_limited[self._tendon] = 1 if engaged else 0
        set_cable_visible(self._model, engaged)

    def follow_vehicle(self) -> None:
        return None


class ElasticCable:
    """Massless elastic cable: a unilateral spring-damper on the tendon ``cable``.

    Parameters
    ----------
    model, data
        The plant's MuJoCo model and data (built with ``cable_model = elastic``).
    stiffness : float
        k = EA/l [N/m].
    damping : float
        c [N s/m].
    length : float
        Unstretched length l [m].
    """

    kind = CableModel.ELASTIC

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        stiffness: float,
        damping: float,
        length: float,
    ) -> None:
        self._model, self._data = model, data
        tendon = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, "cable")
        act = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_ACTUATOR, "cable")
        if tendon < 0 or act < 0:
            raise ValueError("the model has no elastic cable (tendon and actuator 'cable')")
        self.k, self.c, self.length = float(stiffness), float(damping), float(length)
        self._tendon = tendon
        self._len = data.ten_length[tendon : tendon + 1]
        self._vel = data.ten_velocity[tendon : tendon + 1]
        self._ctrl = data.ctrl[act : act + 1]
        self._engaged = False
        self.state = np.array([0.0, self.k, self.c, self.length])
        """Engaged (1/0), k, c and l in one array, as the plant's compiled step reads them
        (:data:`~tetherland.sim.step_kernel.C_ENGAGED` ...)."""

    @property
    def engaged(self) -> bool:
        return self._engaged

    def force(self, length: float, rate: float) -> float:
        """f_L = max(0, k x + c x') for x = length - l > 0, else 0 [N] (length [m],
        rate [m/s])."""
        x = length - self.length
        if x <= 0.0:
            return 0.0
        f = self.k * x + self.c * rate
        return f if f > 0.0 else 0.0

    def advance(self) -> None:
        m, d = self._model, self._data
        mujoco.mj_step1(m, d)  # positions, velocities, tendon length and rate at t_k
        if self._engaged:
            x = self._len[0] - self.length
            if x > 0.0:
                f = self.k * x + self.c * self._vel[0]
                self._ctrl[0] = f if f > 0.0 else 0.0
            else:
                self._ctrl[0] = 0.0
        self._actuate()
        mujoco.mj_step2(m, d)  # actuation, acceleration, constraints, integration

    def _actuate(self) -> None:
        """Apply the mechanism's own forces from the positions at t_k (none here)."""
        return None

    def forward(self) -> None:
        m, d = self._model, self._data
        mujoco.mj_fwdPosition(m, d)
        mujoco.mj_fwdVelocity(m, d)
        self._ctrl[0] = self.force(self._len[0], self._vel[0]) if self._engaged else 0.0
        self._actuate()
        mujoco.mj_forward(m, d)

    def set_engaged(self, engaged: bool) -> None:
        self._engaged = bool(engaged)
        self.state[0] = 1.0 if engaged else 0.0
        if not engaged:
            self._ctrl[0] = 0.0
        set_cable_visible(self._model, engaged)

    def follow_vehicle(self) -> None:
        return None


class ChainCable:
    """Massive cable: a chain of rigid links from the anchor, the hook at its end.

    Parameters
    ----------
    model, data
        The plant's MuJoCo model and data (built with ``cable_model = chain``); the model's
        chain entries are adjusted (see below).
    scenario : Scenario
        Tether, vehicle and time step.
    p_A : (3,) array
        Anchor [m].
    side_W : (3,) array
        Horizontal direction in which a slack chain is laid out when the attachment point
        is straight above or below the anchor (unit) [-].

    Notes
    -----
    MuJoCo softens an equality constraint by an impedance built from the bodies' mean
    inverse inertia at qpos0 (``body_invweight0``). For grams-light links this makes the
    hook connection centimetres soft; the links are given the vehicle's values instead,
    so the connection is as stiff as the ideal cable's limit (the taut connection's true
    inverse inertia is the vehicle's: the straight chain cannot move along itself).
    """

    kind = CableModel.CHAIN

    def __init__(
        self,
        model: mujoco.MjModel,
        data: mujoco.MjData,
        scenario: Scenario,
        p_A: FloatArray,
        side_W: FloatArray,
    ) -> None:
        self._model, self._data = model, data
        t = scenario.tether
        self.spec = chain_spec(scenario)
        self.length = t.length
        k = t.stiffness
        self.k = math.inf if k is None else k
        self.c = t.damping(scenario.vehicle.mass)
        self.dt = scenario.sim.timestep
        sim = scenario.sim
        tau = hook_timeconst(scenario)
        self._k_c = scenario.vehicle.mass / (tau * sim.cable_damping_ratio) ** 2
        self._p_A = np.asarray(p_A, dtype=float)
        self._side = np.asarray(side_W, dtype=float)
        self._r_att = np.asarray(scenario.vehicle.cable_attachment, dtype=float)
        if model.neq != 1:
            raise ValueError("the chain cable expects the hook connect as the only equality")
        self._eq = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_EQUALITY, "hook")
        self._end = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "cable_end")
        n = self.spec.segments
        joint, body = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_BODY
        joints = [mujoco.mj_name2id(model, joint, f"cable_joint{i}") for i in range(n)]
        self._qadr = [int(model.jnt_qposadr[j]) for j in joints]
        self._vadr = [int(model.jnt_dofadr[j]) for j in joints]
        bodies = [mujoco.mj_name2id(model, body, f"cable_link{i}") for i in range(n)]
        vehicle = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "vehicle")
        for b in bodies:
            model.body_invweight0[b] = model.body_invweight0[vehicle]
        self._slot = SENSOR_SLICES["cable_force"].start
        self._sensordata = data.sensordata
        self._site_x = model.site_pos[self._end : self._end + 1, 0]
        self._engaged = False
        self.stretch = 0.0
        """Current elongation s of the line (quasi-static Kelvin-Voigt element) [m]."""
        v0 = self._vadr[0]
        self._armature = model.dof_armature[v0 : v0 + 3 * n]
        self._link_inertia = self.spec.link_mass * self.spec.link_length**2 / 3.0
        self._t_held = 0.0
        self._t_set = 0.0
        self._set_armature(0.0)


    @property
    def engaged(self) -> bool:
        return self._engaged

    @property
    def total_mass(self) -> float:
        """Mass of the simulated cable [kg]."""
        return self.spec.total_mass

    def advance(self) -> None:
        mujoco.mj_step(self._model, self._data)
        if not self._engaged:
            return
        e = self._data.efc_force  # the connect's three rows come first (the only equality)
        f = math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
        self._sensordata[self._slot] = f
        self._set_stretch(self._relax(self.stretch, f))
        # armature for the tension: twice the current one, held and decaying over ~0.1 s
        held = self._t_held * ARMATURE_DECAY
        self._t_held = held if held > 2.0 * f else 2.0 * f
        if not (self._t_set * 0.8 <= self._t_held <= self._t_set):
            self._set_armature(self._t_held)

    def _set_armature(self, tension: float) -> None:
        """Armature for links pulled by ``tension`` (w dt <= CHAIN_W_DT); raising it scales
        the links' joint rates down by (I + a_old)/(I + a_new), so that changing the
        inertia never adds kinetic energy (lowering it keeps the rates)."""
        spec, d = self.spec, self._data
        a_old = self._armature[0]
        a = chain_armature(tension, spec.link_length, spec.link_mass, self.dt)
        if a > a_old:
            scale = (self._link_inertia + a_old) / (self._link_inertia + a)
            for adr in self._vadr:
                d.qvel[adr : adr + 3] *= scale
        self._armature[:] = a
        self._t_set = tension

    def _relax(self, s: float, tension: float) -> float:
        """Next elongation of the Kelvin-Voigt element k s + c s' = f_L [m].

        Implicit Euler over dt with the tension's response to the elongation itself:
        moving the hook point by ds makes the connection pull back K_c ds, K_c = m/tau^2
        (the vehicle mass held by a constraint of time constant tau), so
        k s + c (s - s_k)/dt = f_k - K_c (s - s_k). Without the K_c term the update
        overshoots and diverges (loop gain K_c/k > 1 for soft lines).
        """
        k = self.k
        if k == math.inf:
            return 0.0
        b = self.c / self.dt + self._k_c
        return (tension + b * s) / (k + b)

    def _set_stretch(self, s: float) -> None:
        self.stretch = s
        self._site_x[0] = self.spec.link_length + s

    def forward(self) -> None:
        mujoco.mj_forward(self._model, self._data)
        if self._engaged:
            e = self._data.efc_force
            self._sensordata[self._slot] = math.sqrt(e[0] ** 2 + e[1] ** 2 + e[2] ** 2)

    def set_engaged(self, engaged: bool) -> None:
        self._engaged = bool(engaged)
        d = self._data
        if engaged:
            self._lay_out()
            d.eq_active[self._eq] = 1
        else:
            d.eq_active[self._eq] = 0
            self._park()
        set_cable_visible(self._model, engaged)

    def follow_vehicle(self) -> None:
        if self._engaged:
            self._lay_out()

    # -- chain configuration --------------------------------------------------------

    def attachment_point(self) -> FloatArray:
        """Attachment point from the vehicle's qpos (valid before kinematics) [m]."""
        q = self._data.qpos
        return q[0:3] + quat_to_rotmat(q[3:7]) @ self._r_att

    def _park(self) -> None:
        d = self._data
        self._t_held = 0.0
        self._set_armature(0.0)
        for a in self._qadr:
            d.qpos[a : a + 4] = (1.0, 0.0, 0.0, 0.0)
        for a in self._vadr:
            d.qvel[a : a + 3] = 0.0
        self._set_stretch(0.0)

    def _lay_out(self) -> None:
        """Lay the chain at rest from p_A to the attachment point: straight when the
        distance D >= l (the excess is the initial stretch of an elastic line), else
        hanging in its discrete catenary (:func:`chain_nodes`)."""
        nodes, stretch = chain_nodes(
            self._p_A, self.attachment_point(), self.length, self.spec.segments, self._side
        )
        if self.k == math.inf:
            stretch = 0.0
        quats = joint_quaternions(nodes)
        d = self._data
        for a, q in zip(self._qadr, quats, strict=True):
            d.qpos[a : a + 4] = q
        for a in self._vadr:
            d.qvel[a : a + 3] = 0.0
        self._set_stretch(stretch)


# -- chain geometry (plain numpy: runs at hook events only) ------------------------------


def hanging_chain_angles(
    n: int, span: float, rise: float, link_length: float
) -> FloatArray | None:
    """Upward slopes theta_i of n uniform rigid links hanging at rest between two points
    ``span`` apart horizontally and ``rise`` apart vertically [rad], i = 0 from the first;
    None when no such shape exists (ends nearly on one vertical: the rest shape folds back).

    Each link lies along the mean force on it (its weight at its middle):
    tan(theta_i) = ((i + 1/2) w - V_0)/H, V_0 the first support's vertical force and H
    the horizontal tension (w = 1: the shape does not depend on the weight), found from
    sum l_s cos(theta_i) = span and sum l_s sin(theta_i) = rise: the exact discrete
    catenary, for sqrt(span^2 + rise^2) < n l_s.
    """
    mid = np.arange(n) + 0.5

    def angles(x: FloatArray) -> FloatArray:
        return np.arctan2(mid - x[1], math.exp(x[0]))

    def residual(x: FloatArray) -> FloatArray:
        th = angles(x)
        return np.array([np.cos(th).sum() - span / link_length,
                         np.sin(th).sum() - rise / link_length])  # fmt: skip

    starts = [(math.log(h), f * n) for h in (1e-2, 1.0, 1e2) for f in (0.25, 0.5, 0.75)]
    best = min(starts, key=lambda x: float(np.sum(residual(np.array(x)) ** 2)))
    from scipy.optimize import least_squares  # 0.5 s to import: only where it is needed

    sol = least_squares(residual, best, xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=500)
    if float(np.max(np.abs(sol.fun))) > 1e-9:
        return None
    return angles(sol.x)


def chain_nodes(
    p_A: FloatArray, p_B: FloatArray, length: float, segments: int, side_W: FloatArray
) -> tuple[FloatArray, float]:
    """Joint positions of a chain of ``segments`` equal links from ``p_A`` to ``p_B``.

    Returns the (segments + 1, 3) nodes and the excess distance max(0, D - l) that the
    straight chain leaves to ``p_B``. A slack chain (D < l) hangs at rest in its exact
    discrete catenary (:func:`hanging_chain_angles`) in the vertical plane through both
    ends. With the ends nearly on one vertical, where that shape folds back, it is laid
    as a V instead: its corner at node N // 2, as low as the two straight legs allow, out
    along ``side_W`` (the chain then swings into its rest shape).
    """
    p_A, p_B = np.asarray(p_A, dtype=float), np.asarray(p_B, dtype=float)
    n = int(segments)
    l_s = length / n
    chord = p_B - p_A
    D = float(np.linalg.norm(chord))
    if D >= length:
        return p_A + np.outer(np.arange(n + 1) * l_s, chord / D), D - length
    rise = float(chord[2])
    horizontal = chord - rise * _Z
    span = float(np.linalg.norm(horizontal))
    side = np.asarray(side_W, dtype=float)
    theta = hanging_chain_angles(n, span, rise, l_s) if span > 1e-9 * length else None
    if theta is not None:
        e_h = horizontal / span
        steps = l_s * (np.outer(np.cos(theta), e_h) + np.outer(np.sin(theta), _Z))
        return p_A + np.vstack((np.zeros(3), np.cumsum(steps, axis=0))), 0.0
    e = chord / D if D > 1e-9 else side
    j = n // 2
    a, b = j * l_s, (n - j) * l_s
    # corner on the circle |c - p_A| = a, |c - p_B| = b (empty only if D < b - a = l_s:
    # odd N with the ends closer than a link; then the last leg falls short of p_B)
    x = (a * a - b * b + D * D) / (2.0 * D) if D > 1e-9 else 0.0
    x = min(max(x, -a), a)
    rho = math.sqrt(max(a * a - x * x, 0.0))
    down = -_Z + (_Z @ e) * e
    if float(np.linalg.norm(down)) < 1e-9:  # vertical chord: lay the V out along side_W
        down = side - (side @ e) * e
    w = down / np.linalg.norm(down)
    corner = p_A + x * e + rho * w
    nodes = np.empty((n + 1, 3))
    for i in range(j + 1):
        nodes[i] = p_A + (i / j) * (corner - p_A) if j > 0 else p_A
    for i in range(j, n + 1):
        nodes[i] = corner + ((i - j) / (n - j)) * (p_B - corner)
    return nodes, 0.0


def _min_rotation(a: FloatArray, b: FloatArray) -> FloatArray:
    """Smallest rotation taking unit vector ``a`` to unit vector ``b``."""
    v = np.cross(a, b)
    c = float(a @ b)
    s = float(np.linalg.norm(v))
    if s < 1e-12:
        if c > 0.0:
            return np.eye(3)
        helper = np.array([1.0, 0.0, 0.0]) if abs(a[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
        axis = np.cross(a, helper)
        axis /= np.linalg.norm(axis)
        return 2.0 * np.outer(axis, axis) - np.eye(3)
    k = v / s
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + s * K + (1.0 - c) * K @ K


_R_PARK = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
"""World rotation of the first link's body frame at qpos0: local x along -z_W."""


def joint_quaternions(nodes: FloatArray, frame0_W: FloatArray = _R_PARK) -> list[FloatArray]:
    """Ball-joint quaternions (w, x, y, z) that put the chain's joints at ``nodes``.

    Each link's x axis runs from its node to the next; the frames are carried from the
    parked chain (the first link's frame at qpos0, ``frame0_W`` in F_W: by default
    hanging along -z_W) by the smallest rotations, so no link twists.
    """
    dirs = np.diff(nodes, axis=0)
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    quats = []
    W_prev = np.asarray(frame0_W, dtype=float)
    u_prev = W_prev[:, 0]  # the first joint's parent frame: the body's fixed frame
    for u in dirs:
        W = _min_rotation(u_prev, u) @ W_prev
        quats.append(rotmat_to_quat(W_prev.T @ W))  # children: parent frame = previous link
        W_prev, u_prev = W, u
    return quats


LINE_TENSION_FLOOR = 2.0
"""Least tension the hanging line's armature is designed for [N]: a slack line of a few
grams in contact with the bar and the surface needs it to stay resolvable (it adds
under 1e-6 kg m^2 per joint, nothing against the hook's pendulum, m L^2 ~ 2e-2)."""


CATCH_FILTER_TIME = 0.05
"""Time constant of the low-pass on the bar's push on the hook that decides
:attr:`HangingLine.caught` (a hook bouncing on the bar is not caught) [s]."""


RELEASE_TIME = 0.2
"""A caught hook counts as released once it has not touched the bar for this long (a
hook resting in its crook on a slack line still touches it) [s]."""


class HangingLine:
    """The bar mechanism's cable: a line of capsule links hanging from the vehicle with the
    hook body at its end (docs/mechanism.md); it engages the anchoring cable only through
    contact and friction.

    The tension written to the ``cable_force`` slot is the magnitude of the line's pull on
    the vehicle (force sensor ``line_force`` at the first joint). The links' ball-joint
    armature follows the tension as the chain's does (:class:`ChainCable`): a few grams of
    line pulled by tens of newtons would swing faster than the step resolves. The line and
    hook get the vehicle's ``body_invweight0``, so that their contacts and joints are as
    stiff as the vehicle's (the taut line's true inverse inertia is the vehicle's). The air
    pushes on the links (:mod:`tetherland.sim.line_drag`, written into ``xfrc_applied``
    before every step): without it a slack line whipped by a falling hook gained energy
    from the integration until the simulation diverged.

    :attr:`caught` is the plant's truth for the log and the judge: set when the anchoring
    cable pushes on the line and the hook (net force, low-passed over
    :data:`CATCH_FILTER_TIME`) with more than ``mechanism.catch_threshold`` times the
    hook's weight (it holds the line's pull: a line merely sliding over the bar carries
    about the hook's weight) with the hook's crown within the hook's size of the bar's
    axis; cleared when neither has touched the bar for :data:`RELEASE_TIME` or the crown
    is farther. The contact alone decides what the bodies do; this only classifies. ``engaged`` is
    the same; :meth:`set_engaged` only lays the line out (the contact decides).
    """

    kind = CableModel.CHAIN

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, scenario: Scenario,
                 side_W: FloatArray) -> None:  # fmt: skip
        from tetherland.sim.mjcf import line_spec

        self._model, self._data = model, data
        self.spec = line_spec(scenario)
        mech = scenario.mechanism
        self.dt = scenario.sim.timestep
        self._side = np.asarray(side_W, dtype=float)
        self._r_att = np.asarray(scenario.vehicle.cable_attachment, dtype=float)
        self._ground_z = 0.0
        self._p_A = np.zeros(3)
        n = self.spec.segments
        joint, body = mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_BODY
        joints = [mujoco.mj_name2id(model, joint, f"line_joint{i}") for i in range(n)]
        joints.append(mujoco.mj_name2id(model, joint, "hook_joint"))
        self._qadr = [int(model.jnt_qposadr[j]) for j in joints]
        self._vadr = [int(model.jnt_dofadr[j]) for j in joints]
        vehicle = mujoco.mj_name2id(model, body, "vehicle")
        self._vehicle_body = vehicle
        links = [mujoco.mj_name2id(model, body, f"line_link{i}") for i in range(n)]
        for b in links:
            model.body_invweight0[b] = model.body_invweight0[vehicle]
        self._links = np.array(links, dtype=np.int64)
        self._drag_args = (self._links, int(model.body_rootid[links[0]]),
                           link_drag_factor(self.spec.radius, self.spec.link_length),
                           data.cvel, data.xipos, data.xmat, data.subtree_com,
                           data.xfrc_applied)  # fmt: skip
        sensor = mujoco.mjtObj.mjOBJ_SENSOR
        adr = model.sensor_adr
        self._force = int(adr[mujoco.mj_name2id(model, sensor, "line_force")])
        self._contact = int(adr[mujoco.mj_name2id(model, sensor, "hook_bar")])
        self._slot = SENSOR_SLICES["cable_force"].start
        self._sensordata = data.sensordata
        self._hook_weight = mech.hook_mass * 9.81
        self._catch = mech.catch_threshold * self._hook_weight
        self._shank = mech.hook_shank
        self._floor = mech.hook_reach + mech.hook_radius + 0.002
        v0 = self._vadr[0]
        self._armature = model.dof_armature[v0 : v0 + 3 * n]
        self._link_inertia = self.spec.link_mass * self.spec.link_length**2 / 3.0
        self._t_held = 0.0
        self._t_set = 0.0
        self.caught = False
        self.changed = False
        """True after a step in which :attr:`caught` changed."""
        self._push = 0.0
        self._alpha = min(1.0, self.dt / CATCH_FILTER_TIME)
        self._apart = 0
        self._release_steps = max(1, round(RELEASE_TIME / self.dt))
        site = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, "hook_crown")
        self._crown_xpos = data.site_xpos[site]
        self._bar_mid: tuple[float, ...] = (0.0, 0.0, 0.0)
        self._bar_dir: tuple[float, ...] = (0.0, 1.0, 0.0)
        self._bar_half = 0.5 * mech.bar_length
        near = bar_near_distance(mech)
        self._near2 = near * near
        self._set_armature(0.0)

    @property
    def engaged(self) -> bool:
        return self.caught

    @property
    def hook_bar_force(self) -> float:
        """Net contact force of the anchoring cable on the line and the hook, last step
        [N]."""
        d, c = self._sensordata, self._contact
        return math.sqrt(d[c + 1] ** 2 + d[c + 2] ** 2 + d[c + 3] ** 2) if d[c] > 0.0 else 0.0

    def _read(self) -> float:
        d, i = self._sensordata, self._force
        f = math.sqrt(d[i] * d[i] + d[i + 1] * d[i + 1] + d[i + 2] * d[i + 2])
        d[self._slot] = f
        return f

    def advance(self) -> None:
        line_drag_into(*self._drag_args)  # the air's push on the links, at the step's start
        mujoco.mj_step(self._model, self._data)
        d = self._sensordata
        i = self._force
        f = math.sqrt(d[i] * d[i] + d[i + 1] * d[i + 1] + d[i + 2] * d[i + 2])  # (_read)
        d[self._slot] = f
        held = self._t_held * ARMATURE_DECAY
        held = self._t_held = held if held > 2.0 * f else 2.0 * f
        t_set = self._t_set
        # (a held tension under the floor keeps the floor's armature: nothing to set)
        if not (t_set * 0.8 <= held <= t_set) and (
            held > LINE_TENSION_FLOOR or t_set != LINE_TENSION_FLOOR
        ):
            self._set_armature(held)
        c = self._contact
        touching = d[c] > 0.0
        raw = (math.sqrt(d[c + 1] ** 2 + d[c + 2] ** 2 + d[c + 3] ** 2) if touching
               else 0.0)  # fmt: skip
        push = self._push = self._push + (raw - self._push) * self._alpha
        was = self.caught
        if was:
            self._apart = 0 if touching else self._apart + 1
            self.caught = self._apart < self._release_steps and self._near_bar()
        else:
            # (the crown's distance matters only once the push would catch)
            self.caught = push > self._catch and self._near_bar()
            self._apart = 0
        self.changed = was != self.caught

    def _near_bar(self) -> bool:
        """The hook's crown within the hook's own size of the bar's axis (a line draped
        over the bar with the hook snagged elsewhere is not a caught hook)."""
        c = self._crown_xpos
        a, u, half = self._bar_mid, self._bar_dir, self._bar_half
        dx, dy, dz = c[0] - a[0], c[1] - a[1], c[2] - a[2]
        s = dx * u[0] + dy * u[1] + dz * u[2]
        s = -half if s < -half else (half if s > half else s)
        ex, ey, ez = dx - s * u[0], dy - s * u[1], dz - s * u[2]
        return ex * ex + ey * ey + ez * ez <= self._near2

    def _set_armature(self, tension: float) -> None:
        spec, d = self.spec, self._data
        a_old = self._armature[0]
        tension = max(tension, LINE_TENSION_FLOOR)
        a = chain_armature(tension, spec.link_length, spec.link_mass, self.dt)
        if a > a_old:
            scale = (self._link_inertia + a_old) / (self._link_inertia + a)
            for adr in self._vadr[:-1]:
                d.qvel[adr : adr + 3] *= scale
        self._armature[:] = a
        self._t_set = tension

    def forward(self) -> None:
        mujoco.mj_forward(self._model, self._data)
        self._read()

    def set_engaged(self, engaged: bool) -> None:
        """Lay the line out at rest (``engaged``: straight towards the anchor, else hanging,
        along the ground below ``set_floor``'s height); the contact decides the rest."""
        self._t_held = 0.0
        self._set_armature(0.0)
        self.caught = bool(engaged)
        self.changed = False
        self._push = self._catch if engaged else 0.0
        self.lay_out(toward_W=self._p_A if engaged else None)

    def set_anchor(self, p_A: FloatArray, floor_z: float, bar_axis_W: FloatArray) -> None:
        """The anchor (the bar's middle; for a line laid out engaged), the ground height
        under the start pad (a hanging line is laid along it) and the bar's axis [m, -]."""
        self._p_A = np.asarray(p_A, dtype=float)
        self._ground_z = float(floor_z)
        self._bar_mid = tuple(float(x) for x in self._p_A)
        u = np.asarray(bar_axis_W, dtype=float)
        self._bar_dir = tuple(float(x) for x in u / np.linalg.norm(u))

    def follow_vehicle(self) -> None:
        self.lay_out(toward_W=self._p_A if self.caught else None)

    def lay_out(self, toward_W: FloatArray | None = None) -> None:
        """Put the line and hook at rest: straight to ``toward_W``, else straight down from
        the attachment to just above the ground, then folded back and forth along
        ``side_W`` on it, the hook at the end."""
        d = self._data
        q = d.qpos
        R_WB = quat_to_rotmat(q[3:7])
        p0 = q[0:3] + R_WB @ self._r_att
        n = self.spec.segments
        l_s = self.spec.link_length
        steps = [l_s] * n + [self._shank]
        nodes = [p0]
        side = self._side - (self._side @ _Z) * _Z
        side /= np.linalg.norm(side)
        fold = 1.0
        for j, step in enumerate(steps):
            p = nodes[-1]
            if toward_W is not None:
                e = np.asarray(toward_W) - p
                e = e / max(float(np.linalg.norm(e)), 1e-9)
            elif p[2] - step >= self._ground_z + self._floor:
                e = -_Z
            elif j == len(steps) - 1:
                e = side  # the hook lies on the ground, beside the folds
            else:  # folded back and forth on the ground under the attachment (the links
                # do not touch each other): lifted, the hook rises from below the vehicle
                e, fold = fold * side, -fold
            nodes.append(p + step * e)
        frame0 = R_WB @ _R_PARK
        quats = joint_quaternions(np.array(nodes), frame0)
        for a, qj in zip(self._qadr, quats, strict=True):
            d.qpos[a : a + 4] = qj
        for a in self._vadr:
            d.qvel[a : a + 3] = 0.0
        d.xfrc_applied[self._links, 0:3] = 0.0  # at rest: no drag


def make_cable(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    scenario: Scenario,
    p_A: FloatArray,
    side_W: FloatArray,
) -> Cable:
    """The :class:`Cable` implementation of ``scenario.tether.cable_model`` (the
    :class:`HangingLine` for the bar mechanism)."""
    if scenario.mechanism.kind == "bar":
        return HangingLine(model, data, scenario, side_W)
    if scenario.mechanism.kind == "magnet":
        return MagnetCable(model, data, scenario)
    t = scenario.tether
    kind = t.cable_model
    if kind == CableModel.IDEAL:
        return IdealCable(model, data)
    if kind == CableModel.ELASTIC:
        k = t.stiffness
        assert k is not None
        return ElasticCable(model, data, k, t.damping(scenario.vehicle.mass), t.length)
    return ChainCable(model, data, scenario, p_A, side_W)


class MagnetCable(ElasticCable):
    """The magnet mechanism's cable and magnet (docs/mechanism.md): the massless elastic
    cable of :class:`ElasticCable` from the magnet's eye to the vehicle's attachment, always
    tied (its force acts on the magnet body and the vehicle), the magnet clipped to the
    boom's tip, the EPM the robot switches (:meth:`set_epm`) and the clip's latch it opens
    (:meth:`set_latch`).

    Plant behaviour, after every step:

    - the clip (the weld ``clip``) lets go for good once the force with which it holds
      the magnet back along the magnet's axis (the magnet pulled out of its socket)
      exceeds ``mechanism.clip_force`` (a spring clip pulled apart; the socket carries the
      shear and the moments), or ``mechanism.latch_time`` after the robot's command to open
      its latch, whatever holds the magnet then (the EPM off or not on the plate: it
      drops and hangs on the cable); :meth:`lay_out` clips it again and closes the latch;
    - :attr:`caught` (the plant's truth for the log and the judge, never the robot's):
      set once the magnet's face has touched the plate with the EPM on for
      ``mechanism.catch_time``, cleared at once when the EPM is off or the face leaves the
      plate. Only the contact and the EPM's pull decide what the bodies do;
    - the EPM's pull (:mod:`tetherland.sim.epm`), while on, is written into the magnet's
      ``xfrc_applied`` before each step's acceleration (the plant owns that row).
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, scenario: Scenario) -> None:
        t = scenario.tether
        k = t.stiffness
        assert k is not None
        super().__init__(model, data, k, t.damping(scenario.vehicle.mass), t.length)
        mech = scenario.mechanism
        obj = mujoco.mjtObj
        self._eq = mujoco.mj_name2id(model, obj.mjOBJ_EQUALITY, "clip")
        body = mujoco.mj_name2id(model, obj.mjOBJ_BODY, "magnet")
        self._body = body
        # the EPM's pull (tetherland.sim.epm): the face's cells against the plate's top
        plate = mujoco.mj_name2id(model, obj.mjOBJ_GEOM, "plate")
        R_WP = np.empty(9)
        mujoco.mju_quat2Mat(R_WP, model.geom_quat[plate])  # a world geom: F_W
        top = model.geom_pos[plate] + model.geom_size[plate][2] * R_WP.reshape(3, 3)[:, 2]
        face = mujoco.mj_name2id(model, obj.mjOBJ_SITE, "magnet_face")
        self._pull_args = (data.site_xpos[face], data.xmat[body], data.xipos[body],
                           cell_offsets(mech.magnet_radius), top, R_WP,
                           float(model.geom_size[plate][0]))  # fmt: skip
        self._force = mech.magnet_force
        self._xfrc = data.xfrc_applied[body]
        self.epm_pull = 0.0
        """The EPM's pull on the magnet along the plate's normal at the last step [N]."""
        self._level = 0.0
        """The EPM's pull as a fraction of ``magnet_force``: it builds up linearly over
        ``epm_on_time`` after the command (the charge pulses magnetise it step by step),
        and stays until ``epm_off_time`` after the command off [-]."""
        j = model.body_jntadr[body]
        self._qadr, self._vadr = int(model.jnt_qposadr[j]), int(model.jnt_dofadr[j])
        hinge = mujoco.mj_name2id(model, obj.mjOBJ_JOINT, "boom_hinge")
        self._hinge_q, self._hinge_v = int(model.jnt_qposadr[hinge]), int(model.jnt_dofadr[hinge])
        self._tip = mujoco.mj_name2id(model, obj.mjOBJ_SITE, "boom_tip")
        gimbal = mujoco.mj_name2id(model, obj.mjOBJ_JOINT, "gimbal")
        self._gimbal_q = int(model.jnt_qposadr[gimbal])
        self._gimbal_v = int(model.jnt_dofadr[gimbal])
        self._contact = int(model.sensor_adr[mujoco.mj_name2id(model, obj.mjOBJ_SENSOR,
                                                               "magnet_plate")])  # fmt: skip
        self._half = 0.5 * mech.magnet_thickness
        dt = scenario.sim.timestep
        self._switch_steps = (round(mech.epm_off_time / dt), round(mech.epm_on_time / dt))
        self._command = False
        self._pending = 0
        """Physics steps until the commanded state takes effect (0: none pending)."""
        self._latch_steps = round(mech.latch_time / dt)
        self._latch_command = False
        self._latch_pending = 0
        """Physics steps until the latch opens (0: none pending)."""
        self.clip_force = mech.clip_force
        self._catch_steps = max(1, round(mech.catch_time / scenario.sim.timestep))
        self._touching = 0
        self._p_A = np.zeros(3)
        self._z_S = np.array([0.0, 0.0, 1.0])
        self.caught = False
        self.changed = False
        """True after a step in which :attr:`caught` changed."""
        self.clipped = True
        """True while the clip holds the magnet on the boom's tip."""
        self.clip_pull = 0.0
        """The clip's pull on the magnet at the last step (0 once it let go) [N]."""
        self._engaged = True

    @property
    def engaged(self) -> bool:
        return self.caught

    @property
    def epm_on(self) -> bool:
        """Whether the EPM is switched on (its switch-on time over: the whole force) [-]."""
        return self._level >= 1.0

    def set_epm(self, on: bool) -> None:
        """The robot's command: the EPM on (its pull on the face builds up linearly from the
        command to its whole force ``mechanism.epm_on_time`` later) or off (the pull stays
        until ``epm_off_time`` later, then none); a command repeated meanwhile changes
        nothing."""
        on = bool(on)
        if on == self._command:
            return
        self._command = on
        self._pending = self._switch_steps[on]
        if self._pending == 0:
            self._level = 1.0 if on else 0.0

    @property
    def latch_open(self) -> bool:
        """Whether the robot's last latch command was to open it [-]."""
        return self._latch_command

    def set_latch(self, open_: bool) -> None:
        """The robot's command to the clip's latch: open (the clip lets the magnet go
        ``mechanism.latch_time`` later, held by the EPM or not) or closed (a pending opening
        is cancelled; a clip already open stays open: nothing puts the magnet back in its
        socket). A command repeated meanwhile changes nothing."""
        open_ = bool(open_)
        if open_ == self._latch_command:
            return
        self._latch_command = open_
        self._latch_pending = self._latch_steps if open_ else 0
        if open_ and not self._latch_pending:
            self._unclip()

    def _unclip(self) -> None:
        self._data.eq_active[self._eq] = 0
        self.clipped = False
        self.clip_pull = 0.0

    def _set_now(self, on: bool) -> None:
        self._command = bool(on)
        self._pending = 0
        self._level = 1.0 if on else 0.0

    def set_anchor(self, p_A: FloatArray, z_S: FloatArray) -> None:
        """The anchor (the eye of the held magnet) and the surface normal there [m, -]."""
        self._p_A = np.asarray(p_A, dtype=float)
        self._z_S = np.asarray(z_S, dtype=float)

    def clip_force_W(self) -> FloatArray:
        """Force of the clip on the magnet at the last step, F_W (0 when open) [N]."""
        d = self._data
        if not d.eq_active[self._eq]:
            return np.zeros(3)
        return np.array(d.efc_force[0:3])  # the weld's rows come first (the only equality)

    def advance(self) -> None:
        super().advance()
        d = self._data
        if self._pending:
            self._pending -= 1
            if self._command:  # building up: linear in the time since the command
                self._level = max(self._level, 1.0 - self._pending / self._switch_steps[1])
            if not self._pending:
                self._level = 1.0 if self._command else 0.0
        if self._latch_pending:
            self._latch_pending -= 1
            if not self._latch_pending and self.clipped:
                self._unclip()  # the latch opened
        if self.clipped:
            f = self.clip_force_W()
            n = d.xmat[self._body].reshape(3, 3)[:, 2]  # the magnet's axis, face-ward
            pull = -float(f @ n)  # pulled out of its socket (the tip holds it back)
            self.clip_pull = pull
            if pull > self.clip_force:
                self._unclip()
        s = d.sensordata
        if s[self._contact] > 0.0 and self._level >= 1.0:
            self._touching += 1
        else:
            self._touching = 0
        was = self.caught
        self.caught = self._touching >= self._catch_steps if not was else self._touching > 0
        self.changed = was != self.caught

    def _actuate(self) -> None:
        if self._level > 0.0:
            self.epm_pull = epm_pull_into(*self._pull_args, self._level * self._force,
                                          EPM_RANGE, self._xfrc)  # fmt: skip
        elif self.epm_pull:
            self._xfrc[:] = 0.0
            self.epm_pull = 0.0

    @property
    def plate_force(self) -> float:
        """Net contact force of the plate on the magnet's face at the last step [N]."""
        s, c = self._data.sensordata, self._contact
        return math.sqrt(s[c + 1] ** 2 + s[c + 2] ** 2 + s[c + 3] ** 2) if s[c] > 0.0 else 0.0

    def set_engaged(self, engaged: bool) -> None:
        """Lay the magnet out: on the plate at the anchor with the EPM on (``engaged``), else
        clipped on the boom's tip with the EPM off."""
        self.lay_out(on_plate=engaged)

    def follow_vehicle(self) -> None:
        if self.clipped:
            self.lay_out(on_plate=False)

    def lay_out(self, on_plate: bool = False) -> None:
        """Put the magnet at rest on the boom's tip (unfolded, clipped) or on the plate."""
        m, d = self._model, self._data
        d.qpos[self._hinge_q] = 0.0
        d.qvel[self._hinge_v] = 0.0
        g = self._gimbal_q
        d.qpos[g : g + 4] = (1.0, 0.0, 0.0, 0.0)
        d.qvel[self._gimbal_v : self._gimbal_v + 3] = 0.0
        mujoco.mj_kinematics(m, d)
        if on_plate:
            z = -self._z_S
            centre = self._p_A + self._half * z
            helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
            x = np.cross(helper, z)
            x /= np.linalg.norm(x)
            quat = rotmat_to_quat(np.column_stack((x, np.cross(z, x), z)))
        else:
            R = d.site_xmat[self._tip].reshape(3, 3)
            centre = d.site_xpos[self._tip] + self._half * R[:, 2]
            quat = rotmat_to_quat(R)
        a, v = self._qadr, self._vadr
        d.qpos[a : a + 3] = centre
        d.qpos[a + 3 : a + 7] = quat
        d.qvel[v : v + 6] = 0.0
        d.eq_active[self._eq] = 0 if on_plate else 1
        self.clipped = not on_plate
        self.clip_pull = 0.0
        self._latch_command = on_plate
        self._latch_pending = 0
        self._set_now(on_plate)
        self.caught = on_plate
        self._touching = self._catch_steps if on_plate else 0
        self.changed = False
