"""Planar tethered model (6.18) and its double dynamic extension (6.20), numpy and CasADi.

In the vertical plane P_M = span(x_A, z_A) (delta = 0, roll = 0, psi = psi* constant):

  phi''     = -(g/l) cos(phi) + cos(phi + theta_A) f_R / (m l)        (6.18)
  theta_A'' = tau_y / J_y
  f_L       = f_R sin(phi + theta_A) - m g sin(phi) + m l phi'^2

with u_M = [f_R, tau_y] = Gamma_M f (6.19): f_R = sum f_i and tau_y = e_B . tau_B, the
torque about y_A (e_B = R_BA y_A = [sin psi, cos psi, 0]); J_y = e_B . J e_B.

Double dynamic extension (6.20), "rotor form": state
x = [phi, theta_A, phi', theta_A', f_1..f_4, f_1'..f_4'] (12), input u = [f_1''..f_4''];
phi'', phi''', theta_A'', theta_A''' are functions of x and the 4th derivatives of x and
u (:meth:`ExtendedPlanarModel.derivatives`). The chapter lists phi'', phi''' as states too;
that is the same system.

"Wrench form": the same dynamics in w = [f_R, tau_y]: state
z = [phi, theta_A, phi', theta_A', f_R, tau_y, f_R', tau_y'] (8), input v = [f_R'', tau_y''].
The rotor thrusts that keep the motion planar (no roll and no yaw torque) are
f = G w with G = Gamma^-1 restricted to the (f_R, tau_y) directions; Gamma_M G = I.

Every formula below is written once for a generic math backend (``numpy`` for numbers
and arrays, ``casadi`` for symbols); parameters may be numbers or CasADi symbols.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from types import SimpleNamespace
from typing import TYPE_CHECKING, Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from tetherland import GRAVITY
from tetherland.errors import ConfigError
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.models.integrators import rk4
from tetherland.models.quadrotor import RotorLayout

if TYPE_CHECKING:
    from tetherland.config import Scenario

NX = 12
"""Size of the rotor-form extended state."""
NU = 4
"""Size of the rotor-form input (rotor thrust second derivatives)."""
NZ = 8
"""Size of the wrench-form extended state."""
NV = 2
"""Size of the wrench-form input [f_R'', tau_y'']."""
NC = 10
"""Size of :attr:`PlanarParams.coefficients`."""

PHI, THETA, PHI_DOT, THETA_DOT = 0, 1, 2, 3
THRUSTS = slice(4, 8)
THRUST_RATES = slice(8, 12)

NUMPY = SimpleNamespace(sin=np.sin, cos=np.cos, stack=np.stack)
CASADI = SimpleNamespace(sin=ca.sin, cos=ca.cos, stack=lambda items: ca.vertcat(*items))


@dataclass(frozen=True)
class PlanarParams:
    """Constants of the planar model.

    Attributes
    ----------
    mass : float
        m [kg].
    length : float
        l, anchor to the link end [m].
    inertia : float
        J_y = e_B . J e_B, moment of inertia about y_A [kg m^2].
    torque_row : (4,) array
        e_B . (rows 2-4 of Gamma): tau_y = torque_row . f [m].
    allocation : (4, 4) array
        Gamma of the rotor layout (6.19) [-, m].
    heading : float
        psi*, the constant rotation about z_B [rad].
    gravity : float
        g [m/s^2].
    offset : (2,) tuple
        (r_x, r_z): the cable attachment offset in the plane at theta_A = 0, the x_A and
        z_A components of R_z(psi*) r_att [m] (docs/theory.md section 4.6; (0, 0): the
        chapter's cable at the centre of mass).
    offset_across : float
        y_A component of R_z(psi*) r_att [m]: it adds no planar dynamics, only rotor
        torques about x_A and z_A (:func:`planar_across_torque`).
    """

    mass: float
    length: float
    inertia: float
    torque_row: FloatArray
    allocation: FloatArray
    heading: float = 0.0
    gravity: float = GRAVITY
    offset: tuple[float, float] = (0.0, 0.0)
    offset_across: float = 0.0

    @classmethod
    def from_matrices(
        cls,
        mass: float,
        length: float,
        inertia_B: ArrayLike,
        allocation: ArrayLike,
        heading: float = 0.0,
        gravity: float = GRAVITY,
        r_att_B: ArrayLike | None = None,
    ) -> PlanarParams:
        """Planar constants for a vehicle flying with heading ``psi*`` = ``heading``.

        Parameters
        ----------
        inertia_B : (3,) or (3, 3) array
            J in F_B [kg m^2].
        allocation : (4, 4) array
            Gamma (6.19).
        r_att_B : (3,) array, optional
            Cable attachment offset in F_B [m] (default: at the centre of mass).

        Raises
        ------
        ConfigError
            If y_A is not a principal axis of the body for this heading (J_xx != J_yy
            and psi* not a multiple of 90 deg): rotating about it would then need roll
            and yaw torques, which the planar model does not have.
        """
        J = np.asarray(inertia_B, dtype=float)
        J = np.diag(J) if J.shape == (3,) else J
        e_B = np.array([math.sin(heading), math.cos(heading), 0.0])
        Je = J @ e_B
        J_y = float(e_B @ Je)
        if np.linalg.norm(Je - J_y * e_B) > 1e-9 * np.linalg.norm(J):
            raise ConfigError(
                f"heading psi* = {math.degrees(heading):g} deg: y_A is not a principal axis of "
                "the body (J_xx != J_yy), the planar model (6.18) does not apply; "
                "use a multiple of 90 deg"
            )
        Gamma = np.asarray(allocation, dtype=float)
        r = np.zeros(3) if r_att_B is None else np.asarray(r_att_B, dtype=float)
        c_h, s_h = math.cos(heading), math.sin(heading)
        r0 = np.array([c_h * r[0] - s_h * r[1], s_h * r[0] + c_h * r[1], r[2]])  # R_z(psi) r
        return cls(
            mass=mass,
            length=length,
            inertia=J_y,
            torque_row=e_B @ Gamma[1:4],
            allocation=Gamma,
            heading=heading,
            gravity=gravity,
            offset=(float(r0[0]), float(r0[2])),
            offset_across=float(r0[1]),
        )

    @classmethod
    def from_scenario(
        cls, scenario: Scenario, heading: float = 0.0, geometry: LandingGeometry | None = None
    ) -> PlanarParams:
        """The scenario's vehicle on its taut link of length l + s: the cable stretched by
        the landed hover's tension (:attr:`LandingGeometry.link_length`, docs/theory.md
        section 4.2; l for an inextensible cable). ``geometry``: the scenario's
        :class:`LandingGeometry` when the caller has it (computed otherwise)."""
        v = scenario.vehicle
        geometry = geometry or LandingGeometry.from_scenario(scenario)
        return cls.from_matrices(
            v.mass,
            geometry.link_length,
            v.inertia,
            RotorLayout.from_config(v).allocation,
            heading,
            r_att_B=v.cable_attachment,
        )

    @property
    def has_offset(self) -> bool:
        """Whether the cable is attached away from the centre of mass in the plane."""
        return self.offset != (0.0, 0.0)

    @property
    def coefficients(self) -> FloatArray:
        """[m, l, J_y, g, torque_row (4), r_x, r_z]: the constants the dynamics depend on
        (NC = 10,)."""
        return np.concatenate(
            ([self.mass, self.length, self.inertia, self.gravity], self.torque_row, self.offset)
        )

    @property
    def e_B(self) -> FloatArray:
        """y_A in F_B: the body axis of the planar rotation."""
        return np.array([math.sin(self.heading), math.cos(self.heading), 0.0])

    @functools.cached_property
    def Gamma_M(self) -> FloatArray:
        """(2, 4) map f -> [f_R, tau_y] (6.19) (computed once; read-only)."""
        GM = np.vstack((np.ones(4), self.torque_row))
        GM.setflags(write=False)
        return GM

    @functools.cached_property
    def G(self) -> FloatArray:
        """(4, 2) map [f_R, tau_y] -> rotor thrusts with zero roll and yaw torque [-, 1/m]
        (computed once; read-only)."""
        Gi = np.linalg.inv(self.allocation)
        G = np.column_stack((Gi[:, 0], Gi[:, 1:4] @ self.e_B))
        G.setflags(write=False)
        return G


def planar_terms(
    phi: Any,
    theta: Any,
    dphi: Any,
    dtheta: Any,
    F: Any,
    tau: Any,
    dF: Any,
    dtau: Any,
    ddF: Any,
    ddtau: Any,
    c: Any,
    ops: SimpleNamespace,
) -> dict[str, Any]:
    """Accelerations, jerks, snaps and tension of the planar model, for any backend.

    Arguments are numbers, arrays or CasADi symbols: the output elevation and tilt with
    their rates, the planar wrench w = [F = f_R, tau = tau_y] with w' and w'' (``ddF`` and
    ``ddtau`` may be None, then the snaps are omitted), and ``c`` an object with
    ``mass``, ``length``, ``inertia``, ``gravity`` and ``offset`` (r_x, r_z).

    ``tau`` is the planner's net torque about y_A, J_y theta_A'' (docs/theory.md
    (4.20)): the rotor torque is tau + b f_L (:func:`rotor_torque`), the cable's own
    moment cancelled as the controllers do. The accelerations and the tension are then
    exact with the attachment offset ``c.offset``; the closed-form jerks and snaps are
    those of the chapter's model, exact for a zero offset only (with an offset
    :meth:`ExtendedPlanarModel.derivatives` differentiates the exact model instead).
    """
    a1 = -c.gravity / c.length
    a2 = 1.0 / (c.mass * c.length)
    s = phi + theta
    ds = dphi + dtheta
    cs, ss = ops.cos(s), ops.sin(s)
    cp, sp = ops.cos(phi), ops.sin(phi)
    ddtheta = tau / c.inertia
    a, b = _arms(cs, ss, c.offset)
    ddphi = a1 * cp + a2 * cs * F + (a * ddtheta - b * dtheta**2) / c.length  # (6.18), (4.20)
    out = {
        "phi_ddot": ddphi,
        "theta_ddot": ddtheta,
        "phi_dddot": -a1 * sp * dphi - a2 * ss * ds * F + a2 * cs * dF,
        "theta_dddot": dtau / c.inertia,
        "tension": _tension(F, ss, sp, dphi, dtheta, ddtheta, a, b, c),
    }
    if ddF is not None:
        dds = ddphi + ddtheta
        out["phi_ddddot"] = (
            -a1 * cp * dphi**2
            - a1 * sp * ddphi
            - a2 * cs * ds**2 * F
            - a2 * ss * dds * F
            - 2.0 * a2 * ss * ds * dF
            + a2 * cs * ddF
        )
        out["theta_ddddot"] = ddtau / c.inertia
    return out


def _tension(
    F: Any, ss: Any, sp: Any, dphi: Any, dtheta: Any, ddtheta: Any, a: Any, b: Any, c: Any
) -> Any:
    """f_L (4.21) from f_R, sin(s), sin(phi), the rates, theta_A'' and the arms (a, b)."""
    return (
        F * ss
        - c.mass * c.gravity * sp
        + c.mass * c.length * dphi**2
        + c.mass * (a * dtheta**2 + b * ddtheta)
    )


def planar_tension(
    phi: Any, theta: Any, dphi: Any, dtheta: Any, F: Any, tau: Any, c: Any, ops: SimpleNamespace
) -> Any:
    """The tension f_L (4.21) of :func:`planar_terms` alone (no jerks or snaps) [N]."""
    s = phi + theta
    cs, ss = ops.cos(s), ops.sin(s)
    a, b = _arms(cs, ss, c.offset)
    return _tension(F, ss, ops.sin(phi), dphi, dtheta, tau / c.inertia, a, b, c)


def offset_arms(phi: Any, theta: Any, r0: tuple[Any, Any], ops: SimpleNamespace) -> tuple[Any, Any]:
    """(a, b) = (t.w, d.w), w = y_A x r, r = R_y(theta_A) r0 in the plane (docs/theory.md
    (4.13)): the lever arms of the offset along and across the link [m]."""
    s = phi + theta
    return _arms(ops.cos(s), ops.sin(s), r0)


def _arms(cs: Any, ss: Any, r0: tuple[Any, Any]) -> tuple[Any, Any]:
    """(a, b) of (4.13) from cos(s), sin(s), s = phi + theta_A: with r = R_y(theta_A) r0,
    a = -sin(phi) r_z - cos(phi) r_x = -(r0_x cos s + r0_z sin s) and
    b = cos(phi) r_z - sin(phi) r_x = r0_z cos s - r0_x sin s (two trigonometric
    evaluations instead of four)."""
    return -(r0[0] * cs + r0[1] * ss), r0[1] * cs - r0[0] * ss


def rotor_torque(phi: Any, theta: Any, tau: Any, tension: Any, c: Any, ops: SimpleNamespace) -> Any:
    """Rotor torque about y_A for the net torque ``tau`` = J_y theta_A'' and the tension
    f_L: tau + b f_L, which cancels the cable's moment -b f_L (docs/theory.md (4.22)) [N m]."""
    return tau + offset_arms(phi, theta, c.offset, ops)[1] * tension


def planar_offset_accelerations(
    phi: Any,
    theta: Any,
    dphi: Any,
    dtheta: Any,
    F: Any,
    tau: Any,
    r0: tuple[Any, Any],
    c: Any,
    ops: SimpleNamespace,
) -> dict[str, Any]:
    """phi'', theta_A'' and f_L of the planar model with the cable at an offset, exactly
    (docs/theory.md (4.14)-(4.16)), for any backend.

    ``r0`` = (r_x, r_z): the attachment offset in the plane at theta_A = 0, i.e. the x_A
    and z_A components of R_z(psi*) r_att; at tilt theta_A it is r = R_y(theta_A) r0. With
    w = y_A x r, a = t.w, b = d.w (t = dd/dphi):

      (J_y + m b^2) theta_A'' = tau_y - b F_0,   F_0 = f_R sin(s) - m g sin(phi)
                                                       + m l phi'^2 + m theta_A'^2 a
      f_L = F_0 + m b theta_A''
      l phi'' = -g cos(phi) + f_R cos(s)/m + a theta_A'' - b theta_A'^2

    (s = phi + theta_A; tau_y the rotor torque about y_A). With r0 = 0 this is (6.18).
    """
    ct, st = ops.cos(theta), ops.sin(theta)
    rx = ct * r0[0] + st * r0[1]
    rz = -st * r0[0] + ct * r0[1]
    cp, sp = ops.cos(phi), ops.sin(phi)
    a = -sp * rz - cp * rx
    b = cp * rz - sp * rx
    m, l, g = c.mass, c.length, c.gravity
    s = phi + theta
    F0 = F * ops.sin(s) - m * g * sp + m * l * dphi**2 + m * dtheta**2 * a
    ddtheta = (tau - b * F0) / (c.inertia + m * b * b)
    return {
        "phi_ddot": (-g * cp + F * ops.cos(s) / m + a * ddtheta - b * dtheta**2) / l,
        "theta_ddot": ddtheta,
        "tension": F0 + m * b * ddtheta,
        "cable_torque": -b * (F0 + m * b * ddtheta),
    }


def planar_flat_inputs(
    phi_d: ArrayLike, theta_d: ArrayLike, c: Any, ops: SimpleNamespace = NUMPY
) -> dict[str, Any]:
    """Planar flatness: the wrench w = [f_R, tau_y] and its first two derivatives.

    ``phi_d`` = [phi, phi', phi'', phi''', phi''''] and ``theta_d`` = [theta_A, ...,
    theta_A''''] (first axis the derivative order; trailing axes broadcast). Inverts
    (6.18): f_R = m l (phi'' + (g/l) cos phi) / cos(phi + theta_A), tau_y = J_y theta_A''.
    Singular where cos(phi + theta_A) = 0 (thrust axis along the link). With a numeric
    attachment offset (``c.has_offset``) the exact offset model is inverted instead
    (docs/theory.md (4.19)).
    """
    if ops is NUMPY and getattr(c, "has_offset", False):
        P = np.asarray(phi_d, dtype=float)
        T = np.asarray(theta_d, dtype=float)
        shape = P.shape[1:]
        vals = _offset_flat_function()(P.reshape(5, -1), T.reshape(5, -1), c.coefficients)
        names = ("f_R", "f_R_dot", "f_R_ddot", "tau", "tau_dot", "tau_ddot")
        out: dict[str, Any] = {}
        for name, v in zip(names, vals, strict=True):
            a = np.asarray(v).reshape(shape)
            out[name] = float(a) if a.ndim == 0 else a
        return out
    p0, p1, p2, p3, p4 = (phi_d[i] for i in range(5))
    t0, t1, t2, t3, t4 = (theta_d[i] for i in range(5))
    k = c.gravity / c.length
    ml = c.mass * c.length
    A = p2 + k * ops.cos(p0)
    A1 = p3 - k * ops.sin(p0) * p1
    A2 = p4 - k * (ops.cos(p0) * p1**2 + ops.sin(p0) * p2)
    s, s1, s2 = p0 + t0, p1 + t1, p2 + t2
    B = ops.cos(s)
    B1 = -ops.sin(s) * s1
    B2 = -ops.cos(s) * s1**2 - ops.sin(s) * s2
    F = ml * A / B
    F1 = ml * (A1 * B - A * B1) / B**2
    F2 = ml * (A2 / B - 2.0 * A1 * B1 / B**2 - A * B2 / B**2 + 2.0 * A * B1**2 / B**3)
    J = c.inertia
    return {
        "f_R": F,
        "f_R_dot": F1,
        "f_R_ddot": F2,
        "tau": J * t2,
        "tau_dot": J * t3,
        "tau_ddot": J * t4,
    }


def hover_torque(phi: float, theta: float, tension: float, c: Any) -> float:
    """Rotor torque about y_A holding inclined hovering at (phi, theta_A) with the tension
    f_L and the offset ``c.offset``: tau_y = b f_L, b = d.(y_A x r) (docs/theory.md (4.17))
    [N m]; 0 without an offset."""
    return offset_arms(phi, theta, c.offset, NUMPY)[1] * tension


def planar_across_torque(
    phi: Any, theta: Any, tension: Any, r_y: float, ops: SimpleNamespace
) -> Any:
    """Rotor torque [tau_x, tau_z] about x_A and z_A (F_A) cancelling the cable torque of
    an offset component r_y across the plane: -(r x (-f_L d)) . (x_A, z_A) =
    (f_L r_y sin(phi), -f_L r_y cos(phi)) (docs/theory.md (4.18)) [N m]."""
    return (tension * r_y * ops.sin(phi), -tension * r_y * ops.cos(phi))


@functools.lru_cache(maxsize=8)
def _offset_derivatives_function() -> ca.Function:
    """(x[12], u[4], c[NC]) -> phi''..phi, theta_A..theta_A, f_L of the exact
    offset model, by differentiating its right-hand side along itself (AD)."""
    x, u, cs = ca.SX.sym("x", NX), ca.SX.sym("u", NU), ca.SX.sym("c", NC)
    c = SimpleNamespace(
        mass=cs[0], length=cs[1], inertia=cs[2], gravity=cs[3],
        torque_row=[cs[4 + i] for i in range(4)], offset=(cs[8], cs[9]),
    )  # fmt: skip
    t = rotor_form_terms(x, None, c, CASADI)
    xdot = rotor_form_rhs(x, u, c, CASADI)

    def D(e: ca.SX) -> ca.SX:
        return ca.jtimes(e, x, xdot)

    p3, t3 = D(t["phi_ddot"]), D(t["theta_ddot"])
    outs = [t["phi_ddot"], p3, D(p3), t["theta_ddot"], t3, D(t3), t["tension"]]
    return ca.Function("offset_derivatives", [x, u, cs], outs)


_DERIVATIVE_NAMES = (
    "phi_ddot", "phi_dddot", "phi_ddddot", "theta_ddot", "theta_dddot", "theta_ddddot", "tension",
)  # fmt: skip


def offset_derivatives(x: FloatArray, u: FloatArray | None, c: PlanarParams) -> dict[str, Any]:
    """:meth:`ExtendedPlanarModel.derivatives` of the exact offset model (AD of
    :func:`planar_offset_accelerations`); ``x`` (12,) or (12, n)."""
    x = np.asarray(x, dtype=float)
    n = 1 if x.ndim == 1 else x.shape[1]
    uu = np.zeros((NU, n)) if u is None else np.asarray(u, dtype=float).reshape(NU, n)
    vals = _offset_derivatives_function()(x.reshape(NX, n), uu, c.coefficients)
    out = {}
    for name, v in zip(_DERIVATIVE_NAMES, vals, strict=True):
        a = np.asarray(v).reshape(-1)
        out[name] = float(a[0]) if x.ndim == 1 else a
    if u is None:
        del out["phi_ddddot"], out["theta_ddddot"]
    return out


@functools.lru_cache(maxsize=1)
def _offset_flat_function() -> ca.Function:
    """(phi_d[5], theta_d[5], c[NC]) -> f_R, f_R', f_R'', tau_y, tau_y', tau_y'' inverting
    the offset model (4.20) along the output's time derivatives (AD); tau_y is the net
    torque J_y theta_A''."""
    P, T, cs = ca.SX.sym("phi", 5), ca.SX.sym("theta", 5), ca.SX.sym("c", NC)
    m, l, J, g = cs[0], cs[1], cs[2], cs[3]
    phi, theta, dtheta, ddphi, ddtheta = P[0], T[0], T[1], P[2], T[2]
    a, b = offset_arms(phi, theta, (cs[8], cs[9]), CASADI)
    cp = ca.cos(phi)
    F = m * (l * ddphi + g * cp - a * ddtheta + b * dtheta**2) / ca.cos(phi + theta)
    tau = J * ddtheta  # the net torque (4.20)
    z = ca.vertcat(P[:4], T[:4])
    zdot = ca.vertcat(P[1:], T[1:])

    def D(e: ca.SX) -> ca.SX:
        return ca.jtimes(e, z, zdot)

    F1, tau1 = D(F), D(tau)
    return ca.Function("offset_flat", [P, T, cs], [F, F1, D(F1), tau, tau1, D(tau1)])


def _dot4(row: Any, f: Any) -> Any:
    return row[0] * f[0] + row[1] * f[1] + row[2] * f[2] + row[3] * f[3]


def rotor_form_terms(x: Any, u: Any, c: Any, ops: SimpleNamespace) -> dict[str, Any]:
    """:func:`planar_terms` of a rotor-form state ``x`` (12) and input ``u`` (4, or None)."""
    f, df = [x[4 + i] for i in range(4)], [x[8 + i] for i in range(4)]
    ones = (1.0, 1.0, 1.0, 1.0)
    row = c.torque_row
    ddF = None if u is None else _dot4(ones, [u[i] for i in range(4)])
    ddtau = None if u is None else _dot4(row, [u[i] for i in range(4)])
    return planar_terms(
        x[0], x[1], x[2], x[3],
        _dot4(ones, f), _dot4(row, f), _dot4(ones, df), _dot4(row, df),
        ddF, ddtau, c, ops,
    )  # fmt: skip


def rotor_form_rhs(x: Any, u: Any, c: Any, ops: SimpleNamespace) -> Any:
    """(6.20): d/dt [phi, theta_A, phi', theta_A', f, f'] = [phi', theta_A', phi'', theta_A'',
    f', u]."""
    t = rotor_form_terms(x, None, c, ops)
    return ops.stack(
        [x[2], x[3], t["phi_ddot"], t["theta_ddot"]]
        + [x[8 + i] for i in range(4)]
        + [u[i] for i in range(4)]
    )


def wrench_form_terms(z: Any, v: Any, c: Any, ops: SimpleNamespace) -> dict[str, Any]:
    """:func:`planar_terms` of a wrench-form state ``z`` (8) and input ``v`` (2, or None)."""
    return planar_terms(
        z[0], z[1], z[2], z[3], z[4], z[5], z[6], z[7],
        None if v is None else v[0], None if v is None else v[1], c, ops,
    )  # fmt: skip


def wrench_form_rhs(z: Any, v: Any, c: Any, ops: SimpleNamespace) -> Any:
    """d/dt [phi, theta_A, phi', theta_A', f_R, tau_y, f_R', tau_y'] (the wrench form of 6.20)."""
    t = wrench_form_terms(z, None, c, ops)
    return ops.stack([z[2], z[3], t["phi_ddot"], t["theta_ddot"], z[6], z[7], v[0], v[1]])


@dataclass(frozen=True)
class ExtendedPlanarModel:
    """The double dynamic extension (6.20) of the planar model, numerical and symbolic.

    Numerical methods take numpy arrays whose first axis is the state (12) or input (4)
    index; trailing axes are vectorised (e.g. x of shape (12, n) for n samples).
    """

    params: PlanarParams

    # -- numerical -------------------------------------------------------------------
    def rhs(self, x: ArrayLike, u: ArrayLike) -> FloatArray:
        """x' for the rotor-form state ``x`` and input ``u`` = f'' (6.20)."""
        return rotor_form_rhs(
            np.asarray(x, dtype=float), np.asarray(u, dtype=float), self.params, NUMPY
        )

    def derivatives(self, x: ArrayLike, u: ArrayLike | None = None) -> dict[str, FloatArray]:
        """phi'', theta_A'', phi''', theta_A''' and f_L from ``x``; with ``u`` also the snaps.

        Keys: ``phi_ddot``, ``theta_ddot``, ``phi_dddot``, ``theta_dddot``, ``tension``,
        and with ``u``: ``phi_ddddot``, ``theta_ddddot`` [rad/s^k, N].
        """
        x = np.asarray(x, dtype=float)
        if self.params.has_offset:
            return offset_derivatives(x, u, self.params)
        return rotor_form_terms(
            x, None if u is None else np.asarray(u, dtype=float), self.params, NUMPY
        )

    def tension(self, x: ArrayLike) -> Any:
        """Cable tension f_L (4.21) of rotor-form states ``x`` (12,) or (12, n) [N]: the
        closed form, exact with the attachment offset (what :meth:`derivatives` returns as
        ``tension``, without the jerks and snaps)."""
        x = np.asarray(x, dtype=float)
        p = self.params
        f, row = x[THRUSTS], p.torque_row
        F = f[0] + f[1] + f[2] + f[3]
        tau = row[0] * f[0] + row[1] * f[1] + row[2] * f[2] + row[3] * f[3]
        return planar_tension(x[0], x[1], x[2], x[3], F, tau, p, NUMPY)

    def wrench(self, x: ArrayLike) -> FloatArray:
        """[f_R, tau_y, f_R', tau_y'] of a rotor-form state [N, N m, N/s, N m/s]."""
        x = np.asarray(x, dtype=float)
        GM = self.params.Gamma_M
        return np.concatenate(
            (np.tensordot(GM, x[THRUSTS], 1), np.tensordot(GM, x[THRUST_RATES], 1))
        )

    def hover_state(self, phi: float, theta: float) -> FloatArray:
        """Rotor-form state of inclined hovering at (phi, theta_A): zero rates, f = G [f_R, 0]
        (zero net torque; the rotors add the offset's b f_L, :meth:`rotor_thrusts`)."""
        p = self.params
        den = math.cos(phi + theta)
        f_R = p.mass * p.gravity * math.cos(phi) / den
        return np.concatenate(
            ([phi, theta, 0.0, 0.0], self.params.G @ np.array([f_R, 0.0]), np.zeros(4))
        )

    def rotor_thrusts(self, x: ArrayLike, tension: ArrayLike | None = None) -> FloatArray:
        """The physical rotor thrusts of a rotor-form state: the state's f = G [f_R, tau_y]
        (net torque) plus G [0, b f_L], the offset's cable moment cancelled (4.22) [N]
        (``tension`` f_L if known, else from the state)."""
        x = np.asarray(x, dtype=float)
        if not self.params.has_offset:
            return x[THRUSTS].copy()
        f_L = self.tension(x) if tension is None else np.asarray(tension)
        b = offset_arms(x[0], x[1], self.params.offset, NUMPY)[1]
        G1 = self.params.G[:, 1]
        return x[THRUSTS] + (G1[:, None] * (b * f_L) if x.ndim > 1 else G1 * (b * f_L))

    def to_wrench_form(self, x: ArrayLike) -> FloatArray:
        """Rotor-form state (12) -> wrench-form state (8) (drops roll/yaw torque components)."""
        x = np.asarray(x, dtype=float)
        w = self.wrench(x)
        return np.concatenate((x[:4], w))

    def from_wrench_form(self, z: ArrayLike) -> FloatArray:
        """Wrench-form state (8) -> rotor-form state (12) with planar-consistent thrusts."""
        z = np.asarray(z, dtype=float)
        G = self.params.G
        return np.concatenate((z[:4], np.tensordot(G, z[4:6], 1), np.tensordot(G, z[6:8], 1)))

    # -- symbolic --------------------------------------------------------------------
    def casadi_rhs(self) -> ca.Function:
        """CasADi Function ``f(x[12], u[4]) -> x'`` of (6.20) with this model's constants."""
        x, u = ca.SX.sym("x", NX), ca.SX.sym("u", NU)
        return ca.Function(
            "planar_rhs", [x, u], [rotor_form_rhs(x, u, self.params, CASADI)], ["x", "u"], ["xdot"]
        )

    def casadi_derivatives(self) -> ca.Function:
        """CasADi Function ``(x, u) -> (phi'', phi''', phi'''', theta_A'', theta_A''',
        theta_A'''', f_L)``."""
        x, u = ca.SX.sym("x", NX), ca.SX.sym("u", NU)
        t = rotor_form_terms(x, u, self.params, CASADI)
        names = [
            "phi_ddot",
            "phi_dddot",
            "phi_ddddot",
            "theta_ddot",
            "theta_dddot",
            "theta_ddddot",
            "tension",
        ]
        return ca.Function("planar_derivatives", [x, u], [t[n] for n in names], ["x", "u"], names)

    def casadi_rk4_step(self) -> ca.Function:
        """CasADi Function ``step(x[12], u[4], h) -> x(t + h)``: one classical RK4 step of
        (6.20) with the input held (exact for the thrusts, which are polynomial in t)."""
        x, u, h = ca.SX.sym("x", NX), ca.SX.sym("u", NU), ca.SX.sym("h")
        step = parametric_rk4_step()
        return ca.Function(
            "planar_rk4",
            [x, u, h],
            [step(x, u, h, self.params.coefficients)],
            ["x", "u", "h"],
            ["x_next"],
        )


def parametric_rk4_step() -> ca.Function:
    """``step(x[12], u[4], h, c[8]) -> x(t + h)``: one RK4 step of (6.20) with the input
    held, for the model constants c = :attr:`PlanarParams.coefficients`."""
    x, u, h, c = ca.SX.sym("x", NX), ca.SX.sym("u", NU), ca.SX.sym("h"), ca.SX.sym("c", NC)
    coeffs = SimpleNamespace(
        mass=c[0], length=c[1], inertia=c[2], gravity=c[3], torque_row=[c[4 + i] for i in range(4)],
        offset=(c[8], c[9]),
    )  # fmt: skip

    def f(z: ca.SX, v: ca.SX) -> ca.SX:
        return rotor_form_rhs(z, v, coeffs, CASADI)

    x_next = rk4(f, x, u, h)
    return ca.Function("planar_rk4", [x, u, h, c], [x_next], ["x", "u", "h", "c"], ["x_next"])
