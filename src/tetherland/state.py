"""State records shared by models, simulation, control and estimation.

All vectors in F_W unless the name says otherwise; quaternions scalar-first.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

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


def link_state_of(
    x: FloatArray, r_att_B: FloatArray, p_A: FloatArray, R_WA: FloatArray
) -> LinkState:
    """Link angles and rates of the attachment point around the anchor (DESIGN.md section 3).

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

    The angles are those of the attachment point whether or not the cable is taut.
    Scalar arithmetic: this runs at the control rate.
    """
    px, py, pz, w, qx, qy, qz, vx, vy, vz, ox, oy, oz = x.tolist()
    ax, ay, az = r_att_B.tolist()
    # R_WB r_att and R_WB (omega_B x r_att)
    cx, cy, cz = oy * az - oz * ay, oz * ax - ox * az, ox * ay - oy * ax
    R = (
        (1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - w * qz), 2 * (qx * qz + w * qy)),
        (2 * (qx * qy + w * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - w * qx)),
        (2 * (qx * qz - w * qy), 2 * (qy * qz + w * qx), 1 - 2 * (qx * qx + qy * qy)),
    )
    p0, p1, p2 = p_A.tolist()
    r = [
        px - p0 + R[0][0] * ax + R[0][1] * ay + R[0][2] * az,
        py - p1 + R[1][0] * ax + R[1][1] * ay + R[1][2] * az,
        pz - p2 + R[2][0] * ax + R[2][1] * ay + R[2][2] * az,
    ]
    rd = [
        vx + R[0][0] * cx + R[0][1] * cy + R[0][2] * cz,
        vy + R[1][0] * cx + R[1][1] * cy + R[1][2] * cz,
        vz + R[2][0] * cx + R[2][1] * cy + R[2][2] * cz,
    ]
    A = R_WA.tolist()  # rows of R_WA; F_A components are columns . r
    d = [A[0][i] * r[0] + A[1][i] * r[1] + A[2][i] * r[2] for i in range(3)]
    dd = [A[0][i] * rd[0] + A[1][i] * rd[1] + A[2][i] * rd[2] for i in range(3)]
    dist = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
    if dist < 1e-12:
        return LinkState(math.nan, math.nan, math.nan, math.nan)
    radial = (d[0] * dd[0] + d[1] * dd[1] + d[2] * dd[2]) / dist
    u = [c / dist for c in d]  # unit link direction
    ud = [(dd[i] - u[i] * radial) / dist for i in range(3)]  # its rate
    h = math.hypot(u[0], u[2])
    if h < 1e-12:
        return LinkState(math.nan, math.atan2(-u[1], h), math.nan, math.nan)
    h_dot = (u[0] * ud[0] + u[2] * ud[2]) / h
    return LinkState(
        phi=math.atan2(u[2], u[0]),
        delta=math.atan2(-u[1], h),
        phi_dot=(u[0] * ud[2] - u[2] * ud[0]) / (h * h),
        delta_dot=-ud[1] * h + u[1] * h_dot,
    )
