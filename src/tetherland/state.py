"""State records shared by models, simulation, control and estimation.

All vectors in F_W unless the name says otherwise; quaternions scalar-first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from tetherland.geometry import FloatArray
from tetherland.records import fast_init
from tetherland.rotations import quat_to_rotmat


@fast_init
@dataclass(frozen=True, slots=True)
class RigidBodyState:
    """Pose and twist of the vehicle's centre of mass.

    Attributes
    ----------
    p_W : (3,) array
        Position of the centre of mass O_R [m].
    v_W : (3,) array
        Velocity of O_R [m/s].
    q_WB : (4,) array
        Attitude as a unit quaternion (w, x, y, z), F_B -> F_W.
    omega_B : (3,) array
        Angular velocity in F_B [rad/s].
    """

    p_W: FloatArray
    v_W: FloatArray
    q_WB: FloatArray
    omega_B: FloatArray

    @property
    def R_WB(self) -> FloatArray:
        """Rotation matrix F_B -> F_W."""
        return quat_to_rotmat(self.q_WB)

    @property
    def z_B(self) -> FloatArray:
        """Thrust axis in F_W."""
        return self.R_WB[:, 2]

    @classmethod
    def at_rest(cls, p_W: FloatArray, q_WB: FloatArray | None = None) -> RigidBodyState:
        """A state at ``p_W`` with zero velocity (level attitude by default)."""
        return cls(
            p_W=np.asarray(p_W, dtype=float),
            v_W=np.zeros(3),
            q_WB=np.array([1.0, 0.0, 0.0, 0.0]) if q_WB is None else np.asarray(q_WB, dtype=float),
            omega_B=np.zeros(3),
        )


@fast_init
@dataclass(frozen=True, slots=True)
class LinkState:
    """Taut-link configuration q = (phi, delta) and its rates (section 6.2.2) [rad, rad/s]."""

    phi: float
    delta: float
    phi_dot: float = 0.0
    delta_dot: float = 0.0

    def as_array(self) -> FloatArray:
        return np.array([self.phi, self.delta, self.phi_dot, self.delta_dot])


def link_state_reference(
    x: FloatArray, r_att_B: FloatArray, p_A: FloatArray, R_WA: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Plain numpy version of :func:`link_kernel` (the equations as written).

    Attachment point r = p_W + R_WB r_att - p_A and its velocity r' = v_W + R_WB (omega_B x
    r_att), both in F_A; u = r/|r|, u' = (r' - u (u.r'))/|r|; with h = hypot(u_x, u_z):
    phi = atan2(u_z, u_x), delta = atan2(-u_y, h) (geometry.link_angles), phi' = (u_x u_z'
    - u_z u_x')/h^2, delta' = -u_y' h + u_y h' (docs/theory.md section 3). Returns
    ([phi, delta, phi', delta'], d_B = R_WB^T r/|r|), NaN where undefined.
    """
    p_W, q_WB, v_W, omega_B = x[0:3], x[3:7], x[7:10], x[10:13]
    R_WB = quat_to_rotmat(q_WB)
    r_W = p_W + R_WB @ r_att_B - p_A
    rd_W = v_W + R_WB @ np.cross(omega_B, r_att_B)
    out = np.full(4, np.nan)
    dist = float(np.linalg.norm(r_W))
    if dist < 1e-12:
        return out, np.zeros(3)
    d_B = R_WB.T @ r_W / dist
    u, ud = R_WA.T @ r_W / dist, R_WA.T @ rd_W / dist
    ud = ud - u * (u @ ud)
    h = math.hypot(u[0], u[2])
    out[1] = math.atan2(-u[1], h)
    if h < 1e-12:
        return out, d_B
    out[0] = math.atan2(u[2], u[0])
    out[2] = (u[0] * ud[2] - u[2] * ud[0]) / (h * h)
    out[3] = -ud[1] * h + u[1] * (u[0] * ud[0] + u[2] * ud[2]) / h
    return out, d_B


@njit(cache=True)
def link_into(
    p_W: FloatArray,
    q_WB: FloatArray,
    v_W: FloatArray,
    omega_B: FloatArray,
    r_att_B: FloatArray,
    p_A: FloatArray,
    R_WA: FloatArray,
    out: FloatArray,
    d_B: FloatArray,
) -> None:
    """Compiled :func:`link_state_reference` without allocations: writes [phi, delta,
    phi', delta'] into ``out[:4]`` (NaN where undefined) and d_B into ``d_B[:3]``
    (zeros at the anchor)."""
    w, qx, qy, qz = q_WB[0], q_WB[1], q_WB[2], q_WB[3]
    ax, ay, az = r_att_B[0], r_att_B[1], r_att_B[2]
    R00, R01, R02 = 1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - w * qz), 2 * (qx * qz + w * qy)
    R10, R11, R12 = 2 * (qx * qy + w * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - w * qx)
    R20, R21, R22 = 2 * (qx * qz - w * qy), 2 * (qy * qz + w * qx), 1 - 2 * (qx * qx + qy * qy)
    ox, oy, oz = omega_B[0], omega_B[1], omega_B[2]
    cx, cy, cz = oy * az - oz * ay, oz * ax - ox * az, ox * ay - oy * ax  # omega x r_att
    rx = p_W[0] - p_A[0] + R00 * ax + R01 * ay + R02 * az
    ry = p_W[1] - p_A[1] + R10 * ax + R11 * ay + R12 * az
    rz = p_W[2] - p_A[2] + R20 * ax + R21 * ay + R22 * az
    vx = v_W[0] + R00 * cx + R01 * cy + R02 * cz
    vy = v_W[1] + R10 * cx + R11 * cy + R12 * cz
    vz = v_W[2] + R20 * cx + R21 * cy + R22 * cz
    for i in range(4):
        out[i] = np.nan
    dist = math.sqrt(rx * rx + ry * ry + rz * rz)
    if dist < 1e-12:
        d_B[0] = d_B[1] = d_B[2] = 0.0
        return
    d_B[0] = (R00 * rx + R10 * ry + R20 * rz) / dist
    d_B[1] = (R01 * rx + R11 * ry + R21 * rz) / dist
    d_B[2] = (R02 * rx + R12 * ry + R22 * rz) / dist
    # F_A components (columns of R_WA dotted with r, r'), normalised
    u0 = (R_WA[0, 0] * rx + R_WA[1, 0] * ry + R_WA[2, 0] * rz) / dist
    u1 = (R_WA[0, 1] * rx + R_WA[1, 1] * ry + R_WA[2, 1] * rz) / dist
    u2 = (R_WA[0, 2] * rx + R_WA[1, 2] * ry + R_WA[2, 2] * rz) / dist
    e0 = (R_WA[0, 0] * vx + R_WA[1, 0] * vy + R_WA[2, 0] * vz) / dist
    e1 = (R_WA[0, 1] * vx + R_WA[1, 1] * vy + R_WA[2, 1] * vz) / dist
    e2 = (R_WA[0, 2] * vx + R_WA[1, 2] * vy + R_WA[2, 2] * vz) / dist
    radial = u0 * e0 + u1 * e1 + u2 * e2
    ud0, ud1, ud2 = e0 - u0 * radial, e1 - u1 * radial, e2 - u2 * radial
    h = math.hypot(u0, u2)
    out[1] = math.atan2(-u1, h)
    if h < 1e-12:
        return
    out[0] = math.atan2(u2, u0)
    out[2] = (u0 * ud2 - u2 * ud0) / (h * h)
    out[3] = -ud1 * h + u1 * (u0 * ud0 + u2 * ud2) / h


@njit(cache=True)
def link_kernel(
    x: FloatArray, r_att_B: FloatArray, p_A: FloatArray, R_WA: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Compiled core of :func:`link_state_of`: ([phi, delta, phi', delta'], d_B) of
    x = [p_W, q_WB, v_W, omega_B] (see :func:`link_into`)."""
    out = np.empty(4)
    d_B = np.empty(3)
    link_into(x[0:3], x[3:7], x[7:10], x[10:13], r_att_B, p_A, R_WA, out, d_B)
    return out, d_B


def link_state_of(
    x: FloatArray, r_att_B: FloatArray, p_A: FloatArray, R_WA: FloatArray
) -> LinkState:
    """Link angles and rates of the attachment point around the anchor (docs/theory.md section 3).

    Used for the true state (simulation) and for estimates (estimator) alike.

    Parameters
    ----------
    x : (13,) array
        [p_W (3), q_WB (4), v_W (3), omega_B (3)] (MuJoCo's qpos then qvel).
    r_att_B : (3,) array
        Attachment point in F_B [m].
    p_A : (3,) array
        Anchor [m].
    R_WA : (3, 3) array
        Anchor frame.

    The angles are those of the attachment point whether or not the cable is taut; NaN
    where undefined (attachment point at the anchor, or phi at |delta| = 90 deg).
    """
    out, _ = link_kernel(x, r_att_B, p_A, R_WA)
    return LinkState(float(out[0]), float(out[1]), float(out[2]), float(out[3]))
