"""Body rate and angular acceleration feed-forward from the flat outputs (free flight).

For a quadrotor the desired attitude follows from the desired force F = m (p'' + g z_W)
and the heading psi: R_d = [x_d, y_d, z_d] with z_d = F/||F||, y_d = z_d x x_C/||.||,
x_d = y_d x z_d, x_C = [cos psi, sin psi, 0] (:func:`rotation_from_z_and_yaw`). Its rate
and acceleration follow from F' = m p''' (jerk) and F'' = m p'''' (snap) for a constant
heading:

  omega_d^ = R_d^T R_d',   omega_d'^ = R_d^T R_d'' - (omega_d^)^2   (hat map, F_B of R_d)

with the derivatives of a normalised vector n = v/r, r = ||v||:
  n'  = (v' - n r')/r,  r' = n . v',
  n'' = (v'' - 2 n' r' - n r'')/r,  r'' = n' . v' + n . v''.
"""

from __future__ import annotations

import math

import numpy as np

from tetherland.errors import SingularityError
from tetherland.geometry import FloatArray
from tetherland.rotations import vee

_EPS = 1e-9


def _normalised(
    v: FloatArray, dv: FloatArray, ddv: FloatArray, what: str
) -> tuple[FloatArray, FloatArray, FloatArray]:
    r = float(np.linalg.norm(v))
    if r < _EPS:
        raise SingularityError(f"{what} is zero: its direction is undefined")
    n = v / r
    dr = float(n @ dv)
    dn = (dv - n * dr) / r
    ddr = float(dn @ dv + n @ ddv)
    ddn = (ddv - 2.0 * dn * dr - n * ddr) / r
    return n, dn, ddn


def attitude_feedforward(
    F: FloatArray, dF: FloatArray, ddF: FloatArray, yaw: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Desired attitude, body rate and angular acceleration for a force profile.

    Parameters
    ----------
    F, dF, ddF : (3,) arrays
        Desired force m (p'' + g z_W) and its first two time derivatives, F_W [N, N/s,
        N/s^2].
    yaw : float
        Heading psi (held constant) [rad].

    Returns
    -------
    R_d : (3, 3) array
        Desired attitude R_WB.
    omega_d, omega_dot_d : (3,) arrays
        Its angular velocity [rad/s] and acceleration [rad/s^2] in the desired body frame.

    Raises
    ------
    SingularityError
        When F is zero or z_d is along the heading x_C (yaw undefined).
    """
    z, dz, ddz = _normalised(np.asarray(F, float), np.asarray(dF, float),
                             np.asarray(ddF, float), "desired force")  # fmt: skip
    x_C = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    y, dy, ddy = _normalised(np.cross(z, x_C), np.cross(dz, x_C), np.cross(ddz, x_C),
                             "z_d x x_C (thrust axis along the heading)")  # fmt: skip
    x = np.cross(y, z)
    dx = np.cross(dy, z) + np.cross(y, dz)
    ddx = np.cross(ddy, z) + 2.0 * np.cross(dy, dz) + np.cross(y, ddz)
    R = np.column_stack((x, y, z))
    dR = np.column_stack((dx, dy, dz))
    ddR = np.column_stack((ddx, ddy, ddz))
    W = R.T @ dR
    omega = vee(W)
    omega_dot = vee(R.T @ ddR - W @ W)
    return R, omega, omega_dot
