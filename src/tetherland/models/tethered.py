"""Taut-tether dynamics of the link angles (phi, delta), docs/theory.md section 4, (6.4).

With the thrust vector u = f_R z_B written in F_L components (u_x, u_y, u_z) and all
vectors in F_A (the link ends at the cable attachment point, taken at the centre of mass
in this model, as in the chapter):

  phi''   = [u_z - m g cos(phi) + 2 m l sin(delta) phi' delta'] / (m l cos(delta))
  delta'' = -u_y/(m l) + (g/l) sin(phi) sin(delta) - 0.5 sin(2 delta) phi'^2
  f_L     = u_x - m g cos(delta) sin(phi) + m l (cos(delta)^2 phi'^2 + delta'^2)

The cable is taut while f_L > 0; otherwise the vehicle is in free flight.
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
) -> FloatArray:
    """Taut tethered quadrotor (cable at the centre of mass): link angles and attitude.

    x = [phi, delta, phi', delta', q_WB (w, x, y, z), omega_B]; the thrust f_R z_B drives
    the link (:func:`link_dynamics`), the torque tau_B the attitude (6.2),
    J w' = -w x J w + tau_B, q' = q * (0, w)/2.
    """
    x = np.asarray(x, dtype=float)
    q = x[4:8]
    w = x[8:11]
    from tetherland.rotations import quat_multiply, quat_to_rotmat

    z_B_A = np.asarray(R_WA, dtype=float).T @ quat_to_rotmat(q)[:, 2]
    acc = link_dynamics(
        x[0], x[1], x[2], x[3], thrust_in_link_frame(f_R * z_B_A, x[0], x[1]), mass, length, g
    )
    J = np.asarray(inertia, dtype=float)
    J = np.diag(J) if J.shape == (3,) else J
    w_dot = np.linalg.solve(J, np.asarray(tau_B, dtype=float) - np.cross(w, J @ w))
    q_dot = 0.5 * quat_multiply(q, np.concatenate(([0.0], w)))
    return np.concatenate(([x[2], x[3], acc.phi_ddot, acc.delta_ddot], q_dot, w_dot))
