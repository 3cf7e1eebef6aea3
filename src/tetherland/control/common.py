"""Pieces shared by the controllers: attitude parametrisation of y^b and the cable torque.

The tethered output y^b = [phi, delta, theta_A, psi] uses the attitude parametrisation
of :mod:`tetherland.models.flatness`: R_AB = R_y(theta_e) R_x(roll) R_z(psi), where
theta_e and roll are the two angles of z_B and psi the rotation about z_B.
"""

from __future__ import annotations

import math

import numpy as np

from tetherland.geometry import FloatArray
from tetherland.rotations import cross3


def rot_x(a: float) -> FloatArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> FloatArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> FloatArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def attitude_from_thrust_axis(z_B_A: FloatArray, psi: float) -> FloatArray:
    """R_AB = R_y(theta_e) R_x(roll) R_z(psi) whose third column is the unit ``z_B_A``."""
    z = z_B_A / np.linalg.norm(z_B_A)
    theta_e = math.atan2(z[0], z[2])
    roll = math.atan2(-z[1], math.hypot(z[0], z[2]))
    return rot_y(theta_e) @ rot_x(roll) @ rot_z(psi)


def heading_of(R_AB: FloatArray) -> float:
    """psi of R_AB = R_y(theta_e) R_x(roll) R_z(psi) [rad]: (R_y R_x)^T R_AB = R_z(psi)."""
    z = R_AB[:, 2]
    M = rot_y(math.atan2(z[0], z[2])) @ rot_x(math.atan2(-z[1], math.hypot(z[0], z[2])))
    Rz = M.T @ R_AB
    return math.atan2(Rz[1, 0], Rz[0, 0])


def cable_torque(r_att_B: FloatArray, tension: float, d_B: FloatArray) -> FloatArray:
    """tau_L = r_att x (-f_L d_B): torque of the cable about the centre of mass, F_B [N m]
    (section 6.6.5); d_B is the unit link direction (anchor -> robot) in F_B."""
    return cross3(r_att_B, -tension * d_B)
