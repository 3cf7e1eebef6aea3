"""State records shared by models, simulation, control and estimation.

All vectors in F_W unless the name says otherwise; quaternions scalar-first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from tetherland.geometry import FloatArray
from tetherland.rotations import quat_to_rotmat


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


@dataclass(frozen=True, slots=True)
class LinkState:
    """Taut-link configuration q = (phi, delta) and its rates (section 6.2.2) [rad, rad/s]."""

    phi: float
    delta: float
    phi_dot: float = 0.0
    delta_dot: float = 0.0

    def as_array(self) -> FloatArray:
        return np.array([self.phi, self.delta, self.phi_dot, self.delta_dot])


@njit(cache=True)
def link_kernel(
    x: FloatArray, r_att_B: FloatArray, p_A: FloatArray, R_WA: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Compiled core of :func:`link_state_of`.

    Returns ([phi, delta, phi', delta'], d_B): the link state (NaN where undefined) and
    the unit direction anchor -> attachment point in F_B (zeros at the anchor).
    """
    px, py, pz = x[0], x[1], x[2]
    w, qx, qy, qz = x[3], x[4], x[5], x[6]
    vx, vy, vz = x[7], x[8], x[9]
    ox, oy, oz = x[10], x[11], x[12]
    ax, ay, az = r_att_B[0], r_att_B[1], r_att_B[2]
    R = np.empty((3, 3))
    R[0, 0] = 1 - 2 * (qy * qy + qz * qz)
    R[0, 1] = 2 * (qx * qy - w * qz)
    R[0, 2] = 2 * (qx * qz + w * qy)
    R[1, 0] = 2 * (qx * qy + w * qz)
    R[1, 1] = 1 - 2 * (qx * qx + qz * qz)
    R[1, 2] = 2 * (qy * qz - w * qx)
    R[2, 0] = 2 * (qx * qz - w * qy)
    R[2, 1] = 2 * (qy * qz + w * qx)
    R[2, 2] = 1 - 2 * (qx * qx + qy * qy)
    cx, cy, cz = oy * az - oz * ay, oz * ax - ox * az, ox * ay - oy * ax  # omega x r_att
    r = np.empty(3)
    rd = np.empty(3)
    for i in range(3):
        r[i] = (px, py, pz)[i] - p_A[i] + R[i, 0] * ax + R[i, 1] * ay + R[i, 2] * az
        rd[i] = (vx, vy, vz)[i] + R[i, 0] * cx + R[i, 1] * cy + R[i, 2] * cz
    out = np.full(4, np.nan)
    d_B = np.zeros(3)
    dist = math.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
    if dist < 1e-12:
        return out, d_B
    for i in range(3):
        d_B[i] = (R[0, i] * r[0] + R[1, i] * r[1] + R[2, i] * r[2]) / dist
    d = np.empty(3)
    dd = np.empty(3)
    for i in range(3):  # F_A components: columns of R_WA dotted with r
        d[i] = R_WA[0, i] * r[0] + R_WA[1, i] * r[1] + R_WA[2, i] * r[2]
        dd[i] = R_WA[0, i] * rd[0] + R_WA[1, i] * rd[1] + R_WA[2, i] * rd[2]
    radial = (d[0] * dd[0] + d[1] * dd[1] + d[2] * dd[2]) / dist
    u = d / dist
    ud = (dd - u * radial) / dist
    h = math.hypot(u[0], u[2])
    out[1] = math.atan2(-u[1], h)
    if h < 1e-12:
        return out, d_B
    h_dot = (u[0] * ud[0] + u[2] * ud[2]) / h
    out[0] = math.atan2(u[2], u[0])
    out[2] = (u[0] * ud[2] - u[2] * ud[0]) / (h * h)
    out[3] = -ud[1] * h + u[1] * h_dot
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
