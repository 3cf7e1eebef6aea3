"""Taut-tether dynamics of the link angles (phi, delta), docs/theory.md section 4, (6.4).

With the thrust vector u = f_R z_B written in F_L components (u_x, u_y, u_z) and all
vectors in F_A (the link ends at the cable attachment point, taken at the centre of mass
in this model, as in the chapter):

  phi''   = [u_z - m g cos(phi) + 2 m l sin(delta) phi' delta'] / (m l cos(delta))
  delta'' = -u_y/(m l) + (g/l) sin(phi) sin(delta) - 0.5 sin(2 delta) phi'^2
  f_L     = u_x - m g cos(delta) sin(phi) + m l (cos(delta)^2 phi'^2 + delta'^2)

The cable is taut while f_L > 0; otherwise the vehicle is in free flight.

With the cable attached at r_att (in F_B) away from the centre of mass
(:func:`offset_body_dynamics`, docs/theory.md section 4.6, (4.10)-(4.13)) the link ends at
the attachment point p_R + R_WB r_att, the centre of mass accelerates with the extra
-R_WB(alpha x r + omega x (omega x r)) and the cable exerts the torque r x (-f_L R_BW d):
link accelerations, angular acceleration and tension then solve one 6 x 6 linear system.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland import GRAVITY
from tetherland.errors import SingularityError
from tetherland.geometry import FloatArray, link_direction, link_frame, link_jacobian

COS_DELTA_MIN = 1e-6
"""Below this |cos(delta)| the elevation dynamics are singular (link along y_A)."""


@dataclass(frozen=True)
class LinkAccel:
    """Result of the taut-link dynamics: angular accelerations and cable tension."""

    phi_ddot: float
    delta_ddot: float
    tension: float

    @property
    def taut(self) -> bool:
        return self.tension > 0.0


def thrust_in_link_frame(thrust_A: ArrayLike, phi: float, delta: float) -> FloatArray:
    """(u_x, u_y, u_z) = R_AL^T u for a thrust vector u given in F_A [N]."""
    return link_frame(phi, delta).T @ np.asarray(thrust_A, dtype=float)


def link_dynamics(
    phi: float,
    delta: float,
    phi_dot: float,
    delta_dot: float,
    u_L: ArrayLike,
    mass: float,
    length: float,
    g: float = GRAVITY,
) -> LinkAccel:
    """Taut-link accelerations and tension for thrust components ``u_L`` = (u_x, u_y, u_z).

    Raises
    ------
    SingularityError
        If |cos(delta)| < COS_DELTA_MIN (the link points along y_A).
    """
    u_x, u_y, u_z = (float(x) for x in u_L)
    cd, sd = math.cos(delta), math.sin(delta)
    if abs(cd) < COS_DELTA_MIN:
        raise SingularityError(f"cos(delta) = {cd:.2e}: link along y_A, phi'' undefined")
    sp, cp = math.sin(phi), math.cos(phi)
    ml = mass * length
    phi_dd = (u_z - mass * g * cp + 2.0 * ml * sd * phi_dot * delta_dot) / (ml * cd)
    delta_dd = -u_y / ml + (g / length) * sp * sd - 0.5 * math.sin(2.0 * delta) * phi_dot**2
    tension = u_x - mass * g * cd * sp + ml * (cd * cd * phi_dot**2 + delta_dot**2)
    return LinkAccel(phi_dd, delta_dd, tension)


def tethered_rhs(
    x: ArrayLike, thrust_A: ArrayLike, mass: float, length: float, g: float = GRAVITY
) -> FloatArray:
    """d/dt [phi, delta, phi', delta'] for a thrust vector ``thrust_A`` in F_A."""
    phi, delta, phi_dot, delta_dot = (float(v) for v in x)
    acc = link_dynamics(
        phi, delta, phi_dot, delta_dot, thrust_in_link_frame(thrust_A, phi, delta), mass, length, g
    )
    return np.array([phi_dot, delta_dot, acc.phi_ddot, acc.delta_ddot])


def link_position_velocity(x: ArrayLike, length: float) -> tuple[FloatArray, FloatArray]:
    """Position l d_A and velocity J_q q' of the link end relative to the anchor, in F_A."""
    phi, delta, phi_dot, delta_dot = (float(v) for v in x)
    return (
        length * link_direction(phi, delta),
        link_jacobian(phi, delta, length) @ np.array([phi_dot, delta_dot]),
    )


def tension_coordinate_free(
    d: ArrayLike,
    d_dot: ArrayLike,
    thrust: ArrayLike,
    mass: float,
    length: float,
    g: float = GRAVITY,
) -> float:
    """f_L = d.(f_R z_B - m g z_W) + m l ||d'||^2 (any frame, all three vectors in it)."""
    d = np.asarray(d, dtype=float)
    d_dot = np.asarray(d_dot, dtype=float)
    gravity = np.array([0.0, 0.0, -mass * g])
    return float(d @ (np.asarray(thrust, dtype=float) + gravity) + mass * length * d_dot @ d_dot)


TETHERED_BODY_SIZE = 11
"""[phi, delta, phi', delta', q_WB (4), omega_B (3)]."""


def tethered_body_rhs(
    x: ArrayLike,
    f_R: float,
    tau_B: ArrayLike,
    mass: float,
    length: float,
    inertia: ArrayLike,
    R_WA: ArrayLike,
    g: float = GRAVITY,
    r_att_B: ArrayLike | None = None,
) -> FloatArray:
    """Taut tethered quadrotor: link angles and attitude.

    x = [phi, delta, phi', delta', q_WB (w, x, y, z), omega_B]. With the cable at the
    centre of mass (``r_att_B`` None or zero, the chapter's model) the thrust f_R z_B drives
    the link (:func:`link_dynamics`), the torque tau_B the attitude (6.2),
    J w' = -w x J w + tau_B, q' = q * (0, w)/2. With an attachment offset the link ends at
    the attachment point and both are coupled exactly (:func:`offset_body_dynamics`).
    """
    x = np.asarray(x, dtype=float)
    q = x[4:8]
    w = x[8:11]
    from tetherland.rotations import quat_multiply, quat_to_rotmat

    if r_att_B is not None and np.any(np.asarray(r_att_B, dtype=float) != 0.0):
        acc3 = offset_body_dynamics(x, f_R, tau_B, mass, length, inertia, R_WA, r_att_B, g)
        phi_dd, delta_dd, w_dot = acc3.phi_ddot, acc3.delta_ddot, acc3.omega_dot_B
    else:
        z_B_A = np.asarray(R_WA, dtype=float).T @ quat_to_rotmat(q)[:, 2]
        acc = link_dynamics(
            x[0], x[1], x[2], x[3], thrust_in_link_frame(f_R * z_B_A, x[0], x[1]), mass, length, g
        )
        phi_dd, delta_dd = acc.phi_ddot, acc.delta_ddot
        J = _inertia_matrix(inertia)
        w_dot = np.linalg.solve(J, np.asarray(tau_B, dtype=float) - np.cross(w, J @ w))
    q_dot = 0.5 * quat_multiply(q, np.concatenate(([0.0], w)))
    return np.concatenate(([x[2], x[3], phi_dd, delta_dd], q_dot, w_dot))


def _inertia_matrix(inertia: ArrayLike) -> FloatArray:
    J = np.asarray(inertia, dtype=float)
    return np.diag(J) if J.shape == (3,) else J


@dataclass(frozen=True)
class OffsetBodyAccel:
    """Taut tethered rigid body with the cable at r_att: link and angular accelerations,
    tension (docs/theory.md (4.12))."""

    phi_ddot: float
    delta_ddot: float
    omega_dot_B: FloatArray
    tension: float

    @property
    def taut(self) -> bool:
        return self.tension > 0.0


def link_acceleration_terms(
    phi: float, delta: float, phi_dot: float, delta_dot: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(d_phi, d_delta, c) with d'' = d_phi phi'' + d_delta delta'' + c, in F_A [-, -, 1/s^2].

    d_phi = cos(delta) z_L, d_delta = -y_L (section 3.2) and
    c = d_pp phi'^2 + 2 d_pd phi' delta' + d_dd delta'^2, the second partial derivatives of
    d_A = [cos(delta) cos(phi), -sin(delta), cos(delta) sin(phi)].
    """
    cp, sp, cd, sd = math.cos(phi), math.sin(phi), math.cos(delta), math.sin(delta)
    d_phi = np.array([-cd * sp, 0.0, cd * cp])
    d_delta = np.array([-sd * cp, -cd, -sd * sp])
    d_pp = np.array([-cd * cp, 0.0, -cd * sp])
    d_pd = np.array([sd * sp, 0.0, -sd * cp])
    d_dd = np.array([-cd * cp, sd, -cd * sp])
    c = d_pp * phi_dot**2 + 2.0 * d_pd * phi_dot * delta_dot + d_dd * delta_dot**2
    return d_phi, d_delta, c


def offset_body_dynamics(
    x: ArrayLike,
    f_R: float,
    tau_B: ArrayLike,
    mass: float,
    length: float,
    inertia: ArrayLike,
    R_WA: ArrayLike,
    r_att_B: ArrayLike,
    g: float = GRAVITY,
    cancel_cable_torque: bool = False,
) -> OffsetBodyAccel:
    """Exact taut dynamics with the cable attached at ``r_att_B`` (F_B) [m].

    The link (phi, delta, l) ends at the attachment point p_att = p_R + R r (R = R_AB),
    so p_R'' = l d'' - R(alpha x r + omega x (omega x r)) (4.10); with
    m p_R'' = -m g z_A + f_R R e3 - f_L d (6.4) and
    J alpha = -omega x J omega + tau_B + r x (-f_L R^T d) (4.11), the unknowns
    (phi'', delta'', alpha = omega_B', f_L) solve the linear system (4.12)

      m l (d_phi phi'' + d_delta delta'') + m R [r]x alpha + f_L d
          = -m g z_A + f_R R e3 + m R (omega x (omega x r)) - m l c
      J alpha + f_L r x (R^T d) = -omega x J omega + tau_B.

    Parameters
    ----------
    x : (11,) array
        [phi, delta, phi', delta', q_WB (w, x, y, z), omega_B] [rad, rad/s, -, rad/s].
    f_R, tau_B
        Collective thrust [N] and rotor torque in F_B [N m].
    R_WA : (3, 3) array
        Anchor frame.
    cancel_cable_torque : bool
        The rotors add -r x (-f_L R^T d), the cable's moment at the actual tension, on top
        of ``tau_B`` (the controllers' and the planner's torque law, (4.22)): then
        J alpha = -omega x J omega + tau_B.

    Raises
    ------
    SingularityError
        If the system is singular (|cos(delta)| < COS_DELTA_MIN).
    """
    from tetherland.rotations import quat_to_rotmat

    x = np.asarray(x, dtype=float)
    phi, delta, phi_dot, delta_dot = (float(v) for v in x[:4])
    if abs(math.cos(delta)) < COS_DELTA_MIN:
        raise SingularityError(f"cos(delta) = {math.cos(delta):.2e}: link along y_A")
    R = np.asarray(R_WA, dtype=float).T @ quat_to_rotmat(x[4:8])  # R_AB
    w = x[8:11]
    r = np.asarray(r_att_B, dtype=float)
    J = _inertia_matrix(inertia)
    d = link_direction(phi, delta)
    d_phi, d_delta, c = link_acceleration_terms(phi, delta, phi_dot, delta_dot)
    r_x = np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])
    M = np.zeros((6, 6))
    M[:3, 0] = mass * length * d_phi
    M[:3, 1] = mass * length * d_delta
    M[:3, 2:5] = mass * R @ r_x
    M[:3, 5] = d
    M[3:, 2:5] = J
    M[3:, 5] = 0.0 if cancel_cable_torque else np.cross(r, R.T @ d)
    rhs = np.empty(6)
    rhs[:3] = (
        np.array([0.0, 0.0, -mass * g])
        + f_R * R[:, 2]
        + mass * R @ np.cross(w, np.cross(w, r))
        - mass * length * c
    )
    rhs[3:] = np.asarray(tau_B, dtype=float) - np.cross(w, J @ w)
    sol = np.linalg.solve(M, rhs)
    return OffsetBodyAccel(float(sol[0]), float(sol[1]), sol[2:5].copy(), float(sol[5]))
