"""Planar free-flight model of the perching maneuver and the numbers of one request.

The vehicle moves in the vertical plane of the slope's fall line, P = span(x_A, z_W)
through the landing point p*_L (x_A: horizontal, downhill; the anchor frame's axis, which
exists without a cable too). Coordinates relative to p*_L in (x_A, z_W):

  x  = [px, pz, theta, vx, vz, omega, f_R, tau, f_R', tau']      (10, "wrench form")
  u  = [f_R'', tau'']                                             (2)

  px'' = f_R sin(theta)/m,  pz'' = f_R cos(theta)/m - g,  theta'' = tau/J_y

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

NUMPY = SimpleNamespace(sin=np.sin, cos=np.cos, stack=np.stack)
CASADI = SimpleNamespace(sin=ca.sin, cos=ca.cos, stack=lambda items: ca.vertcat(*items))


def rhs(x: Any, u: Any, mass: Any, inertia: Any, gravity: Any, ops: SimpleNamespace) -> Any:
    """x' of the extended planar model for any backend (numbers, arrays, CasADi)."""
    th, F = x[2], x[6]
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
    x: FloatArray, u: FloatArray, mass: float, inertia: float, gravity: float
) -> dict[str, FloatArray]:
    """Acceleration, jerk and snap of the centre of mass in (x_A, z_W) coordinates.

    Parameters
    ----------
    x : (10, n) array
    u : (2, n) array

    Returns
    -------
    dict
        ``acc``, ``jerk``, ``snap`` (2, n) [m/s^2, m/s^3, m/s^4] and ``omega_dot`` (n,)
        [rad/s^2].
    """
    th, om, F, tau, dF = x[2], x[5], x[6], x[7], x[8]
    z_B = np.stack((np.sin(th), np.cos(th)))
    x_B = np.stack((np.cos(th), -np.sin(th)))
    om_dot = tau / inertia
    acc = F / mass * z_B
    acc[1] -= gravity
    jerk = dF / mass * z_B + F * om / mass * x_B
    snap = (u[0] - F * om * om) / mass * z_B + (2.0 * dF * om + F * om_dot) / mass * x_B
    return {"acc": acc, "jerk": jerk, "snap": snap, "omega_dot": om_dot}


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
