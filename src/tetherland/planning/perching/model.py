"""Planar free-flight model of the perching maneuver and the numbers of one request.

The vehicle moves in the vertical plane of the slope's fall line, P = span(x_A, z_W)
through the landing point p*_L (x_A: horizontal, downhill; the anchor frame's axis, which
exists without a cable too). Coordinates relative to p*_L in (x_A, z_W):

  x  = [px, pz, theta, vx, vz, omega, f_R, tau, f_R', tau']      (10, "wrench form")
  u  = [f_R'', tau'']                                             (2)

  px'' = f_R sin(theta)/m,  pz'' = f_R cos(theta)/m - g,  theta'' = tau/J_y

With the believed rotor drag d_x (``controller.rotor_drag``, switched by
``perching.model_rotor_drag``) the rotors are pushed back in their plane, as the plant's
F = -R_WB diag(d_x, d_y, 0) R_WB^T v (:mod:`tetherland.models.aero`) restricted to the plane
(y_B is normal to it, so d_y never acts): the acceleration gets
-(d_x s / m) (v . x_B) x_B, x_B = [cos theta, -sin theta], with the rotor-speed scale
s = w / w_h = sqrt(f_R / (m g)) (the controllers' feed-forward's,
:func:`tetherland.control.rotor_drag.drag_acceleration`). The drag acts at the centre of
mass: no torque.

theta is the pitch of the thrust axis from vertical towards x_A (z_B = [sin theta, 0,
cos theta] in F_A, as theta_A of the tethered model), omega = theta' the body rate about
y_A = y_B, tau the torque about y_B. This is the 3D rigid body (6.1)-(6.2) restricted to
the plane (roll = 0, heading such that x_B stays in the plane), with a double dynamic
extension on the thrust and torque so that the flat output p(t) is C^3 and its snap is
defined (piecewise continuous): the reference the geometric controller needs. The rotor
thrusts keeping the motion planar are f = G [f_R, tau] (:attr:`PlanarParams.G`).

Landing (conditions (1)-(3) of section 6.3, z_B = z_S): theta(t_L) = beta, the centre of
mass at p*_L + h_R z_S, omega(t_L) = 0, tau(t_L) = 0 (no angular acceleration at t_L-),
p'(t_L) = -v_n z_S with the prescribed approach speed v_n >= 0, and f_R(t_L) = m g cos(beta)
(see :mod:`.problem`).

Clearance: a body point at (b_x, b_z) in the body's pitch plane is at height
h + b_z cos(a) - b_x sin(a) above the surface, with h = z_S . (p - p*_L) and
a = theta - beta the pitch relative to the surface. Lander tips (+-w, -h_R) and the
outer rims of the rotor guards (+-r_g, 0) must stay above the surface before t_L.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from tetherland import GRAVITY
from tetherland.config import PerchingWeights, Scenario
from tetherland.errors import ConfigError
from tetherland.geometry import FloatArray, LandingGeometry, effective_h_R
from tetherland.models.planar import PlanarParams
from tetherland.models.quadrotor import RotorLayout

NX, NU = 10, 2
STATE_NAMES = ("px", "pz", "theta", "vx", "vz", "omega", "f_R", "tau", "f_R_dot", "tau_dot")
INPUT_NAMES = ("f_R_ddot", "tau_ddot")
GUARD_RADIUS_FRACTION = 0.4
"""Rotor-guard radius over arm length, as the simulated vehicle's
(:data:`tetherland.models.airframe.PROP_RADIUS_FRACTION`; a test keeps them equal) [-]."""
PLANE_TOL = 1e-3
"""Largest distance of a start point from the fall-line plane [m]."""

NUMPY = SimpleNamespace(sin=np.sin, cos=np.cos, sqrt=np.sqrt, stack=np.stack)
CASADI = SimpleNamespace(
    sin=ca.sin, cos=ca.cos, sqrt=ca.sqrt, stack=lambda items: ca.vertcat(*items)
)


def drag_terms(x: Any, mass: Any, gravity: Any, drag: Any, ops: SimpleNamespace) -> Any:
    """(a_x, a_z): the rotor drag's acceleration in (x_A, z_W) of states ``x`` for the
    drag coefficient ``drag`` = d_x at the hover rotor speed [N s/m] (see the module
    docstring) [m/s^2]."""
    th, F = x[2], x[6]
    c, s = ops.cos(th), ops.sin(th)
    scale = ops.sqrt(F / (mass * gravity))
    k = -drag * scale * (x[3] * c - x[4] * s) / mass  # -(d s / m) (v . x_B)
    return k * c, -k * s


def rhs(
    x: Any, u: Any, mass: Any, inertia: Any, gravity: Any, ops: SimpleNamespace,
    drag: Any = None,
) -> Any:  # fmt: skip
    """x' of the extended planar model for any backend (numbers, arrays, CasADi); with
    ``drag`` (d_x [N s/m], a number or a symbol) the rotor drag of :func:`drag_terms`
    (None: the drag-free model, expression for expression)."""
    th, F = x[2], x[6]
    if drag is not None:
        ax, az = drag_terms(x, mass, gravity, drag, ops)
        return ops.stack(
            [
                x[3],
                x[4],
                x[5],
                F * ops.sin(th) / mass + ax,
                F * ops.cos(th) / mass - gravity + az,
                x[7] / inertia,
                x[8],
                x[9],
                u[0],
                u[1],
            ]
        )
    return ops.stack(
        [
            x[3],
            x[4],
            x[5],
            F * ops.sin(th) / mass,
            F * ops.cos(th) / mass - gravity,
            x[7] / inertia,
            x[8],
            x[9],
            u[0],
            u[1],
        ]
    )


def flat_derivatives(
    x: FloatArray, u: FloatArray, mass: float, inertia: float, gravity: float,
    drag: float = 0.0,
) -> dict[str, FloatArray]:  # fmt: skip
    """Acceleration, jerk and snap of the centre of mass in (x_A, z_W) coordinates.

    Parameters
    ----------
    x : (10, n) array
    u : (2, n) array
    drag : float
        Rotor drag d_x of the model [N s/m] (0: the drag-free model's closed forms).

    Returns
    -------
    dict
        ``acc``, ``jerk``, ``snap`` (2, n) [m/s^2, m/s^3, m/s^4] and ``omega_dot`` (n,)
        [rad/s^2].
    """
    th, om, F, tau, dF = x[2], x[5], x[6], x[7], x[8]
    om_dot = tau / inertia
    if drag != 0.0:
        c = np.array([mass, inertia, gravity, drag])
        acc, jerk, snap = _drag_flat_function()(x, u, c)
        return {"acc": np.asarray(acc), "jerk": np.asarray(jerk), "snap": np.asarray(snap),
                "omega_dot": om_dot}  # fmt: skip
    z_B = np.stack((np.sin(th), np.cos(th)))
    x_B = np.stack((np.cos(th), -np.sin(th)))
    acc = F / mass * z_B
    acc[1] -= gravity
    jerk = dF / mass * z_B + F * om / mass * x_B
    snap = (u[0] - F * om * om) / mass * z_B + (2.0 * dF * om + F * om_dot) / mass * x_B
    return {"acc": acc, "jerk": jerk, "snap": snap, "omega_dot": om_dot}


@functools.cache
def _drag_flat_function() -> ca.Function:
    """``f(x[10], u[2], c[4]) -> (acc, jerk, snap)`` (2 each) of the model with rotor drag,
    c = [m, J_y, g, d_x]: the acceleration of :func:`rhs` and its time derivatives along
    the motion, d/dt = (d/dx) x' (the input is held, and the acceleration and the jerk do
    not depend on it)."""
    x, u, c = ca.SX.sym("x", NX), ca.SX.sym("u", NU), ca.SX.sym("c", 4)
    xdot = rhs(x, u, c[0], c[1], c[2], CASADI, c[3])
    acc = xdot[3:5]
    jerk = ca.jacobian(acc, x) @ xdot
    snap = ca.jacobian(jerk, x) @ xdot
    return ca.Function("perch_drag_flat", [x, u, c], [acc, jerk, snap])


def guard_reach(scenario: Scenario) -> float:
    """Largest |x_B| of the rotor-guard rims in the pitch plane (x_B, z_B) [m]."""
    v = scenario.vehicle
    rotors = RotorLayout.from_config(v).positions_B
    return float(np.max(np.abs(rotors[:, 0]))) + GUARD_RADIUS_FRACTION * v.arm_length


@dataclass(frozen=True)
class PerchSpec:
    """Everything the perching planner needs to know about one request (SI, radians).

    Attributes
    ----------
    scenario_name : str
    mass, inertia, gravity : float
        m [kg], J_y [kg m^2], g [m/s^2].
    G : (4, 2) array
        [f_R, tau] -> rotor thrusts (planar, no roll or yaw torque) [-, 1/m].
    allocation : (4, 4) array
        Gamma (6.19).
    R_WA : (3, 3) array
        Plane frame: columns x_A (horizontal downhill), y_A, z_W.
    p_L : (3,) array
        Landing point p*_L in F_W (origin of the plane coordinates) [m].
    beta : float
        Slope angle [rad]; z_S = [sin beta, 0, cos beta] in (x_A, y_A, z_W).
    h_R : float
        Centre of mass to landers plane [m].
    lander_half_width, guard_reach : float
        Body extents in the pitch plane [m].
    x_start : (10,) array
        Initial extended state.
    approach_speed : float
        v_n of p'(t_L) = -v_n z_S [m/s].
    approach_height : float
        d_f, height of the approach funnel above the surface [m].
    f_lo, f_hi : float
        Planned rotor thrust bounds [f_min + margin, f_max - margin] [N].
    f_min, f_max : float
        The vehicle's own rotor limits [N].
    max_pitch : float
        |theta| bound [rad].
    clearance_margin : float
        [m].
    weights : PerchingWeights
    rotor_drag : float
        Believed rotor drag d_x in the model [N s/m] (0: drag-free, see
        ``perching.model_rotor_drag``).
    heading : float
        Yaw of x_A in F_W, atan2(x_A.y_W, x_A.x_W): the reference yaw psi [rad].
    """

    scenario_name: str
    mass: float
    inertia: float
    gravity: float
    G: FloatArray
    allocation: FloatArray
    R_WA: FloatArray
    p_L: FloatArray
    beta: float
    h_R: float
    lander_half_width: float
    guard_reach: float
    x_start: FloatArray
    approach_speed: float
    approach_height: float
    f_lo: float
    f_hi: float
    f_min: float
    f_max: float
    max_pitch: float
    clearance_margin: float
    weights: PerchingWeights
    rotor_drag: float = 0.0

    @classmethod
    def from_scenario(
        cls, scenario: Scenario, start: ArrayLike | None = None, approach_speed: float | None = None
    ) -> PerchSpec:
        """The perching request of ``scenario`` (``[perching]``, vehicle and surface).

        Parameters
        ----------
        start : (10,) array, optional
            Initial extended state in plane coordinates (see :meth:`plane_state`); by
            default a hover at ``perching.hover_position`` or ``hover_distance`` along
            the normal through the landing point.
        approach_speed : float, optional
            Overrides ``perching.approach_speed`` [m/s].
        """
        cfg, v = scenario.perching, scenario.vehicle
        geo = LandingGeometry.from_scenario(scenario)
        params = PlanarParams.from_scenario(scenario, heading=0.0)
        R_WA, p_L = geo.R_WA, geo.p_L
        h_R = effective_h_R(scenario)
        spec = cls(
            scenario_name=scenario.name,
            mass=v.mass,
            inertia=params.inertia,
            gravity=GRAVITY,
            G=params.G,
            allocation=params.allocation,
            R_WA=R_WA,
            p_L=p_L,
            beta=geo.theta_A_star,
            h_R=h_R,
            lander_half_width=v.lander_half_width,
            guard_reach=guard_reach(scenario),
            x_start=np.zeros(NX),
            approach_speed=cfg.approach_speed if approach_speed is None else approach_speed,
            approach_height=cfg.approach_height,
            f_lo=v.f_min + v.control_margin,
            f_hi=v.f_max - v.control_margin,
            f_min=v.f_min,
            f_max=v.f_max,
            max_pitch=math.radians(cfg.max_pitch_deg),
            clearance_margin=cfg.clearance_margin,
            weights=cfg.weights,
            rotor_drag=float(scenario.controller.rotor_drag[0]) if cfg.model_rotor_drag else 0.0,
        )
        if start is None:
            if cfg.hover_position is not None:
                p0 = np.asarray(cfg.hover_position, dtype=float)
            else:
                p0 = spec.p_landed_W + cfg.hover_distance * spec.z_S_W
            start = spec.hover_state(p0)
        x0 = np.asarray(start, dtype=float).reshape(-1)
        if x0.shape != (NX,) or not np.all(np.isfinite(x0)):
            raise ValueError(f"start must be 10 finite numbers, got shape {x0.shape}")
        object.__setattr__(spec, "x_start", x0)
        return spec

    # -- frames ----------------------------------------------------------------------
    @property
    def z_S(self) -> FloatArray:
        """z_S in plane coordinates (x_A, z_W)."""
        return np.array([math.sin(self.beta), math.cos(self.beta)])

    @property
    def z_S_W(self) -> FloatArray:
        return self.to_world_vector(self.z_S)

    @property
    def heading(self) -> float:
        x_A = self.R_WA[:, 0]
        return math.atan2(float(x_A[1]), float(x_A[0]))

    @property
    def p_landed(self) -> FloatArray:
        """Landed centre of mass p*_L + h_R z_S in plane coordinates [m]."""
        return self.h_R * self.z_S

    @property
    def p_landed_W(self) -> FloatArray:
        return self.p_L + self.h_R * self.z_S_W

    @property
    def v_final(self) -> FloatArray:
        """Planned touchdown velocity -v_n z_S in plane coordinates [m/s]."""
        return -self.approach_speed * self.z_S

    @property
    def f_R_final(self) -> float:
        """Touchdown thrust m g cos(beta): zero normal acceleration at t_L- [N]."""
        return self.mass * self.gravity * math.cos(self.beta)

    def to_world_vector(self, v: ArrayLike) -> FloatArray:
        """Plane components (x_A, z_W) -> F_W; works on (2,) or (2, n)."""
        v = np.asarray(v, dtype=float)
        return np.tensordot(self.R_WA[:, [0, 2]], v, axes=(1, 0))

    def to_world_point(self, p: ArrayLike) -> FloatArray:
        p = np.asarray(p, dtype=float)
        out = self.to_world_vector(p)
        return out + (self.p_L if out.ndim == 1 else self.p_L[:, None])

    def to_plane(self, p_W: ArrayLike, what: str = "point") -> FloatArray:
        """(x_A, z_W) coordinates of a world point relative to p*_L; it must lie in the plane."""
        d = np.asarray(p_W, dtype=float) - self.p_L
        off = float(self.R_WA[:, 1] @ d)
        if abs(off) > PLANE_TOL:
            raise ConfigError(
                f"{what} is {off:+.3g} m off the vertical plane of the fall line through the "
                f"landing point (tolerance {PLANE_TOL} m): the planar perching model needs it there"
            )
        return np.array([self.R_WA[:, 0] @ d, d[2]])

    def hover_state(self, p_W: ArrayLike) -> FloatArray:
        """Extended state hovering level at the world point ``p_W`` (in the plane)."""
        x = np.zeros(NX)
        x[0:2] = self.to_plane(p_W, "the start point")
        x[6] = self.mass * self.gravity
        return x

    # -- derived quantities ------------------------------------------------------------
    def rotor_thrusts(self, x: ArrayLike) -> FloatArray:
        """Rotor thrusts (n, 4) of states (n, 10) (or one state) [N]."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        return x[:, 6:8] @ self.G.T

    def clearances(self, x: ArrayLike) -> FloatArray:
        """(n, 4) heights above the surface of the lander tips (downhill, uphill) and of the
        guard rims (downhill, uphill) for states (n, 10) [m]."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        return clearance_terms(x.T, self.beta, self.h_R, self.lander_half_width,
                               self.guard_reach, NUMPY).T  # fmt: skip

    def hover_feasible(self) -> bool:
        f = self.G @ np.array([self.mass * self.gravity, 0.0])
        return bool(np.all(f >= self.f_lo - 1e-9) and np.all(f <= self.f_hi + 1e-9))


def clearance_terms(x: Any, beta: Any, h_R: Any, w: Any, reach: Any, ops: SimpleNamespace) -> Any:
    """Heights of the lander tips (+-w, -h_R) and guard rims (+-reach, 0) above P_S."""
    h = ops.sin(beta) * x[0] + ops.cos(beta) * x[1]
    a = x[2] - beta
    s, c = ops.sin(a), ops.cos(a)
    return ops.stack([h - h_R * c - w * s, h - h_R * c + w * s, h - reach * s, h + reach * s])
